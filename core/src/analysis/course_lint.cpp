// Course lint: where the course's reference program (CPSC 102, 2014–18) would stop on, or
// misread, a model file that rayfarm's kinder parser may accept.
//
// The model of that program (docs/profiles.md §4–5, and the course's given model.c, object.c,
// parser.c, material.cpp and ray.h):
// - model_load reads a word with fscanf("%s") and dispatches on it; an unknown word prints
//   "bad entity WORD" and exits. There are no comments: '#' and '//' are words like any other.
// - Each entity reads its name ("%s" into a 32-byte buffer), then a word whose first character
//   must be '{' (the rest of that word is dropped). Objects then require `material NAME`, with
//   NAME defined earlier in the file.
// - parser() reads attribute names ("%s") and each value with one fscanf ("%lf", "%d" or "%s");
//   a name not in its table prints "bad attr NAME" and asserts, a failed value read asserts.
//   A number stops at the first character that cannot continue it, which stays in the stream:
//   `radius 2}` is fine, `pixeldim 640.5 480` reads 640 and then fails on ".5".
// - Attribute groups are separate parser() calls (course_grammar.cpp): each but the last reads
//   exactly as many attributes as it has, so order between groups matters, inside a group not.
// - A word of '}' (or starting with it) ends an entity; the rest of that word is dropped.
//
// Where the course is silent, this lint decides:
// - Every attribute of an object's or light's groups is required (the constructors in students'
//   copies assert `mask == 3`), and a camera needs all three; a material needs at least one
//   (the given material.cpp asserts it). Repeating an attribute is fatal only in a group that
//   reads a fixed count; in the last group the later value wins.
// - A brace glued to a word is reported once; the lint then reads the word as if split there
//   (what the student meant), although the program would drop or keep the rest of the word.
// - triangle: one group in free order, normal and point optional (no reference run exists).
// - Names (entities, materials, textures) over 31 characters overflow; texname over 63; the
//   size of a texture's filename buffer is unknown, so paths are not checked.
// - texname names a texture defined earlier, or else is a path: a word with no '/' or '.' that
//   names no earlier texture is reported as an undefined texture.
// - Hexadecimal, inf and nan numbers are read as glibc's scanf reads them (no warning).
//
// After a problem the lint goes on as rayfarm would read the file (the student wants every
// problem at once) and avoids cascades: one warning per problem, at the token where the course
// program fails (too few values: at the attribute), then it resynchronises at the next known
// attribute, '}' or entity keyword that starts an entity (`KEYWORD NAME {`). A block of comment
// lines is one problem; after an order or unknown-attribute problem an entity reports no more
// order or missing attributes.
#include <algorithm>
#include <array>
#include <string>
#include <vector>

#include "analysis/course_grammar.h"
#include "analysis/course_stream.h"
#include "format/model_lexer.h"
#include "rayfarm/lint.h"
#include "util/name_set.h"

namespace rayfarm {
namespace {

using course::Attr;
using course::Entity;
using course::Stream;
using course::Value;
using course::Word;

constexpr std::string_view kProgram = "the course's program";

std::string quote(std::string_view s) {
  constexpr size_t kShown = 40;
  return "'" + std::string(s.substr(0, kShown)) + (s.size() > kShown ? "...'" : "'");
}

std::string plural(int n, std::string_view one) {
  return std::to_string(n) + " " + std::string(one) + (n == 1 ? "" : "s");
}

// "normal and point", "a, b and c"
std::string join(const std::vector<std::string_view>& words) {
  std::string out;
  for (size_t i = 0; i < words.size(); ++i) {
    if (i > 0) out += i + 1 == words.size() ? " and " : ", ";
    out += words[i];
  }
  return out;
}

bool starts_comment(std::string_view w) {
  return w.starts_with('#') || w.starts_with("//") || w.starts_with("/*");
}

bool is_letter(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }

bool is_keyword(std::string_view w) {
  return course::find_entity(w) || w == "tri" || w == "pplane";
}

// What the program was about to read when it met a word, for the messages.
enum class Reading { entity, name, brace, attribute, number };

class CourseLinter {
 public:
  explicit CourseLinter(std::string_view text) : text_(text), in_(text) {}

  std::vector<Diagnostic> run();

 private:
  // The state of one entity's body.
  struct Body {
    Body(const Entity& e, std::string l, const Word& k)
        : entity(e), label(std::move(l)), keyword(k) {}
    const Entity& entity;
    std::string label;  // "sphere 'left'"
    Word keyword;
    size_t group = 0;  // the group the program is reading
    std::array<std::array<bool, course::kMaxGroupSize>, course::kMaxGroups> seen{};
    bool any_seen = false;
    bool material_missing = false;  // an object without `material` first (already reported)
    bool quiet = false;             // an order or unknown-attribute problem was reported
    const Attr* last = nullptr;     // the attribute whose values were read last
    std::string_view last_first_value;
  };

  void warn(std::string_view code, std::string message, Where where) {
    out_.push_back({Severity::warning, std::string(code), std::move(message), std::move(where)});
  }
  // Enough warnings for what Diagnostics keeps: a garbage file stops early.
  bool full() const { return out_.size() >= 2 * Diagnostics::kMaxErrors; }
  Word peek(Reading reading);

  void lint_entity(const Word& keyword, const Entity& entity, bool brace_reported);
  std::string_view read_name(const Word& keyword, bool& brace_reported);
  void read_open_brace(const std::string& label, bool already_reported);
  void read_body(Body& b);
  void read_attribute(Body& b, const Word& w, course::AttrRef ref);
  void read_values(Body& b, const Attr& attr, const Word& name);
  std::string_view read_word_value(Body& b, const Attr& attr, const Word& name);
  void check_material(const Body& b, std::string_view attr, std::string_view name, const Word& w);
  void check_missing(const Body& b, const Word& close);
  void unknown_attribute(Body& b, const Word& w, std::string_view word);
  void skip_to_known(const Body& b);
  static bool brace_follows(Stream probe);
  bool entity_starts_here() const;
  void skip_unknown_entity();
  void skip_block();
  void skip_vector(std::string_view first);
  std::string glued_brace(std::string_view word, size_t at, std::string_view taken_as);

  std::string_view text_;
  Stream in_;
  int comment_end_line_ = -1;  // the last line of the comment before, and its column
  int comment_column_ = 0;
  std::vector<Diagnostic> out_;
  // Defined so far: a set to look names up, a list for typo hints.
  struct Names {
    NameSet<int> set;
    std::vector<std::string_view> list;
    bool has(std::string_view name) const { return set.find(name) != nullptr; }
    void add(std::string_view name) {
      if (!set.insert(name, 0)) list.push_back(name);
    }
    std::string hint(std::string_view name) const { return nearest_word(name, list); }
  };
  Names materials_;
  Names textures_;
  struct Pending {
    size_t warning;
    std::string_view kind;  // "material" or "texture"
    std::string name;
  };
  std::vector<Pending> pending_;  // undefined-name warnings, in case it is defined later
};

Word CourseLinter::peek(Reading reading) {
  for (;;) {
    Word w = in_.peek();
    if (!w || !starts_comment(w.text)) return w;
    std::string first = quote(w.text);
    std::string what;
    switch (reading) {
      case Reading::entity:
        what = "read " + first + " as an entity keyword and stop with 'bad entity " +
               std::string(w.text) + "'";
        break;
      case Reading::attribute:
        what = "read " + first + " as an attribute name and stop with 'bad attr " +
               std::string(w.text) + "'";
        break;
      case Reading::number:
        what = "fail to read " + first + " as a number and stop";
        break;
      case Reading::name:
        what = "take " + first + " as a name";
        break;
      case Reading::brace:
        what = "stop at " + first + ", which is not '{'";
        break;
    }
    // A block of comment lines is one problem, reported at its first line.
    if (w.where.line != comment_end_line_ + 1 || w.where.column != comment_column_)
      warn("course-comment",
           std::string(kProgram) + " has no comments: it would " + what + "; delete the comment",
           w.where);
    comment_column_ = w.where.column;
    if (w.text.starts_with("/*"))
      in_.skip_past("*/");
    else
      in_.skip_line();
    comment_end_line_ = in_.line();
  }
}

std::string CourseLinter::glued_brace(std::string_view word, size_t at, std::string_view taken_as) {
  return quote(word) + " is one word to " + std::string(kProgram) +
         ": a brace counts only as the first character of a word, so it takes " + quote(word) +
         " as " + std::string(taken_as) + "; put a space before '" + word[at] + "'";
}

std::vector<Diagnostic> CourseLinter::run() {
  if (text_.starts_with("\xEF\xBB\xBF"))
    warn("course-unknown-entity",
         "the file starts with a UTF-8 byte-order mark (bytes EF BB BF, invisible in most "
         "editors): " +
             std::string(kProgram) +
             " reads them as part of the first word and stops with 'bad entity'; save the file "
             "without it",
         {1, 1, {}});
  while (!full()) {
    Word w = peek(Reading::entity);
    if (!w) break;
    std::string_view t = w.text;
    if (t[0] == '}' || t[0] == '{') {
      warn("course-brace",
           std::string(t[0] == '}' ? "an extra '}'" : "a '{' with no entity before it") + ": " +
               std::string(kProgram) + " reads " + quote(t) +
               " as an entity keyword and stops with 'bad entity " + std::string(t) + "'",
           w.where);
      if (t[0] == '{')
        skip_block();
      else
        in_.take(1);
      continue;
    }
    size_t brace = t.find_first_of("{}");
    std::string_view keyword = t.substr(0, brace);
    if (const Entity* e = course::find_entity(keyword)) {
      const bool glued = brace != std::string_view::npos;
      if (glued)  // `camera{`: the name is missing too, one problem
        warn("course-brace",
             glued_brace(t, brace,
                         "the entity keyword and stops with 'bad entity " + std::string(t) + "'") +
                 " and give a name: '" + std::string(keyword) + " NAME {'",
             w.at(brace));
      in_.take(keyword.size());
      lint_entity(w, *e, glued);
      continue;
    }
    std::string message;
    if (keyword == "tri")
      message =
          "'tri' is the 2009 program's triangle: the course's 2014-18 program stops here "
          "with 'bad entity tri'; write 'triangle NAME { material M vertex1 x y z vertex2 x y z "
          "vertex3 x y z }'";
    else if (keyword == "pplane")
      message =
          "'pplane' is only a name in the course's header (its model.c has it commented "
          "out): " +
          std::string(kProgram) + " stops here with 'bad entity pplane'; use " +
          "plane, fplane, tiled_plane or texplane";
    else {
      message = "unknown entity " + quote(t) + ": " + std::string(kProgram) +
                " stops here with 'bad entity " + std::string(t) + "'";
      if (looks_like_value(t))
        message += " (a value too many at the end of the entity before?)";
      else if (std::string hint = nearest_word(keyword, course::entity_keywords()); !hint.empty())
        message += " (did you mean '" + hint + "'?)";
    }
    warn("course-unknown-entity", std::move(message), w.where);
    in_.take(t.size());
    skip_unknown_entity();
  }
  std::stable_sort(out_.begin(), out_.end(), [](const Diagnostic& a, const Diagnostic& b) {
    return a.where.line != b.where.line ? a.where.line < b.where.line
                                        : a.where.column < b.where.column;
  });
  return std::move(out_);
}

// Whether the next word is an entity keyword that starts an entity: a '{' follows within two
// words. A keyword in prose or used as a value does not.
bool CourseLinter::entity_starts_here() const {
  Stream probe = in_;
  Word keyword = probe.peek();
  const size_t brace = keyword.text.find('{');
  if (!is_keyword(keyword.text.substr(0, brace))) return false;
  if (brace != std::string_view::npos) return true;
  probe.take(keyword.text.size());
  return brace_follows(probe);
}

// Whether a '{' follows within the next two words (not crossing an entity keyword).
bool CourseLinter::brace_follows(Stream probe) {
  for (int i = 0; i < 2; ++i) {
    Word w = probe.peek();
    if (!w || is_keyword(w.text)) return false;
    if (w.text.find('{') != std::string_view::npos) return true;
    probe.take(w.text.size());
  }
  return false;
}

// Resumes after an entity the program does not know (its keyword already read): past its body
// when it has one, else at the next entity keyword that starts an entity (`KEYWORD NAME {`),
// so that prose or a stray word does not restart on a keyword inside it.
void CourseLinter::skip_unknown_entity() {
  if (brace_follows(in_)) return skip_block();
  for (Word w = in_.peek(); w && !entity_starts_here(); w = in_.peek()) in_.take(w.text.size());
}

// Up to and including the '}' that closes the next '{'.
void CourseLinter::skip_block() {
  int depth = 0;
  bool opened = false;
  for (Word w = in_.peek(); w; w = in_.peek()) {
    in_.take(w.text.size());
    for (char c : w.text) {
      if (c == '{') ++depth, opened = true;
      if (c == '}' && depth > 0) --depth;
    }
    if (opened && depth == 0) return;
  }
}

void CourseLinter::lint_entity(const Word& keyword, const Entity& entity, bool brace_reported) {
  std::string_view name = read_name(keyword, brace_reported);
  Body b{entity, std::string(entity.keyword) + (name.empty() ? "" : " " + quote(name)), keyword};
  if (entity.keyword == "material") materials_.add(name);
  if (entity.keyword == "texture") textures_.add(name);
  // A use before the definition: say where the definition is.
  auto later = [&](const Pending& p) { return p.kind == entity.keyword && p.name == name; };
  for (const Pending& p : pending_)
    if (later(p))
      out_[p.warning].message +=
          " (it is defined later, at line " + std::to_string(keyword.where.line) + ")";
  std::erase_if(pending_, later);
  read_open_brace(b.label, brace_reported);
  read_body(b);
}

std::string_view CourseLinter::read_name(const Word& keyword, bool& brace_reported) {
  Word w = peek(Reading::name);
  if (!w) return {};  // the body reports the end of the file
  std::string_view kind = keyword.text.substr(0, keyword.text.find_first_of("{}"));
  if (w.text[0] == '{' || w.text[0] == '}') {
    if (brace_reported) return {};
    warn("course-missing-name",
         std::string(kind) + " has no name: " + std::string(kProgram) + " takes " + quote(w.text) +
             " as its name and then stops because the next word is not '{'; " + "write '" +
             std::string(kind) + " NAME {'",
         w.where);
    brace_reported = true;
    return {};
  }
  size_t brace = w.text.find_first_of("{}");
  std::string_view name = w.text.substr(0, brace);
  if (brace != std::string_view::npos) {
    warn("course-brace",
         glued_brace(w.text, brace, "the name, then stops because the next word is not '{'"),
         w.at(brace));
    brace_reported = true;
  }
  in_.take(name.size());
  if (name.size() > course::kNameMax)
    warn("course-name-length",
         "the name " + quote(name) + " has " + std::to_string(name.size()) + " characters: " +
             std::string(kProgram) + " keeps names in 32-byte buffers (31 characters and the " +
             "terminating NUL) and would write past the end; shorten it",
         w.where);
  return name;
}

void CourseLinter::read_open_brace(const std::string& label, bool already_reported) {
  Word w = peek(Reading::brace);
  if (!w) return;
  if (w.text[0] == '{') {
    const bool braces = w.text.find_first_not_of('{') == std::string_view::npos;
    in_.take(braces ? w.text.size() : 1);
    if (!braces)
      warn("course-brace",
           quote(w.text) + ": " + std::string(kProgram) +
               " checks only the first character of the word after the name and drops the " +
               "rest, " + quote(w.text.substr(1)) + ", so what follows is misread; put a " +
               "space after '{'",
           w.where);
    return;
  }
  if (!already_reported)
    warn("course-brace",
         "no '{' after " + label + ": " + std::string(kProgram) + " stops here because " +
             quote(w.text) + " does not start with '{'",
         w.where);
}

void CourseLinter::read_body(Body& b) {
  if (b.entity.object) {
    Word w = peek(Reading::attribute);
    if (w && w.text == "material") {
      in_.take(w.text.size());
      read_word_value(b, {"material", 1, Value::material}, w);
    } else if (w) {
      b.material_missing = true;
      warn("course-material-first",
           std::string(kProgram) + " requires 'material NAME' as the first attribute of " +
               b.label + ": it stops here because " + quote(w.text) +
               " is not 'material'; start the body with the material",
           w.where);
    }
  }
  bool extra_reported = false;  // values too many, reported once per run of them
  while (!full()) {
    Word w = peek(Reading::attribute);
    if (!w) {
      warn("course-brace",
           b.label + " is not closed: the file ends before its '}' and " + std::string(kProgram) +
               " stops",
           b.keyword.where);
      return;
    }
    std::string_view t = w.text;
    if (t[0] == '}') {
      // The program drops the rest of the word: harmless when it is more '}'.
      const bool braces = t.find_first_not_of('}') == std::string_view::npos;
      in_.take(braces ? t.size() : 1);
      if (!braces)
        warn("course-brace",
             quote(t) + ": " + std::string(kProgram) + " ends " + b.label +
                 " at the '}' and drops the rest of the word, " + quote(t.substr(1)) +
                 "; put a space after '}'",
             w.where);
      check_missing(b, w);
      return;
    }
    if (t[0] == '{') {
      warn("course-brace",
           "a '{' inside " + b.label + ": " + std::string(kProgram) +
               " reads it as an attribute name and stops with 'bad attr " + std::string(t) + "'",
           w.where);
      in_.take(1);
      continue;
    }
    if (looks_like_value(t) || t[0] == '<' || t[0] == '(') {
      if (!extra_reported) {
        std::string message = quote(t) + " is a value too many";
        if (b.last) {
          message += " for " + std::string(b.last->name) + ", which takes " +
                     plural(b.last->count, "number");
          if (!b.last->note.empty()) message += " in the 2014-18 program";
        }
        message += ": " + std::string(kProgram) + " would read " + quote(t) +
                   " as an attribute name and stop with 'bad attr " + std::string(t) + "'";
        if (b.last && b.last->count == 1 && !b.last_first_value.empty())
          message +=
              "; write '" + std::string(b.last->name) + " " + std::string(b.last_first_value) + "'";
        if (b.last && !b.last->note.empty()) message += " (" + std::string(b.last->note) + ")";
        warn("course-value-count", std::move(message), w.where);
      }
      extra_reported = true;
      in_.take(t.size());
      continue;
    }
    extra_reported = false;
    size_t brace = t.find_first_of("{}");
    std::string_view word = t.substr(0, brace);
    course::AttrRef ref = course::find_attr(b.entity, word);
    bool late_material = b.entity.object && word == "material";
    if (!ref && !late_material && entity_starts_here()) {
      warn("course-brace",
           b.label + " has no '}' before this " + quote(word) + ": " + std::string(kProgram) +
               " reads it as an attribute and stops with 'bad attr " + std::string(t) +
               "'; close " + b.label + " first",
           w.where);
      return;
    }
    if (brace != std::string_view::npos)
      warn("course-brace",
           glued_brace(t, brace,
                       "an attribute name and stop with 'bad attr " + std::string(t) + "'"),
           w.at(brace));
    in_.take(word.size());
    if (ref) {
      read_attribute(b, w, ref);
    } else if (late_material) {
      if (!b.material_missing)
        warn("course-duplicate-attribute",
             "a second 'material' in " + b.label + ": " + std::string(kProgram) +
                 " reads the material only as the first attribute and stops here with 'bad " +
                 "attr material'; give it once, first",
             w.where);
      b.material_missing = false;
      read_word_value(b, {"material", 1, Value::material}, w);
    } else {
      unknown_attribute(b, w, word);
    }
  }
}

void CourseLinter::read_attribute(Body& b, const Word& w, course::AttrRef ref) {
  const auto& groups = b.entity.groups;
  const size_t g = static_cast<size_t>(ref.group);
  const Attr& attr = groups[g][static_cast<size_t>(ref.index)];
  auto group_names = [&](size_t k) {
    std::vector<std::string_view> names;
    for (const Attr& a : groups[k]) names.push_back(a.name);
    return join(names);
  };
  bool& seen = b.seen[g][static_cast<size_t>(ref.index)];
  if (g == b.group) {
    if (seen && g + 1 < groups.size()) {
      warn("course-duplicate-attribute",
           std::string(attr.name) + " is given twice: " + std::string(kProgram) + " reads " +
               "exactly " + std::to_string(groups[g].size()) + " attributes here (" +
               group_names(g) + "), so it would stop after this one with the others unread; " +
               "remove one",
           w.where);
      b.quiet = true;
    }
  } else if (!b.quiet) {
    std::string message;
    if (g > b.group) {
      std::vector<std::string_view> unread;
      for (size_t k = b.group; k < g; ++k)
        for (size_t i = 0; i < groups[k].size(); ++i)
          if (!b.seen[k][i]) unread.push_back(groups[k][i].name);
      message = std::string(kProgram) + " reads the attributes of " + b.label + " in groups (" +
                group_names(b.group) + " first, then " + group_names(b.group + 1) + "): with " +
                join(unread) + " not yet given it would stop here with 'bad attr " +
                std::string(attr.name) + "'; give " + join(unread) + " before " +
                std::string(attr.name);
    } else {
      message = std::string(attr.name) + " belongs to the group " + group_names(g) + ", which " +
                std::string(kProgram) + " reads before " + group_names(b.group) +
                ": here it would stop with 'bad attr " + std::string(attr.name) + "'; move it up";
    }
    warn("course-order", std::move(message), w.where);
    b.quiet = true;
  }
  seen = true;
  b.any_seen = true;
  b.group = std::max(b.group, g);
  // A group that reads a fixed count hands over to the next once all of it was read.
  auto complete = [&](size_t k) {
    for (size_t i = 0; i < groups[k].size(); ++i)
      if (!b.seen[k][i]) return false;
    return true;
  };
  while (b.group + 1 < groups.size() && complete(b.group)) ++b.group;
  b.last = &attr;
  read_values(b, attr, w);
}

void CourseLinter::read_values(Body& b, const Attr& attr, const Word& name) {
  b.last_first_value = {};
  if (attr.value != Value::real && attr.value != Value::integer) {
    b.last_first_value = read_word_value(b, attr, name);
    return;
  }
  const bool integer = attr.value == Value::integer;
  bool reported = false;
  for (int i = 0; i < attr.count; ++i) {
    Word w = peek(Reading::number);
    if (!w) return;
    std::string_view t = w.text;
    size_t n = course::number_prefix(t, integer);
    bool vector = t[0] == '<' || t[0] == '(' || (n < t.size() && t[n] == ',') ||
                  (n == 0 && t.find(',') != std::string_view::npos);
    if (vector) {
      warn("course-vector-syntax",
           quote(t) + ": " + std::string(kProgram) + " reads " + std::string(attr.name) + " as " +
               plural(attr.count, "number") + " separated by white space and stops at " +
               quote(t.substr(n, 1)) + "; write '" + std::string(attr.name) + " x y z' without " +
               "brackets or commas",
           w.where);
      skip_vector(t);
      return;
    }
    if (n == 0 && (t[0] == '}' || is_letter(t[0]))) {
      warn("course-value-count",
           std::string(attr.name) + " takes " + plural(attr.count, "number") + ", given " +
               std::to_string(i) + ": " + std::string(kProgram) + " would try to read " + quote(t) +
               " as the next one and stop; give all " + std::to_string(attr.count) +
               (i == 1 && attr.count == 3  // rayfarm's one-number colour
                    ? ": '" + std::string(attr.name) + " " + std::string(b.last_first_value) + " " +
                          std::string(b.last_first_value) + " " + std::string(b.last_first_value) +
                          "'"
                    : ""),
           name.where);
      return;
    }
    if (i == 0) b.last_first_value = t.substr(0, n ? n : t.size());
    if (n == t.size() || (n > 0 && (t[n] == '}' || starts_comment(t.substr(n))))) {
      in_.take(n);
      continue;
    }
    if (!reported) {
      std::string message = quote(t) + " is not " + (integer ? "a whole number" : "a number") +
                            " to " + std::string(kProgram) + " (" + (integer ? "%d" : "%lf") + ")";
      message += n == 0 ? ": it stops here"
                        : ": it reads " + quote(t.substr(0, n)) + " and then " +
                              quote(t.substr(n)) + " as the next thing, which misreads or stops";
      if (integer) message += "; " + std::string(attr.name) + " takes whole numbers";
      warn("course-number", std::move(message), w.where);
      reported = true;
    }
    in_.take(t.size());
  }
}

// A word read with %s: a material, a texture name or path, a file name.
std::string_view CourseLinter::read_word_value(Body& b, const Attr& attr, const Word& name) {
  Word w = peek(Reading::name);
  if (!w) return {};
  std::string_view t = w.text;
  if (t[0] == '}' || t[0] == '{') {
    warn("course-value-count",
         std::string(attr.name) + " needs a " + (attr.value == Value::path ? "file name" : "name") +
             ": " + std::string(kProgram) + " would take " + quote(t) +
             " as it and read on past the end of " + b.label,
         name.where);
    return {};
  }
  size_t brace = t.find_first_of("{}");
  std::string_view value = t.substr(0, brace);
  if (brace != std::string_view::npos)
    warn("course-brace",
         glued_brace(t, brace,
                     "the value of " + std::string(attr.name) +
                         (t[brace] == '}' ? " and reads on past the end of " + b.label : "")),
         w.at(brace));
  in_.take(value.size());
  if (attr.value == Value::material) {
    check_material(b, attr.name, value, w);
  } else if (attr.value == Value::texture) {
    if (value.size() > course::kTexnameMax)
      warn("course-name-length",
           "the texname " + quote(value) + " has " + std::to_string(value.size()) +
               " characters: " + std::string(kProgram) + " keeps it in a 64-byte buffer (63 " +
               "characters and the NUL) and would write past the end; shorten it",
           w.where);
    if (!textures_.has(value) && value.find_first_of("/.") == std::string_view::npos) {
      std::string hint = textures_.hint(value);
      pending_.push_back({out_.size(), "texture", std::string(value)});
      warn("course-undefined-texture",
           "no texture " + quote(value) + " is defined before " + b.label + ": " +
               std::string(kProgram) + " would take " + quote(value) +
               " as the path of an image file" +
               (hint.empty() ? "" : " (did you mean '" + hint + "'?)"),
           w.where);
    }
  }
  return value;
}

void CourseLinter::check_material(const Body& b, std::string_view attr, std::string_view name,
                                  const Word& w) {
  // A long name of a defined material was reported at its definition: renaming fixes both.
  if (name.size() > course::kNameMax && !materials_.has(name))
    warn("course-name-length",
         "the material name " + quote(name) + " has " + std::to_string(name.size()) +
             " characters: " + std::string(kProgram) + " reads it into a 32-byte buffer (31 " +
             "characters and the NUL) and would write past the end; shorten it",
         w.where);
  if (materials_.has(name)) return;
  std::string hint = materials_.hint(name);
  pending_.push_back({out_.size(), "material", std::string(name)});
  warn("course-undefined-material",
       std::string(attr) + " " + quote(name) + " of " + b.label + " is not defined before it: " +
           std::string(kProgram) + " looks materials up as it reads and stops here" +
           (hint.empty() ? "" : " (did you mean '" + hint + "'?)"),
       w.where);
}

void CourseLinter::check_missing(const Body& b, const Word& close) {
  if (b.quiet || b.material_missing) return;
  if (b.entity.keyword == "material") {
    if (!b.any_seen)
      warn("course-missing-attribute",
           b.label + " has no attributes: " + std::string(kProgram) +
               " requires at least one (ambient, diffuse, specular, shininess or transparency) " +
               "and stops",
           close.where);
    return;
  }
  std::vector<std::string_view> missing;
  for (size_t g = 0; g < b.entity.groups.size(); ++g)
    for (size_t i = 0; i < b.entity.groups[g].size(); ++i)
      if (b.entity.groups[g][i].required && !b.seen[g][i])
        missing.push_back(b.entity.groups[g][i].name);
  if (missing.empty()) return;
  std::vector<std::string_view> required;
  for (const course::Group& g : b.entity.groups)
    for (const Attr& a : g)
      if (a.required) required.push_back(a.name);
  warn("course-missing-attribute",
       b.label + " has no " + join(missing) + ": " + std::string(kProgram) + " requires " +
           join(required) + " and stops at this '}'; add " + (missing.size() == 1 ? "it" : "them"),
       close.where);
}

void CourseLinter::unknown_attribute(Body& b, const Word& w, std::string_view word) {
  std::string message;
  if (b.entity.keyword == "tiled_plane" && word == "dimension") {
    message = "'dimension' is the 2009 program's tiled_plane: the course's 2014-18 program " +
              std::string("stops here with 'bad attr dimension'; write 'xdir x y z' and ") +
              "'dimensions w h' after normal and point";
  } else if (word == "v0" || word == "v1" || word == "v2") {
    message = quote(word) + " is the 2009 program's tri: the course's 2014-18 program stops " +
              "here with 'bad attr " + std::string(word) + "'; write vertex1, vertex2 and vertex3";
  } else {
    message = b.label + " has no attribute " + quote(word) + " in " + std::string(kProgram) +
              ": it stops here with 'bad attr " + std::string(word) + "'";
    std::vector<std::string_view> names;
    for (const course::Group& g : b.entity.groups)
      for (const Attr& a : g) names.push_back(a.name);
    if (b.entity.object) names.push_back("material");
    std::vector<std::string_view> owners;
    for (const Entity& e : course::entities())
      if (course::find_attr(e, word)) owners.push_back(e.keyword);
    if (std::string hint = nearest_word(word, names); !hint.empty())
      message += " (did you mean '" + hint + "'?)";
    else if (!owners.empty())
      message += " (" + std::string(word) + " is an attribute of " + join(owners) + ")";
  }
  warn("course-unknown-attribute", std::move(message), w.where);
  b.quiet = true;
  skip_to_known(b);
}

// After an unknown attribute: its values, up to the next known attribute, '}' or entity.
void CourseLinter::skip_to_known(const Body& b) {
  for (Word w = peek(Reading::attribute); w; w = peek(Reading::attribute)) {
    std::string_view t = w.text;
    if (t[0] == '{' || t[0] == '}') return;
    std::string_view word = t.substr(0, t.find_first_of("{}"));
    if (course::find_attr(b.entity, word) || (b.entity.object && word == "material") ||
        entity_starts_here())
      return;
    in_.take(word.size());
  }
}

// `<1, 2, 3>`, `(1,2,3)`, `1,2,3` or `1, 2, 3`: up to its closing bracket or last comma part.
void CourseLinter::skip_vector(std::string_view first) {
  const char open = first[0];
  const char close = open == '<' ? '>' : open == '(' ? ')' : 0;
  for (int i = 0; i < 8; ++i) {
    Word w = in_.peek();
    if (!w || w.text[0] == '}' || (i > 0 && is_letter(w.text[0]))) return;
    if (close) {
      size_t end = w.text.find(close);
      if (end != std::string_view::npos) {
        in_.take(end + 1);
        return;
      }
      in_.take(w.text.size());
      continue;
    }
    size_t end = w.text.find('}');
    std::string_view part = w.text.substr(0, end);
    in_.take(part.size());
    if (end != std::string_view::npos || !part.ends_with(',')) {
      Word next = in_.peek();
      if (!next || !next.text.starts_with(',')) return;
    }
  }
}

}  // namespace

void lint_course(std::string_view text, Diagnostics& diags) {
  for (Diagnostic& d : CourseLinter(text).run())
    diags.warning(std::move(d.code), std::move(d.message), std::move(d.where));
}

}  // namespace rayfarm
