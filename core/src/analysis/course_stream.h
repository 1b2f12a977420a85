// A model file as the course's reference program read it: one C stream consumed by
// fscanf("%s"), fscanf("%lf") and fscanf("%d"), with the line and column of every word.
#pragma once

#include <cstddef>
#include <string_view>

#include "rayfarm/diagnostic.h"

namespace rayfarm::course {

// What one fscanf("%s") returns: the characters up to the next white space.
struct Word {
  std::string_view text;  // empty at the end of the file
  Where where;

  explicit operator bool() const { return !text.empty(); }
  // The position of the i-th character of the word.
  Where at(size_t i) const { return {where.line, where.column + static_cast<int>(i), {}}; }
};

// Copyable, so a caller can look ahead on a copy and throw it away.
class Stream {
 public:
  // A UTF-8 byte-order mark is skipped (the caller reports it); columns count from after it,
  // as rayfarm's own lexer counts them.
  explicit Stream(std::string_view text);

  // The word at the read position, after the white space before it (which this consumes).
  Word peek();
  // Consumes the first n characters of the word peek() returned.
  void take(size_t n);
  // Consumes up to the end of the line (a '#' or '//' comment) or past `end` ("*/").
  void skip_line();
  void skip_past(std::string_view end);
  int line() const { return line_; }  // of the read position

 private:
  void advance(size_t n);

  std::string_view text_;
  size_t pos_ = 0;
  int line_ = 1;
  size_t line_start_ = 0;
};

// White space as fscanf skips it (isspace in the C locale).
inline bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\v' || c == '\f' || c == '\r';
}

// How many leading characters of `word` one fscanf("%lf") converts (fscanf("%d") when
// `integer`); the rest stays in the stream for the next read. 0: the read fails.
size_t number_prefix(std::string_view word, bool integer);

}  // namespace rayfarm::course
