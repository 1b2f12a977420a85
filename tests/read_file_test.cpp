// The client's bounded reads (client/read_file.h): a file, a pipe or a stream of exactly the
// limit is read whole, one byte more is refused, and a file whose size the system reports as
// 0 is still read to its end.
#include "read_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

namespace {

namespace fs = std::filesystem;
using rayfarm::cli::read_bounded;
using rayfarm::cli::too_large;

fs::path temp(const std::string& name) {
  const std::string pid = std::to_string(::getpid());
  return fs::temp_directory_path() / ("rayfarm-read-file-" + pid + "-" + name);
}

std::string bytes(std::size_t n) {
  std::string s(n, 'x');
  for (std::size_t i = 0; i < n; ++i) s[i] = static_cast<char>('a' + i % 26);
  return s;
}

TEST(ReadFile, AFileOfTheLimitIsReadAndOneByteMoreIsNot) {
  for (const std::size_t limit : {std::size_t{5}, std::size_t{70000}, std::size_t{200000}}) {
    const fs::path file = temp("limit");
    for (const std::size_t size : {limit - 1, limit, limit + 1}) {
      std::ofstream(file, std::ios::binary) << bytes(size);
      std::ifstream in(file, std::ios::binary);
      std::string text;
      const bool ok = read_bounded(in, file, limit, text);
      EXPECT_EQ(ok, size <= limit) << limit << " " << size;
      if (ok) {
        EXPECT_EQ(text, bytes(size));
      }
      EXPECT_LE(text.size(), limit);
    }
    fs::remove(file);
  }
}

TEST(ReadFile, StreamsAndPipesStopAtTheLimit) {
  for (const std::size_t limit : {std::size_t{5}, std::size_t{65536}, std::size_t{150000}}) {
    for (const std::size_t size : {limit, limit + 1}) {
      std::istringstream stream(bytes(size));
      std::string text;
      EXPECT_EQ(read_bounded(stream, {}, limit, text), size <= limit) << limit << " " << size;
      EXPECT_LE(text.size(), limit);

      // A pipe: its size is not known, and it is read until it ends.
      const fs::path fifo = temp("fifo");
      ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
      std::thread writer([&] { std::ofstream(fifo, std::ios::binary) << bytes(size); });
      std::ifstream in(fifo, std::ios::binary);
      std::string piped;
      const bool ok = read_bounded(in, fifo, limit, piped);
      in.close();  // lets a writer blocked on a full pipe finish
      writer.join();
      fs::remove(fifo);
      EXPECT_EQ(ok, size <= limit) << "pipe " << limit << " " << size;
      if (ok) {
        EXPECT_EQ(piped, bytes(size));
      }
    }
  }
}

TEST(ReadFile, AFileTheSystemSizesAsEmptyIsReadToItsEnd) {
  const fs::path status = "/proc/self/status";
  if (!fs::exists(status)) GTEST_SKIP() << "no /proc";
  std::error_code ec;
  ASSERT_EQ(fs::file_size(status, ec), 0u);
  std::ifstream in(status, std::ios::binary);
  std::string text;
  EXPECT_TRUE(read_bounded(in, status, 1 << 20, text));
  EXPECT_NE(text.find("Name:"), std::string::npos);
  std::ifstream again(status, std::ios::binary);
  std::string cut;
  EXPECT_FALSE(read_bounded(again, status, 16, cut));
}

TEST(ReadFile, TheLimitIsSaidInTheLargestWholeUnit) {
  EXPECT_EQ(too_large(std::uintmax_t{1} << 30), "larger than 1 GiB, the most rayfarm reads from one input");
  EXPECT_EQ(too_large(std::uintmax_t{3} << 20), "larger than 3 MiB, the most rayfarm reads from one input");
  EXPECT_EQ(too_large(1536), "larger than 1536 bytes, the most rayfarm reads from one input");
}

}  // namespace
