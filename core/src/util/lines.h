// Where lines end: at "\n", at "\r\n" (its '\n'), and at a "\r" alone (old Mac files). Every
// line number and column rayfarm reports counts lines this one way.
#pragma once

#include <cstddef>
#include <string_view>

#include "util/count_byte.h"

namespace rayfarm {

// Whether s[i] ends a line.
inline bool ends_line(std::string_view s, std::size_t i) {
  return s[i] == '\n' || (s[i] == '\r' && (i + 1 == s.size() || s[i + 1] != '\n'));
}

// The offset of the first character at or after `from` that ends a line; npos if none.
inline std::size_t find_line_end(std::string_view s, std::size_t from) {
  for (std::size_t i = from; i < s.size(); ++i)
    if ((s[i] == '\n' || s[i] == '\r') && ends_line(s, i)) return i;
  return std::string_view::npos;
}

// How many lines end in `s`: its '\n's, and its '\r's with no '\n' after them.
inline std::size_t count_lines(std::string_view s) {
  std::size_t n = count_byte(s, '\n');
  for (std::size_t i = s.find('\r'); i != std::string_view::npos; i = s.find('\r', i + 1))
    n += ends_line(s, i);
  return n;
}

}  // namespace rayfarm
