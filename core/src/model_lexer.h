// Tokens of the model file: words, '{' and '}', with comments and white space skipped.
#pragma once

#include <string_view>

namespace rayfarm {

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

  const Token& peek(int ahead = 0) {
    while (buffered_ <= ahead) buffer_[buffered_++] = scan();
    return buffer_[ahead];
  }
  Token next() {
    peek(0);
    Token t = buffer_[0];
    for (int i = 1; i < buffered_; ++i) buffer_[i - 1] = buffer_[i];
    --buffered_;
    return t;
  }

 private:
  Token scan();

  static constexpr int kLookahead = 3;
  std::string_view text_;
  size_t pos_ = 0;
  int line_ = 1;
  size_t line_start_ = 0;
  Token buffer_[kLookahead];
  int buffered_ = 0;
};

}  // namespace rayfarm
