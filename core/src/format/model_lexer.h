// Tokens of the model file: words, '{' and '}', with comments and white space skipped.
#pragma once

#include <string_view>

namespace rayfarm {

// Whether s starts with `lower_prefix` (lower case), ignoring the case of s.
inline bool starts_with_nocase(std::string_view s, std::string_view lower_prefix) {
  if (s.size() < lower_prefix.size()) return false;
  for (size_t i = 0; i < lower_prefix.size(); ++i) {
    const char c = s[i] >= 'A' && s[i] <= 'Z' ? static_cast<char>(s[i] - 'A' + 'a') : s[i];
    if (c != lower_prefix[i]) return false;
  }
  return true;
}

// A word that starts like a decimal number (it may still not be one).
inline bool starts_like_number(std::string_view s) {
  const char c = s.empty() ? 0 : s[0];
  return (c >= '0' && c <= '9') || c == '+' || c == '-' || c == '.';
}

// NaN or infinity as strtod would read it (any case, any sign): not numbers in this format,
// but clearly meant as values.
bool is_nan_or_inf_word(std::string_view s);

// A token written where a number belongs, even if it turns out not to be one.
inline bool looks_like_value(std::string_view s) {
  return starts_like_number(s) || is_nan_or_inf_word(s);
}

struct Token {
  enum Kind { word, open, close, end } kind = end;
  std::string_view text;
  int line = 1;
  int column = 1;
};

// Streaming lexer with a little lookahead (the parser needs up to three tokens to tell a
// name from a missing brace), so a 7 MB file never becomes a vector of tokens.
class ModelLexer {
 public:
  explicit ModelLexer(std::string_view text);
  // A lexer for the rest of a file from a line start, `first_line` being that line's number.
  ModelLexer(std::string_view rest, int first_line) : text_(rest), line_(first_line) {}

  const Token& peek(int ahead = 0) {
    while (buffered_ <= ahead) scan(buffer_[buffered_++]);
    return buffer_[ahead];
  }
  Token next() {
    // One named token, so that it is the caller's own (no copy): with nothing looked ahead
    // it is scanned straight into it. (A token written field by field and then copied
    // whole waits for those stores to land.)
    Token t;
    if (buffered_ == 0) {
      scan(t);
    } else {
      t = buffer_[0];
      drop();
    }
    return t;
  }
  // next() for a token already looked at (peek): dropped, not copied.
  void drop() {
    peek(0);
    for (int i = 1; i < buffered_; ++i) buffer_[i - 1] = buffer_[i];
    --buffered_;
  }

 private:
  void scan(Token& t);

  static constexpr int kLookahead = 3;
  std::string_view text_;
  size_t pos_ = 0;
  int line_ = 1;
  size_t line_start_ = 0;
  Token buffer_[kLookahead];
  int buffered_ = 0;
};

}  // namespace rayfarm
