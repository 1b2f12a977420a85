// The JSON reader shared by scenes and assignments (json_tree.h).
#include "format/json_tree.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <deque>
#include <set>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "rayfarm/json_scene.h"
#include "rayfarm/options.h"

namespace rayfarm {
namespace {

using Json = nlohmann::ordered_json;

// Builds the document from SAX events. nlohmann's own builders are quadratic for scenes of
// many entities (ordered_json looks keys up linearly; the callback parser rescans the parent
// after every child), have no depth limit and silently keep the last of repeated keys.
class TreeBuilder {
 public:
  explicit TreeBuilder(std::string_view text) : text_(text) {}

  bool null() { return add(nullptr); }
  bool boolean(bool v) { return add(v); }
  bool number_integer(Json::number_integer_t v) { return add(v); }
  bool number_unsigned(Json::number_unsigned_t v) { return add(v); }
  bool number_float(Json::number_float_t v, const std::string&) { return add(v); }
  bool string(std::string& v) { return add(std::move(v)); }
  bool binary(Json::binary_t&) { return add(nullptr); }  // JSON text has none
  bool start_object(std::size_t) { return open(Json::object()); }
  bool start_array(std::size_t) { return open(Json::array()); }
  bool end_object() { return close(); }
  bool end_array() { return close(); }

  bool key(std::string& k) {
    Frame& f = frames_.back();
    f.key = std::move(k);
    f.repeated = !f.keys.insert(f.key).second;
    if (f.repeated && duplicates_.size() < 20) duplicates_.push_back(path());
    return true;
  }

  bool parse_error(std::size_t position, const std::string& token, const Json::exception& e) {
    if (e.id == 406) {  // "number overflow parsing": point at the start of the number
      error_offset_ = position >= token.size() ? position - token.size() : 0;
      error_ = "the number " + token.substr(0, 60) + " is too large for a double";
    } else {
      // The position is one past the character that failed: point at the start of its
      // token instead, a string's opening quote or a word's first letter or digit.
      std::size_t at = std::min(position > 0 ? position - 1 : 0, text_.size());
      auto word = [&](std::size_t i) {
        const char c = i < text_.size() ? text_[i] : ' ';
        return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '+' || c == '-';
      };
      if (at < text_.size() && text_[at] == '"' && token.size() > 1 && token.back() == '"') {
        // The closing quote of a string: back to the quote no backslash escapes.
        for (std::size_t i = at; i-- > 0;) {
          if (text_[i] != '"') continue;
          std::size_t slashes = 0;
          while (slashes < i && text_[i - 1 - slashes] == '\\') ++slashes;
          if (slashes % 2 == 0) {
            at = i;
            break;
          }
        }
      } else {
        while (at > 0 && word(at) && word(at - 1)) --at;
      }
      error_offset_ = at;
      error_ = error_text(e.what());
    }
    return false;
  }

  Json& root() { return root_; }
  bool too_deep() const { return too_deep_; }
  const std::string& deep_path() const { return deep_path_; }
  const std::string& error() const { return error_; }
  size_t error_offset() const { return error_offset_; }
  const std::vector<std::string>& duplicates() const { return duplicates_; }

  // nlohmann's message without its "[json.exception...] " and "parse error at line L,
  // column C: " prefixes (the position is reported separately).
  static std::string error_text(const std::string& what) {
    std::string text = what;
    if (text.starts_with("[json.exception.")) {
      size_t close = text.find("] ");
      if (close != std::string::npos) text = text.substr(close + 2);
    }
    if (text.starts_with("parse error")) {
      size_t colon = text.find(": ");
      if (colon != std::string::npos) text = text.substr(colon + 2);
    }
    return text;
  }

 private:
  std::string_view text_;
  struct Frame {
    Json* node = nullptr;
    long index = -1;  // arrays: the element being read
    std::string key;  // objects: the member being read
    bool repeated = false;
    std::set<std::string> keys;
  };

  // Where the next value goes: the root, a new array element or a new member. A repeated
  // key's value is parsed into scratch space and dropped (it is reported as an error).
  Json* slot() {
    if (frames_.empty()) return &root_;
    Frame& f = frames_.back();
    if (f.node->is_array()) {
      ++f.index;
      f.node->push_back(nullptr);
      return &f.node->back();
    }
    if (f.repeated) return &scratch_.emplace_back();
    // Keys are unique here, so skip ordered_json's linear search for them.
    auto& members = static_cast<Json::object_t::Container&>(f.node->get_ref<Json::object_t&>());
    members.emplace_back(f.key, nullptr);
    return &members.back().second;
  }

  template <class V>
  bool add(V&& v) {
    *slot() = Json(std::forward<V>(v));
    return true;
  }

  bool open(Json container) {
    Json* node = slot();  // (before the check: the path then names this container's place)
    if (frames_.size() >= static_cast<size_t>(kMaxJsonDepth)) {
      too_deep_ = true;
      deep_path_ = path();
      return false;
    }
    *node = std::move(container);
    // Safe to keep: a container only grows while it is the innermost one.
    Frame frame;
    frame.node = node;
    frames_.push_back(std::move(frame));
    return true;
  }

  bool close() {
    frames_.pop_back();
    return true;
  }

  std::string path() const {
    std::string p;
    for (const Frame& f : frames_)
      p += f.node->is_array() ? "/" + std::to_string(f.index) : "/" + json_pointer_token(f.key);
    return p;
  }

  Json root_;
  std::vector<Frame> frames_;
  std::deque<Json> scratch_;
  std::vector<std::string> duplicates_;
  std::string error_;
  size_t error_offset_ = 0;
  bool too_deep_ = false;
  std::string deep_path_;
};

// Moves `at` past the JSON string that starts there; returns it, quotes included.
std::string_view string_token(std::string_view text, std::size_t& at) {
  const std::size_t start = at++;
  while (at < text.size() && text[at] != '"') at += text[at] == '\\' ? 2 : 1;
  at = std::min(at + 1, text.size());
  return text.substr(start, at - start);
}

// A member's key with its escapes decoded, as the parser decoded it.
std::string key_text(std::string_view token) {
  if (token.size() >= 2 && token.back() == '"' && token.find('\\') == std::string_view::npos)
    return std::string(token.substr(1, token.size() - 2));  // nothing to decode
  const Json j = Json::parse(token.begin(), token.end(), nullptr, false);
  return j.is_string() ? j.get<std::string>() : std::string(token);
}

}  // namespace

std::vector<std::size_t> json_pointer_offsets(std::string_view text,
                                              const std::vector<std::string>& pointers) {
  // The pointers and their holders, for those that name nothing.
  std::unordered_set<std::string> wanted;
  for (const std::string& p : pointers) {
    std::size_t end = p.size();
    while (wanted.insert(p.substr(0, end)).second && end > 0) {
      end = p.rfind('/', end - 1);
      if (end == std::string::npos) break;
    }
  }
  constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  std::unordered_map<std::string, std::size_t> found;
  auto note = [&](const std::string& path, std::size_t offset) {
    if (wanted.count(path)) found.emplace(path, offset);
  };
  // A walk of the text with the pointer of the value in hand; containers on a stack.
  struct Container {
    bool object;
    std::size_t base;  // length of the container's own pointer
    long index;
  };
  std::vector<Container> stack;
  std::string path;
  std::size_t at = text.starts_with("\xEF\xBB\xBF") ? 3 : 0;
  auto skip_blank = [&] {
    while (at < text.size() &&
           (text[at] == ' ' || text[at] == '\t' || text[at] == '\n' || text[at] == '\r'))
      ++at;
  };
  // A member's key (noted at its quote) and its ':', or false where the text has none.
  auto member = [&] {
    if (at >= text.size() || text[at] != '"') return false;
    const std::size_t key_at = at;
    path += "/" + json_pointer_token(key_text(string_token(text, at)));
    note(path, key_at);
    skip_blank();
    if (at >= text.size() || text[at] != ':') return false;
    ++at;
    return true;
  };
  auto element = [&](long index) {
    path += "/" + std::to_string(index);
    note(path, at);
  };
  note(path, 0);
  bool want_value = true;  // else: after a value, a ',' or a closing bracket is next
  while (at < text.size()) {
    skip_blank();
    if (at >= text.size()) break;
    const char c = text[at];
    if (want_value) {
      if (c == '{' || c == '[') {
        stack.push_back({c == '{', path.size(), 0});
        ++at;
        skip_blank();
        if (at < text.size() && (text[at] == '}' || text[at] == ']')) {
          ++at;
          stack.pop_back();
          want_value = false;
          continue;
        }
        if (c == '{') {
          if (!member()) break;
        } else {
          element(0);
        }
        continue;
      }
      if (c == '"') {
        string_token(text, at);
      } else {
        while (at < text.size() && text[at] != ',' && text[at] != '}' && text[at] != ']' &&
               text[at] != ' ' && text[at] != '\n' && text[at] != '\r' && text[at] != '\t')
          ++at;
      }
      want_value = false;
      continue;
    }
    if (stack.empty()) break;
    Container& top = stack.back();
    path.resize(top.base);
    if (c == ',') {
      ++at;
      skip_blank();
      if (top.object) {
        if (!member()) break;
      } else {
        element(++top.index);
      }
      want_value = true;
    } else if (c == '}' || c == ']') {
      ++at;
      stack.pop_back();
    } else {
      break;
    }
  }
  std::vector<std::size_t> out(pointers.size(), kNone);
  for (std::size_t i = 0; i < pointers.size(); ++i) {
    std::string_view p = pointers[i];
    for (;;) {  // the pointer, else the nearest holder found
      if (auto it = found.find(std::string(p)); it != found.end()) {
        out[i] = it->second;
        break;
      }
      const std::size_t slash = p.rfind('/');
      if (slash == std::string_view::npos) {
        out[i] = 0;
        break;
      }
      p = p.substr(0, slash);
    }
  }
  return out;
}

std::string json_pointer_token(std::string_view key) {
  std::string out;
  for (char c : key) {
    if (c == '~')
      out += "~0";
    else if (c == '/')
      out += "~1";
    else
      out += c;
  }
  return out;
}

std::string json_number_text(const Json& number) {
  if (number.is_number_unsigned()) return std::to_string(number.get<std::uint64_t>());
  if (number.is_number_integer()) return std::to_string(number.get<std::int64_t>());
  // A whole number written in float form (1e5, 100.0) is the integer it equals, so a
  // whole-number option takes it; the shortest form would be "1e+05".
  const double v = number.get<double>();
  if (std::abs(v) <= 0x1p53 && v == std::floor(v))
    return std::to_string(static_cast<std::int64_t>(v));
  return format_number(v);
}

std::optional<Json> parse_json_tree(std::string_view text, Diagnostics& diags) {
  // nlohmann's reader takes a NUL byte for the end of the text: what follows it would go
  // unread, unchecked.
  if (const size_t nul = text.find('\0'); nul != std::string_view::npos) {
    diags.error("json-syntax", "invalid JSON: a NUL byte (the file is not plain text)",
                position_of_offset(text, nul));
    return std::nullopt;
  }
  TreeBuilder builder(text);
  bool parsed = false;
  try {
    parsed = Json::sax_parse(text.begin(), text.end(), &builder);
  } catch (const Json::exception& e) {
    diags.error("json-syntax", "invalid JSON: " + TreeBuilder::error_text(e.what()), {});
    return std::nullopt;
  }
  if (builder.too_deep()) {
    diags.error("json-depth",
                "JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels",
                Where{0, 0, builder.deep_path()});
    return std::nullopt;
  }
  if (!parsed) {
    diags.error("json-syntax", "invalid JSON: " + builder.error(),
                position_of_offset(text, builder.error_offset()));
    return std::nullopt;
  }
  for (const std::string& path : builder.duplicates())
    diags.error("duplicate-key", "key given twice", Where{0, 0, path});
  return std::move(builder.root());
}

}  // namespace rayfarm
