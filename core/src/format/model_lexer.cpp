// Model-file lexer.
#include "format/model_lexer.h"

#include "util/lines.h"

namespace rayfarm {
namespace {

// Character classes: white space, and the characters that end a word ('{', '}', '#', and
// '/' when it starts "//").
enum : unsigned char { kSpace = 1, kNewline = 2, kWordEnd = 4, kSlash = 8 };

constexpr auto kClass = [] {
  struct Table {
    unsigned char c[256] = {};
  } t;
  // '<', ',' and '>' separate too: some course files write vectors as <x,y,z>.
  for (char c : {' ', '\t', '\r', '\v', '\f', '<', ',', '>'})
    t.c[static_cast<unsigned char>(c)] = kSpace | kWordEnd;
  t.c[static_cast<unsigned char>('\n')] = kSpace | kNewline | kWordEnd;
  t.c[static_cast<unsigned char>('{')] = kWordEnd;
  t.c[static_cast<unsigned char>('}')] = kWordEnd;
  t.c[static_cast<unsigned char>('#')] = kWordEnd;
  t.c[static_cast<unsigned char>('/')] = kSlash;
  return t;
}();

unsigned char char_class(char c) { return kClass.c[static_cast<unsigned char>(c)]; }


}  // namespace

// Windows editors start UTF-8 files with a byte-order mark; columns count from after it.
ModelLexer::ModelLexer(std::string_view text) : text_(text) {
  if (text_.starts_with("\xEF\xBB\xBF")) pos_ = line_start_ = 3;
}

void ModelLexer::scan(Token& t) {
  const char* p = text_.data();
  const size_t n = text_.size();
  size_t pos = pos_;
  for (;;) {
    while (pos < n) {
      unsigned char k = char_class(p[pos]);
      if (!(k & kSpace)) break;
      if ((k & kNewline) || (p[pos] == '\r' && ends_line(text_, pos))) {
        ++line_;
        line_start_ = pos + 1;
      }
      ++pos;
    }
    if (pos >= n) break;
    bool comment = p[pos] == '#' || (p[pos] == '/' && pos + 1 < n && p[pos + 1] == '/');
    if (!comment) break;
    while (pos < n && p[pos] != '\n' && p[pos] != '\r') ++pos;
  }
  t.line = line_;
  t.column = static_cast<int>(pos - line_start_) + 1;
  if (pos >= n) {
    pos_ = pos;
    t.kind = Token::end;
    t.text = {};
    return;
  }
  char c = p[pos];
  if (c == '{' || c == '}') {
    t.kind = c == '{' ? Token::open : Token::close;
    t.text = text_.substr(pos, 1);
    pos_ = pos + 1;
    return;
  }
  size_t start = pos;
  while (pos < n) {
    unsigned char k = char_class(p[pos]);
    if (k) {
      if (k & kWordEnd) break;
      if (pos + 1 < n && p[pos + 1] == '/') break;  // kSlash: "//" starts a comment
    }
    ++pos;
  }
  pos_ = pos;
  t.kind = Token::word;
  t.text = text_.substr(start, pos - start);
}

bool is_nan_or_inf_word(std::string_view s) {
  if (!s.empty() && (s[0] == '+' || s[0] == '-')) s.remove_prefix(1);
  // Only the first 9 characters count ("nan(" may be followed by anything).
  std::string_view l = s.substr(0, 9);
  return (l.size() == 3 && (starts_with_nocase(l, "nan") || starts_with_nocase(l, "inf"))) ||
         (l.size() == 8 && starts_with_nocase(l, "infinity")) || starts_with_nocase(l, "nan(");
}

}  // namespace rayfarm
