// Model-file parser: entities, attributes and value shapes, with recovery so that every
// error in a file is reported, not only the first.
#include "rayfarm/model_parser.h"

#include <algorithm>
#include <optional>
#include <string>
#include <vector>

#include "format/model_lexer.h"
#include "util/utf8.h"
#include "util/count_byte.h"
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

std::vector<std::string_view> attr_names(const EntitySpec& spec) {
  std::vector<std::string_view> names;
  for (const AttrSpec& a : spec.attrs) names.push_back(a.key);
  return names;
}

std::string with_hint(std::string message, const std::string& hint) {
  if (!hint.empty()) message += " (did you mean '" + hint + "'?)";
  return message;
}

// A word that is not the keyword it shows because of a character that looks like a space or
// like nothing: that character named, and the keyword the text before it is (if any).
struct Unseen {
  std::string note;  // "; it has U+00A0 (a no-break space) in it: ..." or empty
  std::string without;  // the word without such characters ("radius" of "radius\u200b")
  std::string before;   // the word up to the first ("radius" of "radius\u00a01")
  // The keyword it was meant to be, by `is_keyword`; empty if neither reading is one.
  template <class IsKeyword>
  std::string keyword(IsKeyword is_keyword) const {
    return is_keyword(without) ? without : is_keyword(before) ? before : std::string();
  }
};
Unseen unseen(std::string_view word) {
  const Invisible first = find_invisible(word);
  if (first.at == std::string_view::npos) return {};
  Unseen u;
  u.note = "; it has " + first.name() + " in it, which looks like a space or nothing but is " +
           "neither: retype it";
  u.before = std::string(word.substr(0, first.at));
  for (size_t i = 0; i < word.size();) {
    const Invisible c = find_invisible(word.substr(i));
    if (c.at == std::string_view::npos) {
      u.without += word.substr(i);
      break;
    }
    u.without += word.substr(i, c.at);
    i += c.at + utf8_length(word, i + c.at);
  }
  return u;
}


class ModelParser {
 public:
  ModelParser(std::string_view text, Diagnostics& diags)
      : text_(text), lex_(text), diags_(diags) {}

  SceneDesc parse() {
    SceneDesc scene;
    // Room for every entity up front: growing a vector of 100,000 entities copies them and
    // touches twice the memory. An entity takes a '{' and at least ~16 bytes of text.
    const size_t braces = count_byte(text_, '{');
    scene.entities.reserve(std::min(braces, text_.size() / 16 + 1));
    while (lex_.peek().kind != Token::end && !diags_.truncated()) {
      const Token& t = lex_.peek();
      if (t.kind == Token::close) {
        diags_.error("unbalanced-brace", "unmatched '}'", at(t));
        lex_.next();
      } else if (t.kind == Token::open) {
        diags_.error("syntax",
                     "unexpected '{': expected an entity (" + std::string(entity_keyword_list()) +
                         ")",
                     at(t));
        skip_block();
      } else if (const EntitySpec* spec = find_entity(t.text)) {
        scene.entities.push_back(parse_entity(*spec));
      } else if (auto stand_in = unknown_entity()) {
        scene.entities.push_back(std::move(*stand_in));
      }
    }
    if (lex_.peek().kind != Token::end) diags_.reading_stopped();
    return scene;
  }

 private:
  // Skips an unknown entity with its "NAME { ... }". When the word is a typo of a keyword, a
  // stand-in of that kind keeps its name, so a misspelt camera or material does not also
  // cause "no camera" or "undefined material".
  std::optional<EntityDesc> unknown_entity() {
    Token t = lex_.next();
    if (std::string_view why = unsupported_entity(t.text); !why.empty()) {
      diags_.error("unsupported-entity", std::string(why), at(t));
      if (lex_.peek().kind == Token::word && lex_.peek(1).kind == Token::open &&
          !find_entity(lex_.peek().text))
        lex_.next();
      if (lex_.peek().kind == Token::open) skip_block();
      return std::nullopt;
    }
    const Unseen odd = unseen(t.text);
    std::string hint = odd.keyword([](const std::string& w) { return find_entity(w) != nullptr; });
    if (hint.empty()) hint = nearest_word(t.text, entity_keywords());
    std::string what = looks_like_value(t.text)
                           ? "unexpected value " + quoted(t.text) + " outside an entity"
                           : "unknown entity " + quoted(t.text);
    diags_.error("unknown-entity",
                 with_hint(what + odd.note + "; expected one of: " +
                               std::string(entity_keyword_list()),
                           hint),
                 at(t));
    std::optional<EntityDesc> stand_in;
    if (const EntitySpec* guess = hint.empty() ? nullptr : find_entity(hint)) {
      stand_in.emplace();
      stand_in->kind = guess->kind;
      stand_in->where = at(t);
      mark_all_invalid(*stand_in);
    }
    // Its NAME, if it has one: never after a stray value, and never an entity keyword (a
    // stray word before an unnamed camera or light must not swallow that entity).
    if (!looks_like_value(t.text) && lex_.peek().kind == Token::word &&
        lex_.peek(1).kind == Token::open && !find_entity(lex_.peek().text)) {
      Token name = lex_.next();
      if (stand_in && is_valid_name(name.text)) {
        stand_in->name = std::string(name.text);
        stand_in->name_where = at(name);
      }
    }
    if (lex_.peek().kind == Token::open) skip_block();
    return stand_in;
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

    // NAME, unless the next word is an attribute or starts the next entity (then the '{' is
    // what is missing).
    const Token& maybe_name = lex_.peek();
    bool named =
        maybe_name.kind == Token::word &&
        (lex_.peek(1).kind == Token::open || (!find_attr(spec, maybe_name.text) &&
                                              !(find_entity(maybe_name.text) && starts_entity(1))));
    if (named) {
      Token name = lex_.next();
      e.name = std::string(name.text);
      e.name_where = at(name);
      if (!is_valid_name(name.text))
        diags_.error("bad-name",
                     "invalid " + std::string(kw) + " name " + quoted(name.text) +
                         ": names are letters, digits, '_', '.', '-' and start with a letter "
                         "or '_' (at most " +
                         std::to_string(kMaxNameLength) + " characters)",
                     at(name));
    } else if (spec.name_required) {
      diags_.error("missing-name",
                   std::string(kw) + " needs a name: " + std::string(kw) + " NAME { ... }",
                   at(keyword));
    }

    Token open = lex_.peek();
    bool braced = open.kind == Token::open;
    if (braced) {
      lex_.next();
    } else {
      diags_.error("syntax", "expected '{' after " + describe_entity(e), at(open));
      if (open.kind != Token::word || !find_attr(spec, open.text)) {
        mark_all_invalid(e);
        return e;
      }
    }

    SmallVec<int, 8> first_line;
    first_line.assign(spec.attrs.size(), 0);
    e.attrs.reserve(spec.attrs.size());
    int stray = 0;  // braces opened inside the entity before its own attributes
    for (;;) {
      const Token& t = lex_.peek();
      if (t.kind == Token::end) {
        diags_.error("unbalanced-brace", "'{' of " + describe_entity(e) + " is never closed",
                     braced ? at(open) : e.where);
        break;
      }
      if (t.kind == Token::close) {
        // A stray '{' closed again before more of this entity ("{ worlddim 8 6 } viewpoint
        // ..."): that '}' is the stray's, not the entity's end.
        const Token& after = lex_.peek(1);
        const bool closes_stray =
            stray > 0 && (after.kind == Token::close ||
                          (after.kind == Token::word && find_attr(spec, after.text)));
        lex_.next();
        if (!closes_stray) break;
        --stray;
        continue;
      }
      if (t.kind == Token::open) {
        diags_.error("syntax", "unexpected '{' inside " + describe_entity(e), at(t));
        // A stray brace before this entity's own attributes ("sphere s { material m {
        // center ...") is the typo: the attributes after it are still this entity's. Anything
        // else is a block of its own, skipped whole.
        const Token& after = lex_.peek(1);
        if (after.kind == Token::word && find_attr(spec, after.text)) {
          lex_.next();
          ++stray;
        } else {
          skip_block();
        }
        continue;
      }
      if (const AttrSpec* attr = find_attr(spec, t.text)) {
        parse_attr(spec, *attr, e, first_line[attr - spec.attrs.data()]);
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

  // True when the current word ends an attribute's values: the next attribute, a likely typo
  // of one (reported on its own), or the next entity.
  bool ends_values(const EntitySpec& spec, std::string_view word) {
    if (find_attr(spec, word)) return true;
    if (looks_like_value(word)) return false;
    return !nearest_word(word, attr_names(spec)).empty() || (find_entity(word) && starts_entity(1));
  }

  void unknown_attr(const EntitySpec& spec, EntityDesc& e) {
    Token t = lex_.next();
    std::string list;
    for (const AttrSpec& a : spec.attrs) list += (list.empty() ? "" : ", ") + std::string(a.key);
    if (looks_like_value(t.text)) {
      diags_.error("unexpected-value",
                   "unexpected value " + quoted(t.text) + " in " + describe_entity(e) +
                       ": every value follows an attribute (" + list + ")",
                   at(t));
    } else {
      const Unseen odd = unseen(t.text);
      std::string hint =
          odd.keyword([&](const std::string& w) { return find_attr(spec, w) != nullptr; });
      if (hint.empty()) hint = nearest_word(t.text, attr_names(spec));
      diags_.error("unknown-attribute",
                   with_hint("unknown attribute " + quoted(t.text) + " for " + describe_entity(e) +
                                 odd.note + " (attributes: " + list + ")",
                             hint),
                   at(t));
      // The attribute it was meant to be is then not also "missing".
      if (!hint.empty()) e.invalid_keys.push_back(hint);
    }
    while (lex_.peek().kind == Token::word && !ends_values(spec, lex_.peek().text)) lex_.next();
  }

  void parse_attr(const EntitySpec& spec, const AttrSpec& attr, EntityDesc& e, int& first_line) {
    Token key = lex_.next();
    AttrDesc a;
    a.key = std::string(key.text);
    a.where = at(key);
    bool duplicate = first_line > 0;
    if (duplicate)
      diags_.error("duplicate-attribute",
                   "attribute '" + a.key + "' given twice in " + describe_entity(e) +
                       " (first at line " + std::to_string(first_line) + ")",
                   a.where);
    else
      first_line = key.line;

    if (is_word_kind(attr.kind)) {
      // A material is a name; a texture reference or file name any word (a path may start
      // with a digit or a dot). Either way not the next attribute or entity.
      const bool material = attr.kind == ValueKind::material_ref;
      const Token& v = lex_.peek();
      // An attribute's keyword with that attribute's value after it ("material center 1 2 3")
      // is the next attribute, the name left out. Without one ("material radius center ..."),
      // it is a name: JSON scenes may name a material "radius", and the course's program read
      // whatever word came.
      bool next_attribute = false;
      if (const AttrSpec* next = find_attr(spec, v.text);
          next && v.kind == Token::word && lex_.peek(1).kind == Token::word) {
        const std::string_view after = lex_.peek(1).text;
        next_attribute = is_word_kind(next->kind) ? !find_attr(spec, after) && !find_entity(after)
                                                  : looks_like_value(after);
      }
      // A number is no material name; "nan" and "inf" are names, as a material's own
      // name may be.
      if (v.kind != Token::word || (material && starts_like_number(v.text)) || next_attribute ||
          (find_entity(v.text) && starts_entity(1))) {
        diags_.error("missing-value",
                     "'" + a.key + "' needs " + (material ? "a material name" : describe(attr)),
                     at(v));
        if (v.kind == Token::word && material && starts_like_number(v.text)) lex_.next();
        if (!duplicate) e.invalid_keys.push_back(a.key);
        return;
      }
      Token name = lex_.next();
      a.word = std::string(name.text);
      a.value_where.push_back(at(name));
      if (material ? !is_valid_name(name.text) : !is_valid_path(name.text)) {
        diags_.error("bad-name",
                     std::string(material ? "invalid material name " : "invalid file name ") +
                         quoted(name.text),
                     at(name));
        if (!duplicate) e.invalid_keys.push_back(a.key);
        return;
      }
      if (!duplicate) e.attrs.push_back(std::move(a));
      return;
    }

    auto [lo, hi] = value_count(attr.kind);
    bool bad = false;
    int n = 0;
    Where first_extra;
    // "radius 1,5": a decimal comma reads as two numbers; remembered to say so if the count
    // then comes out wrong.
    std::string_view previous, comma_joined;
    for (;;) {
      const Token& v = lex_.peek();
      if (v.kind != Token::word) break;
      // The common case, a number: it is neither an attribute nor anything that ends values.
      bool number_like = starts_like_number(v.text);
      if (!number_like && find_attr(spec, v.text)) break;
      // A word where a number is still needed is a bad number ("radius abc"), unless it
      // is a typo of the next attribute or the next entity.
      if (!number_like && !looks_like_value(v.text) &&
          (valid_value_count(attr.kind, n) || n >= hi || ends_values(spec, v.text)))
        break;
      Token tok = lex_.next();
      ++n;
      if (!previous.empty() && comma_joined.empty() &&
          tok.text.data() == previous.data() + previous.size() + 1 &&
          previous.data()[previous.size()] == ',')
        comma_joined = std::string_view(previous.data(), previous.size() + 1 + tok.text.size());
      previous = tok.text;
      std::string why;
      std::optional<double> number = parse_number(tok.text, &why);
      if (!number) {
        diags_.error("not-a-number", quoted(tok.text) + " is not a number: " + why, at(tok));
        bad = true;
      } else if (n <= hi) {
        a.numbers.push_back(*number);
        a.value_where.push_back(at(tok));
      } else if (n == hi + 1) {
        first_extra = at(tok);
      }
    }
    if (!bad && !valid_value_count(attr.kind, n)) {
      diags_.error("value-count",
                   "'" + a.key + "' takes " + describe(attr) + ", got " +
                       std::to_string(n) + (n == 1 ? " value" : " values") +
                       (comma_joined.empty()
                            ? ""
                            : " (a comma separates numbers: if " + quoted(comma_joined) +
                                  " is one number, write it with a decimal point)"),
                   n > hi ? first_extra : a.where);
      bad = true;
    }
    if (duplicate) return;
    if (bad)
      e.invalid_keys.push_back(a.key);
    else
      e.attrs.push_back(std::move(a));
  }

  std::string describe_entity(const EntityDesc& e) const {
    std::string s(entity_spec(e.kind).keyword);
    if (!e.name.empty()) s += " '" + e.name + "'";
    return s;
  }

  std::string_view text_;
  ModelLexer lex_;
  Diagnostics& diags_;
};

}  // namespace

SceneDesc parse_model(std::string_view text, Diagnostics& diags) {
  return ModelParser(text, diags).parse();
}

}  // namespace rayfarm
