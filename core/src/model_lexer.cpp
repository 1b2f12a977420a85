// Model-file lexer.
#include "model_lexer.h"

namespace rayfarm {
namespace {

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

}  // namespace

// Windows editors start UTF-8 files with a byte-order mark; columns count from after it.
ModelLexer::ModelLexer(std::string_view text) : text_(text) {
  if (text_.starts_with("\xEF\xBB\xBF")) pos_ = line_start_ = 3;
}

const Token& ModelLexer::peek(int ahead) {
  while (buffered_ <= ahead) buffer_[buffered_++] = scan();
  return buffer_[ahead];
}

Token ModelLexer::next() {
  peek(0);
  Token t = buffer_[0];
  for (int i = 1; i < buffered_; ++i) buffer_[i - 1] = buffer_[i];
  --buffered_;
  return t;
}

Token ModelLexer::scan() {
  for (;;) {
    while (pos_ < text_.size() && is_space(text_[pos_])) {
      if (text_[pos_] == '\n') {
        ++line_;
        line_start_ = pos_ + 1;
      }
      ++pos_;
    }
    if (pos_ >= text_.size()) break;
    bool comment = text_[pos_] == '#' ||
                   (text_[pos_] == '/' && pos_ + 1 < text_.size() && text_[pos_ + 1] == '/');
    if (!comment) break;
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
  }
  Token t;
  t.line = line_;
  t.column = static_cast<int>(pos_ - line_start_) + 1;
  if (pos_ >= text_.size()) {
    t.kind = Token::end;
    return t;
  }
  char c = text_[pos_];
  if (c == '{' || c == '}') {
    t.kind = c == '{' ? Token::open : Token::close;
    t.text = text_.substr(pos_++, 1);
    return t;
  }
  size_t start = pos_;
  while (pos_ < text_.size()) {
    char d = text_[pos_];
    if (is_space(d) || d == '{' || d == '}' || d == '#') break;
    if (d == '/' && pos_ + 1 < text_.size() && text_[pos_ + 1] == '/') break;
    ++pos_;
  }
  t.kind = Token::word;
  t.text = text_.substr(start, pos_ - start);
  return t;
}

}  // namespace rayfarm
