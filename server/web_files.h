// The web page's files (server/web/), built into the binary by server/embed_files.cmake.
#pragma once

#include <string_view>

namespace rayfarm::server {

struct WebFile {
  std::string_view name;  // as under server/web/: "index.html", "app.js"
  std::string_view content_type;
  std::string_view body;
  std::string_view etag;  // quoted, from the file's SHA-256
};

// nullptr when there is no such file.
const WebFile* find_web_file(std::string_view name);

}  // namespace rayfarm::server
