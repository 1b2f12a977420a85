# Build step (cmake -P): turns the web page's files into a C++ source, so rayfarmd serves
# them from its own binary (no install step, no path to get wrong). Each file becomes a byte
# array with its content type and an ETag from its SHA-256.
#   cmake -DDIR=server/web -DFILES=a.html,b.js -DOUT=web_files.cpp -P embed_files.cmake
string(REPLACE "," ";" FILES "${FILES}")
set(arrays "")
set(table "")
set(index 0)
foreach(name IN LISTS FILES)
  file(READ "${DIR}/${name}" hex HEX)
  file(SHA256 "${DIR}/${name}" sha)
  string(LENGTH "${hex}" hex_length)
  math(EXPR size "${hex_length} / 2")
  # Two hex digits per byte, 24 bytes a line (CMake's regular expressions have no {n}).
  string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
  string(REPEAT "0x[0-9a-f][0-9a-f]," 24 line)
  string(REGEX REPLACE "(${line})" "\\1\n    " bytes "${bytes}")
  if(name MATCHES "\\.html$")
    set(type "text/html; charset=utf-8")
  elseif(name MATCHES "\\.js$")
    set(type "text/javascript; charset=utf-8")
  elseif(name MATCHES "\\.css$")
    set(type "text/css; charset=utf-8")
  elseif(name MATCHES "\\.svg$")
    set(type "image/svg+xml")
  else()
    message(FATAL_ERROR "embed_files.cmake: no content type for ${name}")
  endif()
  string(SUBSTRING "${sha}" 0 20 etag)
  string(APPEND arrays "const unsigned char k${index}[${size} + 1] = {\n    ${bytes}0};\n")
  string(APPEND table
    "      {\"${name}\", \"${type}\", {reinterpret_cast<const char*>(k${index}), ${size}}, \"\\\"${etag}\\\"\"},\n")
  math(EXPR index "${index} + 1")
endforeach()
file(CONFIGURE OUTPUT "${OUT}.tmp" @ONLY CONTENT [==[// Generated from server/web/ by server/embed_files.cmake at build time: do not edit.
#include "web_files.h"

namespace rayfarm::server {
namespace {

@arrays@
}  // namespace

const WebFile* find_web_file(std::string_view name) {
  static const WebFile kFiles[] = {
@table@  };
  for (const WebFile& f : kFiles)
    if (f.name == name) return &f;
  return nullptr;
}

}  // namespace rayfarm::server
]==])
# Only a changed file is rewritten, so an unchanged page does not relink the server.
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUT}.tmp")
