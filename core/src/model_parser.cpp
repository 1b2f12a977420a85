// Model-file parser: entities, attributes and value shapes, with recovery so that every
// error in a file is reported, not only the first.
#include "rayfarm/model_parser.h"

#include <string>
#include <vector>

#include "model_lexer.h"
#include "rayfarm/schema.h"

namespace rayfarm {
namespace {

Where at(const Token& t) { return {t.line, t.column, {}}; }

std::string quoted(std::string_view s) {
  constexpr size_t kMax = 40;
  std::string out = "'";
  out += s.size() > kMax ? std::string(s.substr(0, kMax)) + "..." : std::string(s);
  return out + "'";
}

bool starts_like_number(std::string_view s) {
  char c = s.empty() ? 0 : s[0];
  return (c >= '0' && c <= '9') || c == '+' || c == '-' || c == '.';
}

bool is_nan_or_inf_word(std::string_view s) {
  if (!s.empty() && (s[0] == '+' || s[0] == '-')) s.remove_prefix(1);
  std::string l(s);
  for (char& c : l) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return l == "nan" || l == "inf" || l == "infinity";
}

std::vector<std::string_view> attr_names(const EntitySpec& spec) {
  std::vector<std::string_view> names;
  for (const AttrSpec& a : spec.attrs) names.push_back(a.key);
  return names;
}

std::string with_hint(std::string message, const std::string& hint) {
  if (!hint.empty()) message += " (did you mean '" + hint + "'?)";
  return message;
}

class ModelParser {
 public:
  ModelParser(std::string_view text, Diagnostics& diags) : lex_(text), diags_(diags) {}

  SceneDesc parse() {
    SceneDesc scene;
    while (lex_.peek().kind != Token::end && !diags_.truncated()) {
      const Token& t = lex_.peek();
      if (t.kind == Token::close) {
        diags_.error("unbalanced-brace", "unmatched '}'", at(t));
        lex_.next();
      } else if (t.kind == Token::open) {
        diags_.error("syntax", "unexpected '{': expected an entity (camera, material, light, "
                     "sphere, plane)", at(t));
        skip_block();
      } else if (const EntitySpec* spec = find_entity(t.text)) {
        scene.entities.push_back(parse_entity(*spec));
      } else {
        unknown_entity();
      }
    }
    return scene;
  }

 private:
  void unknown_entity() {
    Token t = lex_.next();
    std::string hint = nearest_word(t.text, entity_keywords());
    diags_.error("unknown-entity",
                 with_hint("unknown entity " + quoted(t.text) +
                               "; expected camera, material, light, sphere or plane", hint),
                 at(t));
    // Skip "NAME { ... }" that belongs to it, so its attributes do not cascade.
    if (lex_.peek().kind == Token::word && lex_.peek(1).kind == Token::open) lex_.next();
    if (lex_.peek().kind == Token::open) skip_block();
  }

  // Skips a balanced { ... } starting at the current '{'.
  void skip_block() {
    Token open = lex_.next();
    int depth = 1;
    while (depth > 0) {
      Token t = lex_.next();
      if (t.kind == Token::end) {
        diags_.error("unbalanced-brace", "'{' is never closed", at(open));
        return;
      }
      if (t.kind == Token::open) ++depth;
      if (t.kind == Token::close) --depth;
    }
  }

  EntityDesc parse_entity(const EntitySpec& spec) {
    Token keyword = lex_.next();
    EntityDesc e;
    e.kind = spec.kind;
    e.where = at(keyword);
    std::string_view kw = spec.keyword;

    // NAME, unless the next word is an attribute (then the '{' is what is missing).
    const Token& maybe_name = lex_.peek();
    bool named = maybe_name.kind == Token::word &&
                 (lex_.peek(1).kind == Token::open || !find_attr(spec, maybe_name.text));
    if (named) {
      Token name = lex_.next();
      e.name = std::string(name.text);
      e.name_where = at(name);
      if (!is_valid_name(name.text))
        diags_.error("bad-name",
                     "invalid " + std::string(kw) + " name " + quoted(name.text) +
                         ": names are letters, digits, '_', '.', '-' and start with a letter "
                         "or '_' (at most " + std::to_string(kMaxNameLength) + " characters)",
                     at(name));
    } else if (spec.name_required) {
      diags_.error("missing-name", std::string(kw) + " needs a name: " + std::string(kw) +
                                       " NAME { ... }", at(keyword));
    }

    Token open = lex_.peek();
    bool braced = open.kind == Token::open;
    if (braced) {
      lex_.next();
    } else {
      diags_.error("syntax", "expected '{' after " + describe_entity(e), at(open));
      if (open.kind != Token::word || !find_attr(spec, open.text)) return e;
    }

    for (;;) {
      const Token& t = lex_.peek();
      if (t.kind == Token::end) {
        diags_.error("unbalanced-brace", "'{' of " + describe_entity(e) + " is never closed",
                     braced ? at(open) : e.where);
        break;
      }
      if (t.kind == Token::close) {
        lex_.next();
        break;
      }
      if (t.kind == Token::open) {
        diags_.error("syntax", "unexpected '{' inside " + describe_entity(e), at(t));
        skip_block();
        continue;
      }
      if (const AttrSpec* attr = find_attr(spec, t.text)) {
        parse_attr(spec, *attr, e);
        continue;
      }
      if (find_entity(t.text) && starts_entity(1)) {
        diags_.error("unbalanced-brace",
                     "'{' of " + describe_entity(e) + " is never closed before the next " +
                         std::string(t.text),
                     braced ? at(open) : e.where);
        break;
      }
      unknown_attr(spec, e);
    }
    return e;
  }

  // True when the tokens from `ahead` on look like "[NAME] {".
  bool starts_entity(int ahead) {
    const Token& a = lex_.peek(ahead);
    if (a.kind == Token::open) return true;
    return a.kind == Token::word && lex_.peek(ahead + 1).kind == Token::open;
  }

  void unknown_attr(const EntitySpec& spec, const EntityDesc& e) {
    Token t = lex_.next();
    std::string list;
    for (const AttrSpec& a : spec.attrs) list += (list.empty() ? "" : ", ") + std::string(a.key);
    std::string hint = nearest_word(t.text, attr_names(spec));
    std::string what = starts_like_number(t.text) || is_nan_or_inf_word(t.text)
                           ? "unexpected value " + quoted(t.text) + " in "
                           : "unknown attribute " + quoted(t.text) + " for ";
    diags_.error("unknown-attribute",
                 with_hint(what + describe_entity(e) + " (attributes: " + list + ")", hint),
                 at(t));
    // Skip its values: everything up to the next known attribute or brace.
    while (lex_.peek().kind == Token::word && !find_attr(spec, lex_.peek().text) &&
           !(find_entity(lex_.peek().text) && starts_entity(1)))
      lex_.next();
  }

  void parse_attr(const EntitySpec& spec, const AttrSpec& attr, EntityDesc& e) {
    Token key = lex_.next();
    AttrDesc a;
    a.key = std::string(key.text);
    a.where = at(key);
    if (const AttrDesc* first = e.find(a.key))
      diags_.error("duplicate-attribute",
                   "attribute '" + a.key + "' given twice in " + describe_entity(e) +
                       " (first at line " + std::to_string(first->where.line) + ")",
                   a.where);

    if (attr.kind == ValueKind::material_ref) {
      const Token& v = lex_.peek();
      if (v.kind != Token::word || (find_attr(spec, v.text) && lex_.peek(1).kind == Token::word)) {
        diags_.error("missing-value", "'" + a.key + "' needs a material name", at(v));
        e.invalid_keys.push_back(a.key);
        return;
      }
      Token name = lex_.next();
      a.word = std::string(name.text);
      a.value_where.push_back(at(name));
      if (!is_valid_name(name.text))
        diags_.error("bad-name", "invalid material name " + quoted(name.text), at(name));
      if (!e.find(a.key)) e.attrs.push_back(std::move(a));
      return;
    }

    bool bad = false;
    while (lex_.peek().kind == Token::word) {
      const Token& v = lex_.peek();
      if (find_attr(spec, v.text)) break;
      if (!starts_like_number(v.text) && !is_nan_or_inf_word(v.text)) break;
      Token tok = lex_.next();
      std::string why;
      if (auto n = parse_number(tok.text, &why)) {
        a.numbers.push_back(*n);
        a.value_where.push_back(at(tok));
      } else {
        diags_.error("not-a-number", quoted(tok.text) + " is not a number: " + why, at(tok));
        bad = true;
      }
      if (a.numbers.size() > 16) break;  // absurd counts are reported below, not read forever
    }
    auto [lo, hi] = value_count(attr.kind);
    int n = static_cast<int>(a.numbers.size());
    if (!bad && (n < lo || n > hi)) {
      diags_.error("value-count",
                   "'" + a.key + "' takes " + std::string(describe(attr.kind)) + ", got " +
                       std::to_string(n) + (n == 1 ? " value" : " values"),
                   n > hi ? a.value_where[hi] : a.where);
      bad = true;
    }
    if (bad) e.invalid_keys.push_back(a.key);
    else if (!e.find(a.key)) e.attrs.push_back(std::move(a));
  }

  std::string describe_entity(const EntityDesc& e) const {
    std::string s(entity_spec(e.kind).keyword);
    if (!e.name.empty()) s += " '" + e.name + "'";
    return s;
  }

  ModelLexer lex_;
  Diagnostics& diags_;
};

}  // namespace

SceneDesc parse_model(std::string_view text, Diagnostics& diags) {
  return ModelParser(text, diags).parse();
}

}  // namespace rayfarm
