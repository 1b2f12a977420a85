// A folder of a test's own under the system's temporary folder (a unique name from mkdtemp),
// removed with everything in it when the test ends, however it ends.
#pragma once

#include <stdlib.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>

namespace rayfarm::test {

struct TempDir {
  std::filesystem::path path;
  explicit TempDir(std::string_view name = "test") {
    std::string tmpl =
        (std::filesystem::temp_directory_path() / ("rayfarm-" + std::string(name) + "-XXXXXX"))
            .string();
    if (!::mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp " + tmpl);
    path = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
};

}  // namespace rayfarm::test
