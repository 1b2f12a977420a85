// The course program's view of a model file: fscanf words and number prefixes.
#include "analysis/course_stream.h"

#include "util/lines.h"

namespace rayfarm::course {

Stream::Stream(std::string_view text) : text_(text) {
  if (text_.starts_with("\xEF\xBB\xBF")) pos_ = line_start_ = 3;
}

void Stream::advance(size_t n) {
  for (const size_t end = pos_ + n; pos_ < end && pos_ < text_.size(); ++pos_)
    if (ends_line(text_, pos_)) {
      ++line_;
      line_start_ = pos_ + 1;
    }
}

Word Stream::peek() {
  size_t start = pos_;
  while (start < text_.size() && is_space(text_[start])) ++start;
  advance(start - pos_);
  size_t end = pos_;
  while (end < text_.size() && !is_space(text_[end])) ++end;
  return {text_.substr(pos_, end - pos_), {line_, static_cast<int>(pos_ - line_start_) + 1, {}}};
}

void Stream::take(size_t n) { advance(n); }

void Stream::skip_line() {
  size_t end = find_line_end(text_, pos_);
  advance((end == std::string_view::npos ? text_.size() : end) - pos_);
}

void Stream::skip_past(std::string_view end) {
  size_t at = text_.find(end, pos_);
  advance((at == std::string_view::npos ? text_.size() : at + end.size()) - pos_);
}

namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_hex_digit(char c) {
  return is_digit(c) || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
}
char lower(char c) { return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c; }

bool starts_with_nocase(std::string_view s, std::string_view lower_prefix) {
  if (s.size() < lower_prefix.size()) return false;
  for (size_t i = 0; i < lower_prefix.size(); ++i)
    if (lower(s[i]) != lower_prefix[i]) return false;
  return true;
}

// Digits (hexadecimal ones when `hex`) from i; returns the index after them.
size_t digits(std::string_view s, size_t i, bool hex, size_t& count) {
  count = 0;
  while (i < s.size() && (hex ? is_hex_digit(s[i]) : is_digit(s[i]))) ++i, ++count;
  return i;
}

}  // namespace

// glibc's scanf grammar for %lf (as strtod's) and %d. Where scanf consumes characters and
// then fails ("1e" followed by a letter), this counts only what converts: either way the
// program misreads the word, and the lint reports it.
size_t number_prefix(std::string_view s, bool integer) {
  size_t i = 0, n = 0;
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  if (integer) {
    i = digits(s, i, false, n);
    return n ? i : 0;
  }
  std::string_view rest = s.substr(i);
  if (starts_with_nocase(rest, "infinity")) return i + 8;
  if (starts_with_nocase(rest, "inf")) return i + 3;
  if (starts_with_nocase(rest, "nan")) {
    size_t close = rest.find(')');
    return i +
           (rest.size() > 3 && rest[3] == '(' && close != std::string_view::npos ? close + 1 : 3);
  }
  bool hex =
      rest.size() > 2 && rest[0] == '0' && lower(rest[1]) == 'x' &&
      (is_hex_digit(rest[2]) || (rest[2] == '.' && rest.size() > 3 && is_hex_digit(rest[3])));
  if (hex) i += 2;
  size_t whole = 0, fraction = 0;
  i = digits(s, i, hex, whole);
  if (i < s.size() && s[i] == '.') i = digits(s, i + 1, hex, fraction);
  if (whole + fraction == 0) return 0;
  if (i < s.size() && lower(s[i]) == (hex ? 'p' : 'e')) {
    size_t j = i + 1, exponent = 0;
    if (j < s.size() && (s[j] == '+' || s[j] == '-')) ++j;
    j = digits(s, j, false, exponent);
    if (exponent) i = j;
  }
  return i;
}

}  // namespace rayfarm::course
