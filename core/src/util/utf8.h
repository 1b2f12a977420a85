// UTF-8 well-formedness (RFC 3629): what JSON text and terminals accept.
#pragma once

#include <cstddef>
#include <cstdio>
#include <string>
#include <string_view>

namespace rayfarm {

// Length of the valid UTF-8 sequence of two to four bytes at s[i], or 0 (an ASCII byte, a
// stray continuation byte, a truncated, overlong or surrogate sequence, beyond U+10FFFF).
inline std::size_t utf8_length(std::string_view s, std::size_t i) {
  auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = byte(i);
  const std::size_t n = c >= 0xf0 ? 4 : c >= 0xe0 ? 3 : c >= 0xc2 ? 2 : 0;
  if (n == 0 || c > 0xf4 || i + n > s.size()) return 0;
  for (std::size_t k = 1; k < n; ++k)
    if ((byte(i + k) & 0xc0) != 0x80) return 0;
  const unsigned char c1 = byte(i + 1);
  if ((c == 0xe0 && c1 < 0xa0) || (c == 0xed && c1 > 0x9f) || (c == 0xf0 && c1 < 0x90) ||
      (c == 0xf4 && c1 > 0x8f))
    return 0;
  return n;
}

// "U+00A0 (a no-break space)": a character named in a message, with what it is where that
// explains why a word or a number was not read as it looks (pasted from a document or a web
// page). The one naming for every reader.
inline std::string code_point_name(unsigned code) {
  char hex[16];
  std::snprintf(hex, sizeof hex, "U+%04X", code);
  const bool space = (code >= 0x2000 && code <= 0x200A) || code == 0x3000;
  const char* what = code == 0xA0                        ? " (a no-break space)"
                     : code == 0x2009                    ? " (a thin space)"
                     : code == 0x202F                    ? " (a narrow no-break space)"
                     : code == 0x200B                    ? " (a zero-width space)"
                     : code == 0xFEFF                    ? " (a byte-order mark)"
                     : code == 0x2212                    ? " (a minus sign; write '-')"
                     : code == 0x2013                    ? " (an en dash; write '-')"
                     : space                             ? " (a Unicode space)"
                     : code >= 0x200C && code <= 0x2060  ? " (an invisible character)"
                                                         : "";
  return hex + std::string(what);
}

// The code point of the valid multi-byte UTF-8 sequence at s[i] (utf8_length(s, i) > 0).
inline unsigned utf8_code(std::string_view s, std::size_t i, std::size_t n) {
  unsigned code = static_cast<unsigned char>(s[i]) & (0x7Fu >> n);
  for (std::size_t k = 1; k < n; ++k) code = (code << 6) | (static_cast<unsigned char>(s[i + k]) & 0x3Fu);
  return code;
}

// A character that is not ASCII but looks like white space or like nothing at all: a
// no-break space, the Unicode spaces, zero-width characters, a byte-order mark. Found in a
// word, it is why the word is not the keyword it shows.
struct Invisible {
  std::size_t at = std::string_view::npos;  // byte offset of the first one
  unsigned code = 0;
  std::string name() const { return code_point_name(code); }
};

inline Invisible find_invisible(std::string_view s) {
  for (std::size_t i = 0; i < s.size();) {
    const std::size_t n = static_cast<unsigned char>(s[i]) < 0x80 ? 1 : utf8_length(s, i);
    if (n <= 1) {
      ++i;
      continue;
    }
    const unsigned code = utf8_code(s, i, n);
    if (code == 0xA0 || (code >= 0x2000 && code <= 0x200D) || code == 0x2028 || code == 0x2029 ||
        code == 0x202F || code == 0x205F || code == 0x2060 || code == 0x3000 || code == 0xFEFF)
      return {i, code};
    i += n;
  }
  return {};
}

// Text from a program we do not trust (a student's output), fit for any report, terminal or
// XML file: invalid UTF-8 (a tail cut inside a character, raw bytes), control characters other
// than tab and newline (a terminal's escape sequences, NUL) and U+FFFE/U+FFFF each become U+FFFD.
inline std::string printable_text(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    if (c < 0x80) {
      const bool ok = c == '\n' || c == '\t' || (c >= 0x20 && c != 0x7f);
      out += ok ? std::string(1, static_cast<char>(c)) : std::string("\xEF\xBF\xBD");
      ++i;
      continue;
    }
    const std::size_t n = utf8_length(s, i);
    const bool nonchar = n == 3 && c == 0xef && static_cast<unsigned char>(s[i + 1]) == 0xbf &&
                         static_cast<unsigned char>(s[i + 2]) >= 0xbe;
    const bool c1 = n == 2 && c == 0xc2 && static_cast<unsigned char>(s[i + 1]) < 0xa0;
    if (n == 0 || nonchar || c1) {
      out += "\xEF\xBF\xBD";
      i += n == 0 ? 1 : n;
    } else {
      out.append(s.substr(i, n));
      i += n;
    }
  }
  return out;
}

inline bool is_valid_utf8(std::string_view s) {
  for (std::size_t i = 0; i < s.size();) {
    if (static_cast<unsigned char>(s[i]) < 0x80) {
      ++i;
    } else if (std::size_t n = utf8_length(s, i)) {
      i += n;
    } else {
      return false;
    }
  }
  return true;
}

}  // namespace rayfarm
