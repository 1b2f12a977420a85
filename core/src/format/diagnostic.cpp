// Diagnostics: collection with a cap, clang-style formatting, typo suggestions.
#include "rayfarm/diagnostic.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <sstream>

#include "util/lines.h"
#include "util/utf8.h"

namespace rayfarm {

namespace {

// Text as it may be shown on a terminal or in a log: control bytes (an escape sequence in a
// hostile file) and bytes that are not valid UTF-8 become '?', one for one (so a caret under a
// source line still lines up); tabs stay where asked. At most `max_length` bytes, then "...".
std::string printable(std::string_view text, bool keep_tabs, size_t max_length) {
  std::string out;
  out.reserve(std::min(text.size(), max_length));
  for (size_t i = 0; i < text.size();) {
    if (out.size() >= max_length - 7) {
      out += "...";
      break;
    }
    auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x80) {
      const bool control = (c < 0x20 && !(keep_tabs && c == '\t')) || c == 0x7f;
      out += control ? '?' : static_cast<char>(c);
      ++i;
    } else if (size_t n = utf8_length(text, i)) {
      out.append(text, i, n);
      i += n;
    } else {
      out += '?';
      ++i;
    }
  }
  return out;
}

// Messages quote the input: keep each one short printable line of valid UTF-8 whatever was
// sent, so it cannot break a terminal, a log line or a JSON error body.
std::string clean(const std::string& message) { return printable(message, false, 1000); }

}  // namespace

void Diagnostics::error(std::string code, std::string message, Where where) {
  ++errors_;
  if (errors_ > kMaxErrors) {
    truncated_ = true;
    return;
  }
  where.path = clean(std::move(where.path));
  items_.push_back({Severity::error, std::move(code), clean(std::move(message)), std::move(where)});
}

void Diagnostics::warning(std::string code, std::string message, Where where) {
  if (items_.size() >= 2 * kMaxErrors) {
    truncated_ = true;
    return;
  }
  where.path = clean(std::move(where.path));
  items_.push_back(
      {Severity::warning, std::move(code), clean(std::move(message)), std::move(where)});
}

void sort_by_place(std::vector<Diagnostic>& ds, const std::vector<size_t>& place) {
  std::vector<size_t> order(ds.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return (a < place.size() ? place[a] : 0) < (b < place.size() ? place[b] : 0);
  });
  std::vector<Diagnostic> sorted;
  sorted.reserve(ds.size());
  for (size_t i : order) sorted.push_back(std::move(ds[i]));
  ds = std::move(sorted);
}

void Diagnostics::reorder(const std::vector<size_t>& place) { sort_by_place(items_, place); }

std::string Diagnostics::error_count_text() const {
  return counted_all_ ? std::to_string(errors_) : "more than " + std::to_string(kMaxErrors);
}

const Diagnostic* Diagnostics::first_error() const {
  for (const Diagnostic& d : items_)
    if (d.severity == Severity::error) return &d;
  return nullptr;
}

namespace {

std::string_view source_line(std::string_view source, int line) {
  size_t start = 0;
  for (int l = 1; l < line; ++l) {
    size_t nl = find_line_end(source, start);
    if (nl == std::string_view::npos) return {};
    start = nl + 1;
  }
  size_t end = find_line_end(source, start);
  std::string_view text =
      source.substr(start, end == std::string_view::npos ? source.size() - start : end - start);
  if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
  return text;
}

}  // namespace

std::string format_diagnostic(const Diagnostic& d, std::string_view file_name,
                              std::string_view source) {
  std::ostringstream out;
  const char* kind = d.severity == Severity::error ? "error" : "warning";
  out << file_name;
  if (d.where.line > 0) out << ':' << d.where.line << ':' << d.where.column;
  out << ": " << kind << ": ";
  if (!d.where.path.empty()) out << "at " << d.where.path << ": ";
  out << d.message << '\n';
  if (d.where.line > 0) {
    std::string_view text = source_line(source, d.where.line);
    size_t upto = std::min(static_cast<size_t>(std::max(d.where.column, 1) - 1), text.size());
    // A long line (minified JSON is one) is shown as the stretch around the column.
    constexpr size_t kLongLine = 400, kAround = 60;
    bool cut_left = false, cut_right = false;
    if (text.size() > kLongLine) {
      size_t from = upto > kAround ? upto - kAround : 0;
      size_t to = std::min(text.size(), upto + kAround);
      auto continuation = [&](size_t i) {
        return (static_cast<unsigned char>(text[i]) & 0xC0) == 0x80;
      };
      while (from > 0 && continuation(from)) --from;  // whole UTF-8 characters only
      while (to < text.size() && continuation(to)) ++to;
      cut_left = from > 0;
      cut_right = to < text.size();
      text = text.substr(from, to - from);
      upto -= from;
    }
    if (!text.empty()) {
      out << "  " << (cut_left ? "..." : "") << printable(text, true, std::string_view::npos)
          << (cut_right ? "..." : "") << "\n  " << (cut_left ? "   " : "");
      // One space (or the tab) per character the line above shows, so the caret lines up
      // under the offending one after non-ASCII text too (the column counts bytes).
      for (size_t i = 0; i < upto;) {
        out << (text[i] == '\t' ? '\t' : ' ');
        const size_t n = static_cast<unsigned char>(text[i]) < 0x80 ? 0 : utf8_length(text, i);
        i += n > 0 ? n : 1;
      }
      out << "^\n";
    }
  }
  return out.str();
}

std::string format_diagnostics(const Diagnostics& ds, std::string_view file_name,
                               std::string_view source) {
  std::string out;
  for (const Diagnostic& d : ds.items()) out += format_diagnostic(d, file_name, source);
  if (ds.truncated())
    out += std::string(file_name) + ": note: too many errors; " + ds.error_count_text() +
           " in all, only the first " + std::to_string(Diagnostics::kMaxErrors) + " shown\n";
  return out;
}

namespace {

// Optimal string alignment distance: Levenshtein plus adjacent transpositions, so the common
// typo "lihgt" is one edit from "light", not two.
size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<size_t> before(b.size() + 1), above(b.size() + 1), row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) above[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      row[j] = std::min({above[j] + 1, row[j - 1] + 1, above[j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        row[j] = std::min(row[j], before[j - 2] + 1);
    }
    std::swap(before, above);
    std::swap(above, row);
  }
  return above[b.size()];
}

}  // namespace

Where position_of_offset(std::string_view text, size_t offset) {
  Where w{1, 1, {}};
  size_t start = text.starts_with("\xEF\xBB\xBF") ? 3 : 0;  // a byte-order mark takes no column
  for (size_t i = start; i < offset && i < text.size(); ++i) {
    if (ends_line(text, i)) {
      ++w.line;
      w.column = 1;
    } else {
      ++w.column;
    }
  }
  return w;
}

std::string nearest_word(std::string_view word, std::span<const std::string_view> candidates) {
  if (word.size() > 64 || candidates.size() > kMaxHintCandidates) return {};
  std::string lower(word);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  std::string_view best;
  size_t best_distance = SIZE_MAX;
  for (std::string_view c : candidates) {
    size_t d = edit_distance(lower, c);
    if (d < best_distance) {
      best_distance = d;
      best = c;
    }
  }
  // A typo is a small share of the word: "radious" -> "radius", "plain" -> "plane", but "foo"
  // suggests nothing, and neither does a rewrite of a whole short name ("x" -> "m").
  size_t allowed = std::max<size_t>(1, (std::min(word.size(), best.size()) + 1) / 3);
  if (best.empty() || best_distance > allowed || best_distance >= best.size()) return {};
  return std::string(best);
}

}  // namespace rayfarm
