# Build step (cmake -P): turns the Function library (rayfarm1.lua) into a C++ source, so every
# node loads exactly the library it was built with (FUNCTION LOAD REPLACE at connect).
#   cmake -DIN=rayfarm1.lua -DOUT=farm_library.cpp -P farm_library.cmake
file(READ "${IN}" hex HEX)
string(LENGTH "${hex}" hex_length)
math(EXPR size "${hex_length} / 2")
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
string(REPEAT "0x[0-9a-f][0-9a-f]," 24 line)
string(REGEX REPLACE "(${line})" "\\1\n    " bytes "${bytes}")
file(CONFIGURE OUTPUT "${OUT}.tmp" @ONLY CONTENT [==[// Generated from server/farm/rayfarm1.lua by farm_library.cmake at build time: do not edit.
#include "farm_client.h"

namespace rayfarm::farm {
namespace {
const unsigned char kLibrary[@size@ + 1] = {
    @bytes@0};
}  // namespace

std::string_view function_library() {
  return {reinterpret_cast<const char*>(kLibrary), @size@};
}

}  // namespace rayfarm::farm
]==])
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUT}.tmp")
