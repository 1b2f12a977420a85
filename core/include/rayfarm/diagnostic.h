// Structured errors and warnings about scene input: what went wrong and where.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace rayfarm {

// Where a piece of input came from: line/column (1-based, 0 = unknown) for model files and
// JSON syntax errors, a JSON pointer ("/objects/2/radius") for JSON values.
struct Where {
  int line = 0;
  int column = 0;
  std::string path;

  bool operator==(const Where&) const = default;
};

enum class Severity { error, warning };

struct Diagnostic {
  Severity severity = Severity::error;
  std::string code;     // stable, machine-readable: "unknown-attribute", "missing-attribute", ...
  std::string message;  // one line, includes any suggestion
  Where where;
};

// Collects diagnostics up to a cap, so a garbage file cannot produce megabytes of errors.
// Puts `ds` in the order of `place` (one per item, in ds's order), ties as they were.
void sort_by_place(std::vector<Diagnostic>& ds, const std::vector<size_t>& place);

class Diagnostics {
 public:
  static constexpr size_t kMaxErrors = 50;

  void error(std::string code, std::string message, Where where);
  void warning(std::string code, std::string message, Where where);

  bool has_errors() const { return errors_ > 0; }
  size_t error_count() const { return errors_; }
  bool truncated() const { return truncated_; }
  const std::vector<Diagnostic>& items() const { return items_; }
  const Diagnostic* first_error() const;
  // sort_by_place on the items.
  void reorder(const std::vector<size_t>& place);

  // A reader that stops once past the cap (the model parser: a garbage file is not worth
  // reading to its end) says so: error_count() is then a lower bound.
  void reading_stopped() { counted_all_ = false; }
  bool counted_all() const { return counted_all_; }
  // "12", or "more than 50" when reading stopped.
  std::string error_count_text() const;

 private:
  std::vector<Diagnostic> items_;
  size_t errors_ = 0;
  bool truncated_ = false;
  bool counted_all_ = true;
};

// "FILE:LINE:COL: error: MESSAGE", then the source line and a caret under the column.
// JSON-path diagnostics print as "FILE: error: at /path: MESSAGE".
std::string format_diagnostic(const Diagnostic& d, std::string_view file_name,
                              std::string_view source);
std::string format_diagnostics(const Diagnostics& ds, std::string_view file_name,
                               std::string_view source);

// The line and column (1-based) of a byte offset into a text; a byte-order mark takes no column.
Where position_of_offset(std::string_view text, size_t offset);

// The candidate closest to `word` by edit distance, or empty when none is close enough
// to be a plausible typo. Empty too past kMaxHintCandidates candidates: a file of many
// names, each referenced wrongly, must not cost a time quadratic in its size.
inline constexpr size_t kMaxHintCandidates = 1000;
std::string nearest_word(std::string_view word, std::span<const std::string_view> candidates);

}  // namespace rayfarm
