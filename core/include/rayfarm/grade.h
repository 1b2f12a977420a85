// Grading students' images against rayfarm's own renders of an assignment's scenes: the
// assignment file, the pass and credit rules, hints that name the likely mistake, and the
// result files of the grading platforms (docs/grading.md).
#pragma once

#include <algorithm>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "rayfarm/compare.h"
#include "rayfarm/diagnostic.h"
#include "rayfarm/image.h"
#include "rayfarm/load.h"
#include "rayfarm/options.h"

namespace rayfarm::grading {

// How a test's points follow from the comparison.
struct CreditRule {
  enum class Kind { all, linear, steps };
  Kind kind = Kind::all;   // all: full points when the test passes, none otherwise
  std::string metric;      // linear, steps: bad_fraction, mean_abs, rmse or max_abs
  double full = 0;         // linear: full points at or below this value of the metric
  double zero = 0;         //         none at or above this
  std::vector<std::pair<double, double>> steps;  // (metric at most, fraction of the points)
};

struct TestSpec {
  std::string name;
  std::string scene;  // as written: relative to the assignment file
  std::string image;  // the student's file name
  double points = 1;
  OptionSet options;  // the test's render options (after the assignment's)
  int threshold = 0;  // a channel difference up to this is no difference (levels)
  bool neighborhood = false;
  double max_bad_fraction = 0;  // the test passes with at most this fraction of bad pixels
  CreditRule credit;
  std::string visibility = "visible";  // visible, hidden, after_due_date, after_published
  std::string problem;                 // group (Autolab's problem names); default: the name
  Where where;                         // of the test in the assignment file
};

struct Assignment {
  std::string name;
  std::vector<TestSpec> tests;
};

// Reads an assignment (JSON). Problems are reported with their JSON path; nullopt on errors.
std::optional<Assignment> parse_assignment(std::string_view text, Diagnostics& diags);

// A scene as the grader read it.
struct SceneFiles {
  std::string path;  // as the assignment writes it
  std::string text;
  std::map<std::string, std::string> textures;  // by the path the scene writes
  std::shared_ptr<const LoadedScene> loaded;    // with diagnostics; `scene` set when valid
};

// A student's image, or why there is none.
struct StudentImage {
  std::optional<Image> image;
  std::string error;     // missing or unreadable: what and where
  std::string note;      // e.g. another file name used, or the program's exit status
  std::string log_tail;  // a program's output (--run), last part: output_tail's
};

// The names a student may have handed `image` in under instead: the same name with the other
// format's extension, in either case (".ppm" for ".png" and back). Both graders grade the
// first that exists, with a note saying so.
std::vector<std::string> other_image_names(const std::string& image);

// The end of a program's output as every report shows it: its last `bytes` at most, as text
// that any format, terminal or XML file takes (invalid UTF-8, a character cut in two, and
// control characters but tab and newline become U+FFFD).
std::string output_tail(std::string_view log, std::size_t bytes);

// Where grading gets its files and renders: the command line reads the disk and renders
// here; the server reads the request's parts and renders through its queue.
// A scene's text loaded and checked, its textures read through `textures` and kept by the
// path the scene writes. nullopt with the diagnostics (as `file_name:line:col: ...`) in `error`.
std::optional<SceneFiles> load_scene_files(const std::string& path, const std::string& text,
                                           const ResourceResolver& textures,
                                           const std::string& file_name, std::string* error);

// The content key of a test's reference (the scene must be loaded with LoadDetail::full).
std::string reference_key(const SceneFiles& scene, const RenderOptions& options);

class Backend {
 public:
  virtual ~Backend() = default;
  // The scene of a test, read (with its textures) and checked, e.g. by load_scene_files.
  // nullopt with `error`. grade() asks once per path.
  virtual std::optional<SceneFiles> scene(const std::string& path, std::string* error) = 0;
  virtual std::optional<Image> render(const SceneFiles& scene, const RenderOptions& options,
                                      std::string* error) = 0;
  virtual StudentImage student(const TestSpec& test, const SceneFiles* scene) = 0;
};

struct Hint {
  std::string code;
  std::string message;
};

struct TestResult {
  std::string name;
  std::string problem;
  std::string visibility;
  double score = 0;
  double max_score = 0;
  std::string status;  // passed, failed, error (the grader could not grade it: no reference)
  std::string message;  // one line: why it passed or failed
  std::optional<CompareResult> metrics;
  int threshold = 0;
  bool neighborhood = false;
  double max_bad_fraction = 0;
  std::vector<Hint> hints;
  std::optional<Image> reference, student, diff;
  std::string reference_key;     // content key of the reference render
  std::string reference_sha256;  // of its pixels (width, height, bytes)
  std::string student_note, log_tail;
  bool student_missing = false;  // no readable image
};

struct GradeResult {
  std::string assignment;
  std::vector<TestResult> tests;
  double score = 0;
  double max_score = 0;
  std::string error;  // the grader itself failed (e.g. the lock does not match): score 0

  // Of the points to be had; where none are, 1 when every test passed.
  double fraction() const {
    if (max_score > 0) return score / max_score;
    return !tests.empty() && std::all_of(tests.begin(), tests.end(),
                                         [](const TestResult& t) { return t.status == "passed"; })
               ? 1
               : 0;
  }
};

struct GradeSettings {
  RenderOptions base;  // before the scene's and the test's options (a server's default profile)
  bool hints = true;
  int threads = 0;  // for the per-pixel records of hints (0: all cores)
  // Called once every reference is had, before any student's image is asked for (a `--run`
  // program is run): the tests with their names and references' hashes and keys, or the
  // message of one that has none. A non-empty answer stops the grade there, as a grader
  // error saying it, with no tests (e.g. a lock the references do not match).
  std::function<std::string(const GradeResult& references)> check_references;
};

// Grades every test. A test whose reference cannot be had (its scene has errors, its
// options conflict) is the assignment's fault, not the student's: the whole result is then a
// grader error (set_grader_error), never a silent zero for that test.
GradeResult grade(const Assignment& assignment, Backend& backend, const GradeSettings& settings);

// Makes the result a grader error saying `why`: every score 0 (the total and each test's, so
// that no platform lists points the grade does not give); statuses and messages stay.
void set_grader_error(GradeResult& r, std::string why);

// The hints for one comparison (grade() calls it; exposed for tests and /compare).
// `record` renders nothing: `alternative` renders the test's scene with other options.
std::vector<Hint> find_hints(const Image& reference, const Image& student,
                             const TestSpec& test, const RenderOptions& options,
                             const Scene* scene,
                             const std::function<std::optional<Image>(const RenderOptions&)>&
                                 alternative,
                             int threads);

// Lock files: the content key and the pixels' hash of every reference, so that a new
// version of rayfarm cannot change grades silently.
nlohmann::json lock_json(const GradeResult& result);
// Empty when `result` has the references the lock names; else what changed, per test.
std::vector<std::string> check_lock(const GradeResult& result, const nlohmann::json& lock);
// The grader error of a lock file's text `lock`, named `name` in it: empty when `result` has
// the references the lock names. Each problem also goes to `problems`.
std::string lock_mismatch(const GradeResult& result, const std::string& lock,
                          const std::string& name, std::vector<std::string>* problems = nullptr);

enum class Format { gradescope, prairielearn, autolab, junit, json, html, md };
std::optional<Format> parse_format(std::string_view name);
std::string_view to_string(Format f);

// The platform's result file (Autolab: the whole standard output, the score line last).
std::string write_result(const GradeResult& result, Format format);

std::string sha256_of_image(const Image& image);

}  // namespace rayfarm::grading
