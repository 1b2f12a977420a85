// Grading one assignment: each test's reference rendered by the backend, the student's image
// compared with the test's rules, points from its credit rule, and hints (hints.cpp).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include "rayfarm/grade.h"
#include "rayfarm/content_key.h"
#include "rayfarm/render.h"
#include "rayfarm/sha256.h"
#include "grade/numbers.h"

namespace rayfarm::grading {
namespace {

double metric_value(const CompareResult& m, const std::string& metric) {
  if (metric == "mean_abs") return m.mean_abs;
  if (metric == "rmse") return m.rmse;
  if (metric == "max_abs") return m.max_abs;
  return m.differing_fraction;
}

// The fraction of the points the credit rule gives.
double credit_fraction(const TestSpec& t, const CompareResult& m, bool passed) {
  const CreditRule& c = t.credit;
  if (c.kind == CreditRule::Kind::all) return passed ? 1 : 0;
  const double v = metric_value(m, c.metric);
  if (c.kind == CreditRule::Kind::linear) {
    if (v <= c.full) return 1;
    if (v >= c.zero) return 0;
    return (c.zero - v) / (c.zero - c.full);
  }
  for (const auto& [limit, fraction] : c.steps)
    if (v <= limit) return fraction;
  return 0;
}


}  // namespace

std::optional<SceneFiles> load_scene_files(const std::string& path, const std::string& text,
                                           const ResourceResolver& textures,
                                           const std::string& file_name, std::string* error) {
  const RecordingResolver recording(textures);  // the files belong to its content key
  auto loaded = std::make_shared<LoadedScene>(load_scene(text, LoadDetail::full, &recording));
  if (loaded->diags.has_errors() || !loaded->scene) {
    *error = format_diagnostics(loaded->diags, file_name, text);
    while (!error->empty() && error->back() == '\n') error->pop_back();
    return std::nullopt;
  }
  return SceneFiles{path, text, recording.files(), std::move(loaded)};
}

std::vector<std::string> other_image_names(const std::string& image) {
  const size_t slash = image.find_last_of("/\\");
  const size_t dot = image.rfind('.');
  const std::string stem =
      dot != std::string::npos && (slash == std::string::npos || dot > slash + 1) ? image.substr(0, dot)
                                                                                 : image;
  std::vector<std::string> out;
  for (const char* ext : {".ppm", ".png", ".PPM", ".PNG"})
    if (stem + ext != image) out.push_back(stem + ext);
  return out;
}

std::string reference_key(const SceneFiles& scene, const RenderOptions& options) {
  return content_key(scene.loaded->desc, options, texture_hashes(*scene.loaded->scene, scene.textures));
}

std::string sha256_of_image(const Image& image) {
  std::string bytes = std::to_string(image.width) + "x" + std::to_string(image.height) + "\n";
  bytes.append(reinterpret_cast<const char*>(image.rgb.data()), image.rgb.size());
  return sha256_hex(bytes);
}

void set_grader_error(GradeResult& r, std::string why) {
  r.error = std::move(why);
  r.score = 0;
  for (TestResult& t : r.tests) t.score = 0;
}

GradeResult grade(const Assignment& assignment, Backend& backend, const GradeSettings& settings) {
  GradeResult out;
  out.assignment = assignment.name;
  std::map<std::string, std::optional<SceneFiles>> scenes;  // tests often share a scene
  std::map<std::string, std::string> scene_errors;
  // Every reference before any student's image: a student's program (`--run`) runs as the
  // grader does, and must not change a reference this grade has yet to read (a cached one).
  struct Reference {
    RenderOptions options;
    std::optional<Image> image;
    std::string sha256, key;  // of the image, and of what it was rendered from
    std::string error;        // why there is none
  };
  std::vector<Reference> references;
  for (const TestSpec& t : assignment.tests) {
    Reference& ref = references.emplace_back();
    if (!scenes.count(t.scene)) scenes[t.scene] = backend.scene(t.scene, &scene_errors[t.scene]);
    const std::optional<SceneFiles>& scene = scenes[t.scene];
    if (!scene) {
      ref.error = "the reference could not be rendered: " + scene_errors[t.scene];
      continue;
    }
    ref.options = settings.base;
    Diagnostics diags;
    apply_options(ref.options, scene->loaded->scene->render, diags);
    apply_options(ref.options, t.options, diags);
    if (diags.has_errors()) {
      ref.error = "the test's options: " + diags.first_error()->message;
      continue;
    }
    if (std::string conflict = profile_conflict(ref.options); !conflict.empty()) {
      ref.error = "the test's options: " + conflict;
      continue;
    }
    std::string error;
    ref.image = backend.render(*scene, ref.options, &error);
    if (!ref.image) {
      ref.error = "the reference could not be rendered: " + error;
      continue;
    }
    ref.sha256 = sha256_of_image(*ref.image);
    ref.key = reference_key(*scene, ref.options);
  }
  if (settings.check_references) {
    GradeResult had;
    had.assignment = assignment.name;
    for (std::size_t k = 0; k < assignment.tests.size(); ++k) {
      TestResult& r = had.tests.emplace_back();
      r.name = assignment.tests[k].name;
      if (!references[k].image) {
        r.status = "error";
        r.message = references[k].error;
        continue;
      }
      r.reference_sha256 = references[k].sha256;
      r.reference_key = references[k].key;
    }
    if (std::string why = settings.check_references(had); !why.empty()) {
      for (const TestSpec& t : assignment.tests) out.max_score += t.points;
      set_grader_error(out, why);
      return out;
    }
  }
  for (std::size_t k = 0; k < assignment.tests.size(); ++k) {
    const TestSpec& t = assignment.tests[k];
    TestResult r;
    r.name = t.name;
    r.problem = t.problem;
    r.visibility = t.visibility;
    r.max_score = t.points;
    r.threshold = t.threshold;
    r.neighborhood = t.neighborhood;
    r.max_bad_fraction = t.max_bad_fraction;
    out.max_score += t.points;
    auto fail = [&](std::string status, std::string message) {
      r.status = std::move(status);
      r.message = std::move(message);
      out.tests.push_back(std::move(r));
    };

    std::string error;
    std::optional<Image>& reference = references[k].image;
    if (!reference) {
      fail("error", references[k].error);
      continue;
    }
    const std::optional<SceneFiles>& scene = scenes[t.scene];
    const RenderOptions& options = references[k].options;
    r.reference_sha256 = references[k].sha256;
    r.reference_key = references[k].key;

    StudentImage student = backend.student(t, &*scene);
    r.student_note = student.note;
    r.log_tail = student.log_tail;
    r.reference = reference;
    if (!student.image) {
      r.student_missing = true;
      r.hints.push_back({"missing_image", student.error});
      fail("failed", student.error);
      continue;
    }
    r.student = student.image;
    const Image& ref = *reference;
    const Image& mine = *student.image;
    if (mine.width != ref.width || mine.height != ref.height) {
      std::string message = "your image is " + std::to_string(mine.width) + "x" +
                            std::to_string(mine.height) + ", the reference is " +
                            std::to_string(ref.width) + "x" + std::to_string(ref.height);
      if (mine.width == ref.height && mine.height == ref.width)
        message += ": width and height are swapped (pixeldim gives columns, then rows)";
      else
        message += ": the image size is the camera's pixeldim (columns, then rows)";
      r.hints.push_back({"wrong_size", message});
      // Kept for the report when about the reference's size; a far larger one (a 49 KB PNG
      // can hold 4096x4096) is not held for the rest of the grading.
      const long long theirs = static_cast<long long>(mine.width) * mine.height;
      if (theirs > std::max<long long>(4LL * ref.width * ref.height, 1LL << 20)) r.student.reset();
      fail("failed", message);
      continue;
    }
    CompareOptions copts{t.threshold, t.neighborhood};
    std::optional<CompareResult> m = compare_images(ref, mine, copts, &error);
    if (!m) {
      fail("error", error);
      continue;
    }
    r.metrics = m;
    const bool all_or_nothing = t.credit.kind == CreditRule::Kind::all;
    const bool passed = m->differing_fraction <= t.max_bad_fraction;
    const double credit = credit_fraction(t, *m, passed);
    // Scores to 1/10000 of a point, as the points are (0.1 + 0.2 must sum as a platform shows
    // it). With a scale of credit the test passes when it earns its full points.
    r.score = std::round(t.points * credit * 10000) / 10000;
    // Full points as shown: a credit a hair under 1 that rounds to them is a pass (a test of
    // no points passes on its full credit alone).
    const bool full = credit >= 1 || (t.points > 0 && r.score >= t.points);
    r.status = (all_or_nothing ? passed : full) ? "passed" : "failed";
    if (m->max_abs == 0) {
      r.message = "identical to the reference";
    } else {
      const long long pixels = static_cast<long long>(ref.width) * ref.height;
      // The limit as the student can weigh it: in pixels when the two percentages print
      // alike (98.43% against up to 98.43%, and failed).
      std::string limit = percent(t.max_bad_fraction);
      if (limit == percent(m->differing_fraction))
        limit = std::to_string(static_cast<long long>(
                    std::floor(t.max_bad_fraction * static_cast<double>(pixels)))) +
                " pixels";
      r.message = std::to_string(m->differing_pixels) + " of " + std::to_string(pixels) +
                  " pixels differ by more than " + std::to_string(t.threshold) +
                  (t.threshold == 1 ? " level" : " levels") +
                  (t.neighborhood ? " (3x3 neighbourhood)" : "") + " (" +
                  percent(m->differing_fraction) +
                  (!all_or_nothing            ? ""
                   : t.max_bad_fraction > 0 ? "; up to " + limit + " may"
                                            : "; none may") +
                  "); mean difference " + num(m->mean_abs) + ", largest " +
                  std::to_string(m->max_abs);
      r.diff = diff_image(ref, mine, copts);
      if (settings.hints) {
        const Scene* sc = scene->loaded->scene ? &*scene->loaded->scene : nullptr;
        Backend& b = backend;
        const SceneFiles& files = *scene;
        r.hints = find_hints(
            ref, mine, t, options, sc,
            [&](const RenderOptions& o) {
              std::string e;
              return b.render(files, o, &e);
            },
            settings.threads);
      }
    }
    out.score += r.score;
    out.tests.push_back(std::move(r));
  }
  out.score = std::round(out.score * 10000) / 10000;
  out.max_score = std::round(out.max_score * 10000) / 10000;
  for (const TestResult& t : out.tests)
    if (t.status == "error") {
      set_grader_error(out, "test '" + t.name + "': " + t.message);
      break;
    }
  return out;
}

nlohmann::json lock_json(const GradeResult& result) {
  nlohmann::json tests = nlohmann::json::object();
  for (const TestResult& t : result.tests)
    if (!t.reference_sha256.empty())
      tests[t.name] = {{"reference_key", t.reference_key}, {"reference_sha256", t.reference_sha256}};
  return {{"assignment", result.assignment},
          {"render_version", kRenderVersion},
          {"tests", tests}};
}

std::string lock_mismatch(const GradeResult& result, const std::string& lock,
                          const std::string& name, std::vector<std::string>* problems) {
  const nlohmann::json doc = nlohmann::json::parse(lock, nullptr, false);
  const std::vector<std::string> found =
      doc.is_discarded() ? std::vector<std::string>{"the lock file is not JSON"}
                         : check_lock(result, doc);
  if (problems) *problems = found;
  if (found.empty()) return "";
  return "the references are not the ones in " + name + ": " + found.front() +
         (found.size() > 1 ? " (and " + std::to_string(found.size() - 1) + " more)" : "");
}

std::vector<std::string> check_lock(const GradeResult& result, const nlohmann::json& lock) {
  std::vector<std::string> problems;
  if (!lock.is_object() || !lock.contains("tests") || !lock["tests"].is_object())
    return {"the lock file is not a rayfarm lock (no \"tests\" object)"};
  const nlohmann::json& tests = lock["tests"];
  for (const TestResult& t : result.tests) {
    if (!tests.contains(t.name)) {
      problems.push_back("test '" + t.name + "' is not in the lock: freeze the assignment again");
      continue;
    }
    const nlohmann::json& l = tests[t.name];
    // A lock edited by hand may hold anything: what is not a string matches nothing.
    auto text = [&](const char* key) {
      return l.is_object() && l.contains(key) && l[key].is_string() ? l[key].get<std::string>()
                                                                    : std::string();
    };
    const std::string want = text("reference_sha256");
    if (!l.is_object() || !l.contains("reference_sha256") || !l["reference_sha256"].is_string())
      problems.push_back("test '" + t.name + "': the lock's entry has no reference_sha256 string");
    else if (t.reference_sha256.empty())
      problems.push_back("test '" + t.name + "': no reference to check (" + t.message + ")");
    else if (t.reference_sha256 != want)
      problems.push_back("test '" + t.name + "': the reference image is not the locked one (" +
                         (text("reference_key") == t.reference_key
                              ? std::string("same scene and options, another rendering")
                              : std::string("the scene, its options or rayfarm changed")) +
                         ")");
  }
  for (auto it = tests.begin(); it != tests.end(); ++it) {
    bool present = std::any_of(result.tests.begin(), result.tests.end(),
                               [&](const TestResult& t) { return t.name == it.key(); });
    if (!present) problems.push_back("the lock names test '" + it.key() + "', which the assignment no longer has");
  }
  return problems;
}

}  // namespace rayfarm::grading
