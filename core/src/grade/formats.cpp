// A grading result in each platform's file (docs/grading.md): Gradescope and PrairieLearn
// results.json, Autolab's score line, JUnit XML, rayfarm's JSON, an HTML report and Markdown.
// Output is deterministic: no times or dates, fixed number formats.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "rayfarm/grade.h"
#include "rayfarm/image_io.h"
#include "rayfarm/render.h"
#include "grade/numbers.h"
#include "util/utf8.h"

namespace rayfarm::grading {
namespace {

using Json = nlohmann::json;

// Grader output quotes file names and messages a student's files chose: bytes that are not
// UTF-8 become U+FFFD instead of an exception.
std::string text(const Json& j, int indent = -1) {
  return j.dump(indent, ' ', false, Json::error_handler_t::replace);
}

std::string fixed(double v, int digits = 4) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  std::string s = buf;
  // Trailing zeros say nothing: 2.5000 reads 2.5.
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  return s;
}

// Scores as JSON numbers without binary noise (0.30000000000000004).
Json score_number(double v) {
  const double r = std::round(v * 10000) / 10000;
  if (r == std::floor(r) && std::abs(r) < 1e15) return static_cast<long long>(r);
  return std::stod(fixed(r));
}

std::string base64(const std::vector<unsigned char>& data) {
  static const char* kAlphabet =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((data.size() + 2) / 3 * 4);
  for (size_t i = 0; i < data.size(); i += 3) {
    unsigned v = data[i] << 16;
    if (i + 1 < data.size()) v |= data[i + 1] << 8;
    if (i + 2 < data.size()) v |= data[i + 2];
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < data.size() ? kAlphabet[(v >> 6) & 63] : '=';
    out += i + 2 < data.size() ? kAlphabet[v & 63] : '=';
  }
  return out;
}

std::string data_url(const Image& image) {
  return "data:image/png;base64," + base64(encode_png(image));
}

// One pixel per factor x factor block: its top-left pixel, or for a difference map the
// brightest of the block, so that a single wrong pixel stays visible.
Image shrunk(const Image& in, int factor, bool brightest) {
  if (factor <= 1) return in;
  Image out(std::max(1, in.width / factor), std::max(1, in.height / factor));
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      std::uint8_t* o = out.row(y) + 3 * x;
      for (int by = 0; by < (brightest ? factor : 1); ++by)
        for (int bx = 0; bx < (brightest ? factor : 1); ++bx) {
          const int sx = std::min(x * factor + bx, in.width - 1);
          const int sy = std::min(y * factor + by, in.height - 1);
          const std::uint8_t* p = in.row(sy) + 3 * sx;
          for (int c = 0; c < 3; ++c) o[c] = std::max(o[c], p[c]);
        }
    }
  return out;
}

std::string escape_xml(const std::string& s) {
  std::string out;
  // XML 1.0 takes valid UTF-8 only, and no control characters but tab and newlines: a file
  // name or message with raw bytes would make the whole report unreadable.
  for (char c : printable_text(s)) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

// Text for Markdown that a platform renders (Gradescope's "md"): names and messages quote the
// student's file names, so '<' and '&' are entities and no tag of theirs reaches the page.
std::string md_text(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else out += c;
  }
  return out;
}

std::string md_cell(std::string s) {
  std::string out;
  for (char c : md_text(s)) {
    if (c == '|') out += "\\|";
    else if (c == '\n') out += ' ';
    else out += c;
  }
  return out;
}

std::string metrics_line(const TestResult& t) {
  if (!t.metrics) return "";
  const CompareResult& m = *t.metrics;
  return "differing pixels " + std::to_string(m.differing_pixels) + " (" +
         percent(m.differing_fraction) + "), mean difference " + num(m.mean_abs) + ", RMSE " +
         num(m.rmse) + ", largest " + std::to_string(m.max_abs) + ", PSNR " +
         (std::isinf(m.psnr) ? std::string("inf") : fixed(m.psnr, 2) + " dB");
}

// What a student reads for one test: the verdict, the hints, then the numbers.
std::string feedback(const TestResult& t, bool markdown) {
  const auto said = [&](const std::string& s) { return markdown ? md_text(s) : s; };
  std::string out = said(t.message) + "\n";
  if (!t.hints.empty()) {
    out += markdown ? "\n**Hints**\n\n" : "\nHints:\n";
    for (const Hint& h : t.hints) out += "- " + said(h.message) + " [" + h.code + "]\n";
  }
  if (t.metrics) out += "\n" + metrics_line(t) + "\n";
  if (!t.student_note.empty()) out += "\n" + said(t.student_note) + "\n";
  if (!t.log_tail.empty()) {
    // A fence longer than any run of backticks in the output: the output cannot close it
    // and go on as the grader's own Markdown.
    size_t longest = 0, run = 0;
    for (char c : t.log_tail) longest = std::max(longest, run = c == '`' ? run + 1 : 0);
    const std::string fence(std::max<size_t>(3, longest + 1), '`');
    out += markdown ? "\nYour program's output (the end):\n\n" + fence + "\n" + t.log_tail + "\n" +
                          fence + "\n"
                    : "\nYour program's output (the end):\n" + t.log_tail + "\n";
  }
  return out;
}

Json test_json(const TestResult& t) {
  Json j = {{"name", t.name},
            {"problem", t.problem},
            {"visibility", t.visibility},
            {"status", t.status},
            {"score", score_number(t.score)},
            {"max_score", score_number(t.max_score)},
            {"message", t.message},
            {"threshold", t.threshold},
            {"neighborhood", t.neighborhood},
            {"max_bad_fraction", t.max_bad_fraction}};
  Json hints = Json::array();
  for (const Hint& h : t.hints) hints.push_back({{"code", h.code}, {"message", h.message}});
  j["hints"] = hints;
  j["metrics"] = t.metrics ? compare_json(*t.metrics, {t.threshold, t.neighborhood}) : Json(nullptr);
  if (!t.reference_key.empty()) j["reference_key"] = t.reference_key;
  if (!t.reference_sha256.empty()) j["reference_sha256"] = t.reference_sha256;
  if (!t.student_note.empty()) j["note"] = t.student_note;
  if (!t.log_tail.empty()) j["log_tail"] = t.log_tail;
  return j;
}

// `with_points` false: no total, which would tell the scores of tests the students do not see.
std::string header_text(const GradeResult& r, bool with_points = true) {
  std::string out = r.assignment +
                    (with_points ? ": " + fixed(r.score) + " / " + fixed(r.max_score) + " points"
                                 : std::string()) +
                    " (rayfarm render version " + std::to_string(kRenderVersion) + ")\n";
  if (!r.error.empty()) out += "grader error: " + r.error + "\n";
  return out;
}

std::string gradescope(const GradeResult& r) {
  Json tests = Json::array();
  int number = 0;
  for (const TestResult& t : r.tests) {
    Json j = {{"number", std::to_string(++number)},
              {"name", t.name},
              {"score", score_number(t.score)},
              {"max_score", score_number(t.max_score)},
              {"status", t.status == "passed" ? "passed" : "failed"},
              {"output", feedback(t, true)},
              {"output_format", "md"},
              {"visibility", t.visibility}};
    Json extra = test_json(t);
    extra.erase("name");
    extra.erase("message");
    j["extra_data"] = extra;
    tests.push_back(j);
  }
  // Gradescope shows the top-level output to students whatever the tests' visibility.
  const bool all_visible = std::all_of(r.tests.begin(), r.tests.end(),
                                       [](const TestResult& t) { return t.visibility == "visible"; });
  Json out = {{"score", score_number(r.error.empty() ? r.score : 0)},
              {"output", header_text(r, all_visible)},
              {"output_format", "md"},
              {"tests", tests}};
  return text(out, 2) + "\n";
}

// PrairieLearn keeps results under 1 MB: images go on failed tests, shrunk to share what the
// text leaves (a program's output on 64 tests is some 150 KB of it).
std::string prairielearn(const GradeResult& r) {
  constexpr size_t kLimit = 1000 * 1000;
  constexpr size_t kImageBudget = 700 * 1024;
  constexpr size_t kImageWrapping = 256;  // an image list's labels, keys and indentation
  Json tests = Json::array();
  std::vector<std::string> format_errors;
  bool any_image = false;
  size_t failing = 0, text_size = 0;
  for (const TestResult& t : r.tests) {
    if (!t.student_missing) any_image = true;
    else format_errors.push_back(t.name + ": " + t.message);
    failing += t.status != "passed" && t.reference && t.student;
    Json j = {{"name", t.name},
              {"points", score_number(t.score)},
              {"max_points", score_number(t.max_score)},
              {"message", t.message},
              {"output", feedback(t, false)}};
    text_size += text(j, 2).size() + 64;  // (nested one level deeper in the file)
    tests.push_back(std::move(j));
  }
  text_size += text(header_text(r)).size() + 4096;
  for (const std::string& e : format_errors) text_size += text(e).size() + 8;
  const size_t room = kLimit > text_size + failing * kImageWrapping
                          ? kLimit - text_size - failing * kImageWrapping
                          : 0;
  const size_t per_test = failing ? std::min(kImageBudget, room) / failing : 0;
  for (size_t i = 0; i < r.tests.size(); ++i) {
    const TestResult& t = r.tests[i];
    if (t.status != "passed" && t.reference && t.student) {
      for (int factor = 1; factor <= 64; factor *= 2) {
        Json images = Json::array();
        size_t size = 0;
        auto add = [&](const char* label, const Image& im, bool brightest = false) {
          std::string url = data_url(shrunk(im, factor, brightest));
          size += url.size();
          images.push_back({{"label", label}, {"url", url}});
        };
        add("Reference", *t.reference);
        add("Yours", *t.student);
        if (t.diff) add("Difference", *t.diff, true);
        if (size <= per_test) {
          tests[i]["images"] = images;
          break;
        }
      }
    }
  }
  Json out = {{"gradable", r.error.empty() && any_image},
              {"score", score_number(r.error.empty() ? r.fraction() : 0)},
              {"message", header_text(r)},
              {"tests", tests}};
  if (!r.error.empty()) out["format_errors"] = Json::array({"grader error: " + r.error});
  else if (!any_image) out["format_errors"] = format_errors;
  return text(out, 2) + "\n";
}

// Text for people first, then the formatted feedback line, then the score line last.
std::string autolab(const GradeResult& r) {
  std::string out = header_text(r);
  Json scores = Json::object();
  Json stage = Json::object();
  for (const TestResult& t : r.tests) {
    out += "\n== " + t.name + ": " + fixed(t.score) + " / " + fixed(t.max_score) + " (" + t.status +
           ")\n" + feedback(t, false);
    const double before = scores.contains(t.problem) ? scores[t.problem].get<double>() : 0;
    scores[t.problem] = score_number(before + (r.error.empty() ? t.score : 0));
    Json s = {{"passed", t.status == "passed"}};
    if (!t.hints.empty()) s["hint"] = t.hints.front().message;
    stage[t.name] = s;
  }
  Json semantic = {{"_presentation", "semantic"}, {"stages", {"Images"}}, {"Images", stage}};
  Json result = {{"scores", scores},
                 {"scoreboard", {score_number(r.error.empty() ? r.score : 0), score_number(r.max_score)}}};
  return out + "\n" + text(semantic) + "\n" + text(result) + "\n";
}

std::string junit(const GradeResult& r) {
  int failures = 0, errors = 0;
  for (const TestResult& t : r.tests) {
    failures += t.status == "failed";
    errors += t.status == "error";
  }
  const std::string suite = escape_xml(r.assignment);
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites name=\"" + suite +
                    "\" tests=\"" + std::to_string(r.tests.size()) + "\" failures=\"" +
                    std::to_string(failures) + "\" errors=\"" + std::to_string(errors) + "\">\n";
  out += "  <testsuite name=\"" + suite + "\" tests=\"" + std::to_string(r.tests.size()) +
         "\" failures=\"" + std::to_string(failures) + "\" errors=\"" + std::to_string(errors) +
         "\" skipped=\"0\">\n";
  out += "    <properties>\n      <property name=\"score\" value=\"" + fixed(r.score) +
         "\"/>\n      <property name=\"max_score\" value=\"" + fixed(r.max_score) + "\"/>\n";
  if (!r.error.empty())
    out += "      <property name=\"grader_error\" value=\"" + escape_xml(r.error) + "\"/>\n";
  out += "    </properties>\n";
  for (const TestResult& t : r.tests) {
    out += "    <testcase classname=\"" + suite + "\" name=\"" + escape_xml(t.name) + "\">\n";
    if (t.status != "passed") {
      const char* tag = t.status == "error" ? "error" : "failure";
      out += "      <" + std::string(tag) + " message=\"" + escape_xml(t.message) + "\">" +
             escape_xml(feedback(t, false)) + "</" + tag + ">\n";
    }
    out += "      <system-out>" + escape_xml("score " + fixed(t.score) + " / " + fixed(t.max_score) +
                                             (t.metrics ? "; " + metrics_line(t) : "")) +
           "</system-out>\n    </testcase>\n";
  }
  return out + "  </testsuite>\n</testsuites>\n";
}

std::string json(const GradeResult& r) {
  Json tests = Json::array();
  for (const TestResult& t : r.tests) tests.push_back(test_json(t));
  Json out = {{"assignment", r.assignment},
              {"score", score_number(r.error.empty() ? r.score : 0)},
              {"max_score", score_number(r.max_score)},
              {"render_version", kRenderVersion},
              {"tests", tests}};
  if (!r.error.empty()) out["error"] = r.error;
  return text(out, 2) + "\n";
}

std::string html(const GradeResult& r) {
  std::string out =
      "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" +
      escape_xml(r.assignment) +
      "</title>\n<style>body{font:15px system-ui,sans-serif;margin:2em;color:#222}"
      "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:.5em;vertical-align:top}"
      "img{image-rendering:pixelated;max-width:320px}.passed{color:#176f2c}.failed,.error{color:#b00020}"
      "pre{white-space:pre-wrap;max-width:36em}</style></head><body>\n<h1>" +
      escape_xml(r.assignment) + "</h1>\n<p>Score: <b>" + fixed(r.error.empty() ? r.score : 0) +
      " / " + fixed(r.max_score) + "</b></p>\n";
  if (!r.error.empty()) out += "<p class=\"error\">Grader error: " + escape_xml(r.error) + "</p>\n";
  out += "<table><tr><th>Test</th><th>Reference</th><th>Yours</th><th>Difference</th><th>Score</th></tr>\n";
  for (const TestResult& t : r.tests) {
    auto cell = [&](const std::optional<Image>& im) {
      return im ? "<td><img alt=\"\" src=\"" + data_url(*im) + "\"></td>" : std::string("<td>-</td>");
    };
    out += "<tr><td><b>" + escape_xml(t.name) + "</b><pre>" + escape_xml(feedback(t, false)) +
           "</pre></td>" + cell(t.reference) + cell(t.student) + cell(t.diff) + "<td class=\"" +
           t.status + "\">" + fixed(t.score) + " / " + fixed(t.max_score) + "<br>" + t.status +
           "</td></tr>\n";
  }
  return out + "</table>\n</body></html>\n";
}

std::string markdown(const GradeResult& r) {
  std::string out = "# " + md_cell(r.assignment) + "\n\n**Score: " +
                    fixed(r.error.empty() ? r.score : 0) + " / " + fixed(r.max_score) + "**\n\n";
  if (!r.error.empty()) out += "Grader error: " + md_text(r.error) + "\n\n";
  out += "| test | score | status | result |\n|---|---:|---|---|\n";
  for (const TestResult& t : r.tests)
    out += "| " + md_cell(t.name) + " | " + fixed(t.score) + " / " + fixed(t.max_score) + " | " +
           t.status + " | " + md_cell(t.message) + " |\n";
  for (const TestResult& t : r.tests) {
    if (t.hints.empty() && t.log_tail.empty()) continue;
    out += "\n## " + md_cell(t.name) + "\n\n" + feedback(t, true);
  }
  return out;
}

}  // namespace

std::string output_tail(std::string_view log, std::size_t bytes) {
  std::string_view tail = log.size() > bytes ? log.substr(log.size() - bytes) : log;
  // A cut inside a character leaves continuation bytes first: not a character of its own.
  while (log.size() > bytes && !tail.empty() && (static_cast<unsigned char>(tail[0]) & 0xc0) == 0x80)
    tail.remove_prefix(1);
  return printable_text(tail);
}

std::optional<Format> parse_format(std::string_view name) {
  for (Format f : {Format::gradescope, Format::prairielearn, Format::autolab, Format::junit,
                   Format::json, Format::html, Format::md})
    if (to_string(f) == name) return f;
  return std::nullopt;
}

std::string_view to_string(Format f) {
  switch (f) {
    case Format::gradescope: return "gradescope";
    case Format::prairielearn: return "prairielearn";
    case Format::autolab: return "autolab";
    case Format::junit: return "junit";
    case Format::json: return "json";
    case Format::html: return "html";
    case Format::md: return "md";
  }
  return "json";
}

std::string write_result(const GradeResult& result, Format format) {
  switch (format) {
    case Format::gradescope: return gradescope(result);
    case Format::prairielearn: return prairielearn(result);
    // The two plain-text reports quote file names of the student's folder, which may be any
    // bytes: a report must be UTF-8 throughout (the JSON and XML writers see to their own).
    case Format::autolab: return printable_text(autolab(result));
    case Format::junit: return junit(result);
    case Format::json: return json(result);
    case Format::html: return html(result);
    case Format::md: return printable_text(markdown(result));
  }
  return json(result);
}

}  // namespace rayfarm::grading
