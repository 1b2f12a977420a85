// The assignment file (docs/grading.md): what to render, which student file to compare, and
// how points follow. Every problem is reported with its JSON path, like scene errors.
#include <algorithm>
#include <array>
#include <cmath>
#include <set>

#include "format/json_tree.h"
#include "rayfarm/grade.h"

namespace rayfarm::grading {
namespace {

using Json = nlohmann::ordered_json;

constexpr std::array<std::string_view, 9> kTopKeys = {
    "name", "profile", "options", "tests", "threshold", "neighborhood", "max_bad_fraction",
    "credit", "visibility"};
constexpr std::array<std::string_view, 11> kTestKeys = {
    "name", "scene", "image", "points", "options", "threshold", "neighborhood",
    "max_bad_fraction", "credit", "visibility", "problem"};
constexpr std::array<std::string_view, 4> kVisibility = {"visible", "hidden", "after_due_date",
                                                         "after_published"};
constexpr std::array<std::string_view, 4> kMetrics = {"bad_fraction", "mean_abs", "rmse",
                                                      "max_abs"};

template <size_t N>
std::string one_of(const std::array<std::string_view, N>& words) {
  std::string out;
  for (size_t i = 0; i < N; ++i) out += (i ? (i + 1 == N ? " or " : ", ") : "") + std::string(words[i]);
  return out;
}

class Reader {
 public:
  explicit Reader(Diagnostics& diags) : diags_(diags) {}

  void error(const std::string& path, std::string message) {
    diags_.error("bad-assignment", std::move(message), Where{0, 0, path});
  }

  template <size_t N>
  void known_keys(const Json& object, const std::string& path,
                  const std::array<std::string_view, N>& keys) {
    for (auto it = object.begin(); it != object.end(); ++it) {
      if (std::find(keys.begin(), keys.end(), it.key()) != keys.end()) continue;
      std::string near = nearest_word(it.key(), keys);
      error(path + "/" + it.key(), "unknown key '" + it.key() + "'" +
                                       (near.empty() ? "" : "; did you mean '" + near + "'?"));
    }
  }

  std::optional<std::string> string(const Json& v, const std::string& path) {
    if (!v.is_string() || v.get<std::string>().empty()) {
      error(path, "must be a non-empty string");
      return std::nullopt;
    }
    return v.get<std::string>();
  }

  std::optional<double> number(const Json& v, const std::string& path, double lo, double hi) {
    if (!v.is_number() || !std::isfinite(v.get<double>()) || v.get<double>() < lo ||
        v.get<double>() > hi) {
      error(path, "must be a number in " + format_number(lo) + ".." + format_number(hi));
      return std::nullopt;
    }
    return v.get<double>();
  }

  void options(const Json& v, const std::string& path, OptionSet& out) {
    if (!v.is_object()) return error(path, "must be an object of render options");
    for (auto it = v.begin(); it != v.end(); ++it) {
      const std::string at = path + "/" + it.key();
      std::string text;
      if (it->is_string()) text = it->get<std::string>();
      else if (it->is_boolean()) text = it->get<bool>() ? "1" : "0";
      else if (it->is_number()) text = json_number_text(*it);
      else if (it->is_array()) {  // a colour
        for (const Json& e : *it) text += (text.empty() ? "" : ",") + (e.is_number() ? format_number(e.get<double>()) : std::string("?"));
      } else {
        error(at, "must be a string, number or boolean");
        continue;
      }
      RenderOptions probe;
      if (auto bad = apply_option(probe, it.key(), text)) {
        error(at, *bad);
        continue;
      }
      out.push_back({it.key(), text, Where{0, 0, at}});
    }
  }

  void credit(const Json& v, const std::string& path, CreditRule& out) {
    if (v.is_string()) {
      if (v.get<std::string>() != "all") error(path, "must be \"all\", {\"linear\": ...} or {\"steps\": ...}");
      out = CreditRule{};
      return;
    }
    if (!v.is_object() || (v.contains("linear") == v.contains("steps")))
      return error(path, "must be \"all\", {\"linear\": {...}} or {\"steps\": [...]}");
    auto metric = [&](const Json& holder, const std::string& at, const char* fallback) {
      if (!holder.contains("metric")) return std::string(fallback);
      const Json& m = holder["metric"];
      if (!m.is_string() ||
          std::find(kMetrics.begin(), kMetrics.end(), m.get<std::string>()) == kMetrics.end()) {
        error(at + "/metric", "must be " + one_of(kMetrics));
        return std::string(fallback);
      }
      return m.get<std::string>();
    };
    if (v.contains("linear")) {
      const Json& l = v["linear"];
      const std::string at = path + "/linear";
      if (!l.is_object()) return error(at, "must be {\"metric\": ..., \"full\": ..., \"zero\": ...}");
      for (auto it = l.begin(); it != l.end(); ++it)
        if (it.key() != "metric" && it.key() != "full" && it.key() != "zero")
          error(at + "/" + it.key(), "unknown key '" + it.key() + "' (metric, full, zero)");
      out.kind = CreditRule::Kind::linear;
      out.metric = metric(l, at, "mean_abs");
      if (!l.contains("full") || !l.contains("zero"))
        return error(at, "needs \"full\" (the metric's value for full points) and \"zero\" (for none)");
      auto full = number(l["full"], at + "/full", 0, 1e9);
      auto zero = number(l["zero"], at + "/zero", 0, 1e9);
      if (full && zero && !(*zero > *full)) error(at + "/zero", "must be more than \"full\"");
      out.full = full.value_or(0);
      out.zero = zero.value_or(1);
      return;
    }
    const std::string at = path + "/steps";
    const Json& s = v["steps"];
    out.kind = CreditRule::Kind::steps;
    out.metric = metric(v, path, "bad_fraction");
    for (auto it = v.begin(); it != v.end(); ++it)
      if (it.key() != "metric" && it.key() != "steps")
        error(path + "/" + it.key(), "unknown key '" + it.key() + "' (steps, metric)");
    if (!s.is_array() || s.empty())
      return error(at, "must be a list of [metric at most, fraction of the points]");
    for (size_t i = 0; i < s.size(); ++i) {
      const std::string ai = at + "/" + std::to_string(i);
      if (!s[i].is_array() || s[i].size() != 2) {
        error(ai, "must be [metric at most, fraction of the points]");
        continue;
      }
      auto limit = number(s[i][0], ai + "/0", 0, 1e9);
      auto fraction = number(s[i][1], ai + "/1", 0, 1);
      if (limit && fraction) {
        if (!out.steps.empty() && !(*limit > out.steps.back().first))
          error(ai + "/0", "steps must rise: each limit more than the one before");
        out.steps.emplace_back(*limit, *fraction);
      }
    }
  }

  // The fields a test and the assignment share (the assignment's are the tests' defaults).
  void shared(const Json& o, const std::string& path, TestSpec& t) {
    if (o.contains("threshold"))
      t.threshold = static_cast<int>(number(o["threshold"], path + "/threshold", 0, 255).value_or(0));
    if (o.contains("threshold") && o["threshold"].is_number() && !o["threshold"].is_number_integer())
      error(path + "/threshold", "must be a whole number of levels");
    if (o.contains("neighborhood")) {
      const Json& n = o["neighborhood"];
      if (n.is_boolean()) t.neighborhood = n.get<bool>();
      else if (n.is_number_integer() && (n == 0 || n == 1)) t.neighborhood = n == 1;
      else error(path + "/neighborhood", "must be 0 or 1 (or false or true)");
    }
    if (o.contains("max_bad_fraction"))
      t.max_bad_fraction = number(o["max_bad_fraction"], path + "/max_bad_fraction", 0, 1).value_or(0);
    if (o.contains("credit")) credit(o["credit"], path + "/credit", t.credit);
    if (o.contains("visibility")) {
      const Json& v = o["visibility"];
      if (!v.is_string() ||
          std::find(kVisibility.begin(), kVisibility.end(), v.get<std::string>()) == kVisibility.end())
        error(path + "/visibility", "must be " + one_of(kVisibility));
      else
        t.visibility = v.get<std::string>();
    }
    if (o.contains("options")) options(o["options"], path + "/options", t.options);
  }

  // A file name inside the student's folder: relative, without "..".
  bool plain_relative(const std::string& name) {
    if (name.empty() || name.front() == '/' || name.find('\\') != std::string::npos) return false;
    size_t start = 0;
    while (start <= name.size()) {
      size_t end = name.find('/', start);
      if (end == std::string::npos) end = name.size();
      std::string_view part(name.data() + start, end - start);
      if (part.empty() || part == "." || part == "..") return false;
      start = end + 1;
    }
    return true;
  }

 private:
  Diagnostics& diags_;
};

std::string stem_of(const std::string& path) {
  size_t slash = path.find_last_of('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  size_t dot = name.find_last_of('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

}  // namespace

std::optional<Assignment> parse_assignment(std::string_view text, Diagnostics& diags) {
  // Read as scenes are: a key given twice is an error at its path, not the last one winning.
  std::optional<Json> parsed = parse_json_tree(text, diags);
  if (!parsed) return std::nullopt;
  Json& root = *parsed;
  Reader r(diags);
  if (!root.is_object()) {
    r.error("", "an assignment is a JSON object with \"name\" and \"tests\"");
    return std::nullopt;
  }
  r.known_keys(root, "", kTopKeys);
  Assignment a;
  if (!root.contains("name")) r.error("/name", "missing: the assignment's name");
  else a.name = r.string(root["name"], "/name").value_or("");
  TestSpec defaults;
  if (root.contains("profile")) {
    RenderOptions probe;
    if (!root["profile"].is_string()) {
      r.error("/profile", "must be \"lecture\" or \"cpsc102\"");
    } else if (auto bad = apply_option(probe, "profile", root["profile"].get<std::string>())) {
      r.error("/profile", *bad);
    } else {
      defaults.options.push_back({"profile", root["profile"].get<std::string>(), Where{0, 0, "/profile"}});
    }
  }
  r.shared(root, "", defaults);
  if (!root.contains("tests") || !root["tests"].is_array() || root["tests"].empty()) {
    r.error("/tests", "must be a non-empty list of tests");
    return std::nullopt;
  }
  std::set<std::string> names;
  const Json& tests = root["tests"];
  for (size_t i = 0; i < tests.size(); ++i) {
    const std::string path = "/tests/" + std::to_string(i);
    const Json& o = tests[i];
    if (!o.is_object()) {
      r.error(path, "a test is an object with \"name\", \"scene\" and \"image\"");
      continue;
    }
    r.known_keys(o, path, kTestKeys);
    TestSpec t = defaults;
    t.options = defaults.options;
    t.where = Where{0, 0, path};
    if (!o.contains("name")) r.error(path + "/name", "missing: the test's name");
    else t.name = r.string(o["name"], path + "/name").value_or("");
    if (!t.name.empty() && !names.insert(t.name).second)
      r.error(path + "/name", "another test is named '" + t.name + "'");
    if (!o.contains("scene")) r.error(path + "/scene", "missing: the scene file, relative to the assignment");
    else t.scene = r.string(o["scene"], path + "/scene").value_or("");
    if (o.contains("image")) {
      t.image = r.string(o["image"], path + "/image").value_or("");
      if (!t.image.empty() && !r.plain_relative(t.image))
        r.error(path + "/image", "must be a file name relative to the student's folder, without '..'");
    } else if (!t.scene.empty()) {
      t.image = stem_of(t.scene) + ".ppm";
    }
    // Kept to 1/10000 of a point, as scores are: full marks are then the points exactly.
    if (o.contains("points"))
      t.points = std::round(r.number(o["points"], path + "/points", 0, 1e6).value_or(0) * 10000) / 10000;
    if (o.contains("problem")) t.problem = r.string(o["problem"], path + "/problem").value_or("");
    if (t.problem.empty()) t.problem = t.name;
    TestSpec scratch = t;
    scratch.options.clear();
    r.shared(o, path, scratch);
    t.threshold = scratch.threshold;
    t.neighborhood = scratch.neighborhood;
    t.max_bad_fraction = scratch.max_bad_fraction;
    t.credit = scratch.credit;
    t.visibility = scratch.visibility;
    t.options.insert(t.options.end(), scratch.options.begin(), scratch.options.end());
    a.tests.push_back(std::move(t));
  }
  if (diags.has_errors()) return std::nullopt;
  return a;
}

}  // namespace rayfarm::grading
