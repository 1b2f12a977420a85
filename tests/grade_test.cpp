// Grading (rayfarm/grade.h): the assignment file and its errors, the pass and credit rules,
// each hint built from the mistake it names (the student's image is rayfarm's render with
// that mistake made: another rounding, no shadow test, rows written bottom first, ...), the
// platforms' result files and the lock.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <regex>

#include "rayfarm/grade.h"
#include "rayfarm/image_io.h"
#include "rayfarm/render.h"
#include "test_util.h"
#include "util/utf8.h"

namespace rayfarm::grading {
namespace {

using Json = nlohmann::json;

// A small course scene: a floor, a glinting red sphere, a mirror sphere, one light.
const char* kScene = R"(camera c
{ pixeldim 64 48
  worlddim 8 6
  viewpoint 4 3 6 }
material floor
{ ambient 1 1 1
  diffuse .7 .7 .7 }
material red
{ ambient 2 .5 .5
  diffuse .8 .2 .2
  specular .4 .4 .4
  shininess 20 }
material mirror
{ ambient .2 .2 .2
  diffuse .1 .1 .1
  specular .8 .8 .8 }
light l
{ location 1 6 4
  emissivity 6 6 6 }
plane ground
{ material floor
  normal 0 1 0
  point 0 0 0 }
sphere ball
{ material red
  center 3 1 -3
  radius 1 }
sphere glass
{ material mirror
  center 5.5 1.2 -4
  radius 1.2 }
)";

class FakeBackend final : public Backend {
 public:
  std::map<std::string, std::string> scenes;
  std::map<std::string, Image> images;
  std::map<std::string, std::string> unreadable;
  int renders = 0;

  std::optional<SceneFiles> scene(const std::string& path, std::string* error) override {
    auto it = scenes.find(path);
    if (it == scenes.end()) {
      *error = "no scene " + path;
      return std::nullopt;
    }
    auto loaded = std::make_shared<LoadedScene>(load_scene(it->second, LoadDetail::full));
    if (!loaded->scene) {
      *error = loaded->diags.first_error()->message;
      return std::nullopt;
    }
    return SceneFiles{path, it->second, {}, loaded};
  }
  std::optional<Image> render(const SceneFiles& s, const RenderOptions& o, std::string* error) override {
    ++renders;
    Image image = render_image(*s.loaded->scene, o, 2, nullptr, {}, nullptr, error);
    if (image.width == 0) return std::nullopt;
    return image;
  }
  StudentImage student(const TestSpec& t, const SceneFiles*) override {
    StudentImage s;
    if (auto it = unreadable.find(t.image); it != unreadable.end()) {
      std::string error;
      s.image = decode_image(it->second, &error);
      s.error = "your image " + t.image + " cannot be read: " + error;
      return s;
    }
    auto it = images.find(t.image);
    if (it == images.end()) s.error = "your image " + t.image + " was not found";
    else s.image = it->second;
    return s;
  }
};

Assignment parse_ok(const std::string& text) {
  Diagnostics diags;
  auto a = parse_assignment(text, diags);
  EXPECT_TRUE(a) << (diags.first_error() ? diags.first_error()->message : "");
  return a ? *a : Assignment{};
}

// The first error of an assignment that must not parse: "PATH: MESSAGE".
std::string first_error(const std::string& text) {
  Diagnostics diags;
  EXPECT_FALSE(parse_assignment(text, diags));
  const Diagnostic* d = diags.first_error();
  if (!d) return "";
  if (d->where.line) return std::to_string(d->where.line) + ":" + std::to_string(d->where.column) + ": " + d->message;
  return d->where.path + ": " + d->message;
}

Image render_with(const std::string& text, std::vector<std::pair<std::string, std::string>> options) {
  Scene scene = test::scene_from(text);
  RenderOptions o;
  for (auto& [k, v] : options) EXPECT_FALSE(apply_option(o, k, v)) << k;
  return render_image(scene, o, 2);
}

// Grades one test of kScene with the student's image made by `student`.
TestResult grade_one(const Image& student, const std::string& test_fields = "",
                     const std::string& profile = "cpsc102", std::string scene = kScene) {
  FakeBackend b;
  b.scenes["lab.txt"] = scene;
  b.images["lab.ppm"] = student;
  Assignment a = parse_ok(R"({"name": "Lab", "profile": ")" + profile +
                          R"(", "tests": [{"name": "lab", "scene": "lab.txt")" + test_fields +
                          "}]}");
  GradeResult r = grade(a, b, {});
  EXPECT_EQ(r.tests.size(), 1u);
  return r.tests.empty() ? TestResult{} : r.tests[0];
}

std::vector<std::string> codes(const TestResult& t) {
  std::vector<std::string> out;
  for (const Hint& h : t.hints) out.push_back(h.code);
  return out;
}

bool has(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

TEST(Assignment, ReadsTestsWithDefaultsFromTheTop) {
  Assignment a = parse_ok(R"({
    "name": "Lab 3", "profile": "cpsc102", "threshold": 1, "neighborhood": 1,
    "tests": [
      {"name": "one", "scene": "scenes/one.txt", "points": 3},
      {"name": "two", "scene": "two.json", "image": "out/two.png", "threshold": 0,
       "max_bad_fraction": 0.01, "options": {"spp": 4, "shadows": false},
       "credit": {"linear": {"metric": "mean_abs", "full": 0.5, "zero": 8}},
       "visibility": "after_due_date", "problem": "Shadows"}]})");
  ASSERT_EQ(a.tests.size(), 2u);
  EXPECT_EQ(a.name, "Lab 3");
  EXPECT_EQ(a.tests[0].image, "one.ppm");  // the scene's name with .ppm
  EXPECT_EQ(a.tests[0].points, 3);
  EXPECT_EQ(a.tests[0].threshold, 1);
  EXPECT_TRUE(a.tests[0].neighborhood);
  EXPECT_EQ(a.tests[0].problem, "one");
  EXPECT_EQ(a.tests[1].threshold, 0);
  EXPECT_EQ(a.tests[1].max_bad_fraction, 0.01);
  EXPECT_EQ(a.tests[1].credit.kind, CreditRule::Kind::linear);
  EXPECT_EQ(a.tests[1].visibility, "after_due_date");
  EXPECT_EQ(a.tests[1].problem, "Shadows");
  // The assignment's profile, then the test's own options.
  ASSERT_EQ(a.tests[1].options.size(), 3u);
  EXPECT_EQ(a.tests[1].options[0].name, "profile");
  for (const OptionValue& o : a.tests[1].options) {
    if (o.name == "spp") {
      EXPECT_EQ(o.value, "4");
    } else if (o.name == "shadows") {
      EXPECT_EQ(o.value, "0");
    }
  }
}

// Whole numbers are options as written: spp 100000 was read as "1e+05" and refused as not an
// integer, and a 64-bit seed lost its last digit.
TEST(Assignment, WholeNumberOptionsAreReadAsWritten) {
  Assignment a = parse_ok(R"({"name": "x", "options": {"spp": 100000, "seed": 18446744073709551615},
      "tests": [{"name": "a", "scene": "a.txt", "options": {"width": 40000, "max_dist": 12.5}}]})");
  ASSERT_EQ(a.tests.size(), 1u);
  std::map<std::string, std::string> text;
  for (const auto& o : a.tests[0].options) text[o.name] = o.value;
  EXPECT_EQ(text["spp"], "100000");
  EXPECT_EQ(text["seed"], "18446744073709551615");
  EXPECT_EQ(text["width"], "40000");
  EXPECT_EQ(text["max_dist"], "12.5");

  // A whole number in float form is the same number.
  Assignment f = parse_ok(R"({"name": "x", "options": {"spp": 1e5, "width": 640.0},
      "tests": [{"name": "a", "scene": "a.txt", "options": {"max_dist": 1.5e1}}]})");
  ASSERT_EQ(f.tests.size(), 1u);
  text.clear();
  for (const auto& o : f.tests[0].options) text[o.name] = o.value;
  EXPECT_EQ(text["spp"], "100000");
  EXPECT_EQ(text["width"], "640");
  EXPECT_EQ(text["max_dist"], "15");
}

TEST(Assignment, ErrorsArePlacedByTheirJsonPath) {
  EXPECT_EQ(first_error(R"({"tests": [{"name": "a", "scene": "a.txt"}]})"),
            "/name: missing: the assignment's name");
  EXPECT_EQ(first_error(R"({"name": "x", "tests": [{"name": "a", "scene": "a.txt", "threshhold": 2}]})"),
            "/tests/0/threshhold: unknown key 'threshhold'; did you mean 'threshold'?");
  EXPECT_EQ(first_error(R"({"name": "x", "tests": [{"name": "a", "scene": "a.txt", "options": {"spp": 0}}]})")
                .substr(0, 26),
            "/tests/0/options/spp: must");
  EXPECT_EQ(first_error(R"({"name": "x", "tests": [{"name": "a", "scene": "a.txt", "options": {"sppp": 2}}]})")
                .substr(0, 22),
            "/tests/0/options/sppp:");
  EXPECT_EQ(first_error(R"({"name": "x", "tests": [{"name": "a", "scene": "a.txt"}, {"name": "a", "scene": "b.txt"}]})"),
            "/tests/1/name: another test is named 'a'");
  EXPECT_EQ(first_error(R"({"name": "x", "tests": [{"name": "a", "scene": "a.txt", "image": "../a.ppm"}]})"),
            "/tests/0/image: must be a file name relative to the student's folder, without '..'");
  EXPECT_EQ(first_error(R"({"name": "x", "tests": [{"name": "a", "scene": "a.txt", "credit": {"steps": [[0.1, 1], [0.05, 0.5]]}}]})"),
            "/tests/0/credit/steps/1/0: steps must rise: each limit more than the one before");
  EXPECT_EQ(first_error(R"({"name": "x", "tests": [{"name": "a", "scene": "a.txt", "credit": {"linear": {"full": 2, "zero": 1}}}]})"),
            "/tests/0/credit/linear/zero: must be more than \"full\"");
  EXPECT_EQ(first_error(R"({"name": "x", "profile": "cpsc103", "tests": [{"name": "a", "scene": "a.txt"}]})").substr(0, 9),
            "/profile:");
  EXPECT_EQ(first_error(R"({"name": "x", "tests": []})"), "/tests: must be a non-empty list of tests");
  // A whole number past int's range is no 0 or 1 (4294967297 was read as 1).
  for (const char* n : {"4294967297", "-4294967295", "18446744073709551615", "2"})
    EXPECT_EQ(first_error(std::string(R"({"name": "x", "tests": [{"name": "a", "scene": "a.txt", "neighborhood": )") + n + "}]}"),
              "/tests/0/neighborhood: must be 0 or 1 (or false or true)") << n;
  // Syntax errors have a line and column.
  EXPECT_EQ(first_error("{\"name\": \"x\",\n  \"tests\": [\n    {\"name\": \"a\" \"scene\": 1}]}").substr(0, 2), "3:");
  // So does a number past double's range (it threw out of the parser: the grader aborted).
  EXPECT_EQ(first_error("{\"name\": \"x\",\n \"tests\": [{\"name\": \"a\", \"points\": 1e400}]}"),
            "2:36: invalid JSON: the number 1e400 is too large for a double");
  // A key given twice is an error where it repeats, as in a scene: the last one used to win
  // silently (an assignment edited by two people, the second "points" unseen).
  EXPECT_EQ(first_error(R"({"name": "x", "tests": [{"name": "a", "scene": "a.txt", "points": 5, "points": 50}]})"),
            "/tests/0/points: key given twice");
  EXPECT_EQ(first_error(R"({"name": "x", "tests": [{"name": "a", "scene": "a.txt"}], "tests": []})"),
            "/tests: key given twice");
  // Nesting is bounded as in scenes.
  EXPECT_EQ(first_error(R"({"name": "x", "tests": )" + std::string(100, '[') + std::string(100, ']') + "}"),
            "/tests/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0/0: JSON nested deeper than 64 levels");
}

TEST(Grade, AnIdenticalImagePassesWithFullPoints) {
  const Image ref = render_with(kScene, {{"profile", "cpsc102"}});
  TestResult t = grade_one(ref, R"(, "points": 4)");
  EXPECT_EQ(t.status, "passed");
  EXPECT_EQ(t.score, 4);
  EXPECT_EQ(t.message, "identical to the reference");
  EXPECT_TRUE(t.hints.empty());
  EXPECT_FALSE(t.diff);
  EXPECT_EQ(t.reference_sha256.size(), 64u);
}

TEST(Grade, MissingUnreadableAndWronglySizedImagesFailWithAHint) {
  FakeBackend b;
  b.scenes["lab.txt"] = kScene;
  b.unreadable["bad.ppm"] = "P6\n64 48\n255\nxyz";
  Image small(48, 64);
  b.images["small.ppm"] = small;
  b.images["huge.ppm"] = Image(2048, 2048);  // what a 49 KB PNG can hold
  Assignment a = parse_ok(R"({"name": "Lab", "tests": [
      {"name": "missing", "scene": "lab.txt"},
      {"name": "bad", "scene": "lab.txt", "image": "bad.ppm"},
      {"name": "small", "scene": "lab.txt", "image": "small.ppm"},
      {"name": "no scene", "scene": "nowhere.txt"},
      {"name": "huge", "scene": "lab.txt", "image": "huge.ppm"}]})");
  GradeResult r = grade(a, b, {});
  ASSERT_EQ(r.tests.size(), 5u);
  // A wrong size near the reference's is kept for the report; a far larger one is not held.
  EXPECT_TRUE(r.tests[2].student.has_value());
  EXPECT_EQ(codes(r.tests[4]), std::vector<std::string>{"wrong_size"});
  EXPECT_FALSE(r.tests[4].student.has_value());
  EXPECT_EQ(r.tests[0].status, "failed");
  EXPECT_EQ(codes(r.tests[0]), std::vector<std::string>{"missing_image"});
  EXPECT_EQ(r.tests[0].message, "your image lab.ppm was not found");
  EXPECT_TRUE(r.tests[0].student_missing);
  EXPECT_EQ(codes(r.tests[1]), std::vector<std::string>{"missing_image"});
  EXPECT_NE(r.tests[1].message.find("cannot be read: "), std::string::npos);
  EXPECT_EQ(codes(r.tests[2]), std::vector<std::string>{"wrong_size"});
  EXPECT_EQ(r.tests[2].message,
            "your image is 48x64, the reference is 64x48: width and height are swapped "
            "(pixeldim gives columns, then rows)");
  EXPECT_EQ(r.tests[3].status, "error");
  // A test without its reference makes the whole result the grader's error.
  EXPECT_EQ(r.error.rfind("test 'no scene': ", 0), 0u) << r.error;
  EXPECT_EQ(r.score, 0);
  EXPECT_EQ(r.max_score, 5);
}

TEST(Grade, CreditRulesGivePartialPoints) {
  const Image ref = render_with(kScene, {{"profile", "cpsc102"}});
  Image off = ref;
  for (std::uint8_t& v : off.rgb) v = static_cast<std::uint8_t>(std::min(255, v + 4));
  // mean_abs is a little under 4 (saturated channels stay): between full (1) and zero (7).
  TestResult linear = grade_one(off, R"(, "points": 10, "credit": {"linear": {"metric": "mean_abs", "full": 1, "zero": 7}})");
  ASSERT_TRUE(linear.metrics);
  const double expected = 10 * (7 - linear.metrics->mean_abs) / 6;
  EXPECT_NEAR(linear.score, expected, 1e-3);
  EXPECT_EQ(linear.status, "failed");
  TestResult steps = grade_one(off, R"(, "points": 10, "credit": {"metric": "max_abs", "steps": [[2, 1], [4, 0.5], [8, 0.25]]})");
  EXPECT_EQ(steps.score, 5);
  TestResult all = grade_one(off, R"(, "points": 10)");
  EXPECT_EQ(all.score, 0);
  TestResult forgiven = grade_one(off, R"(, "points": 10, "threshold": 4)");
  EXPECT_EQ(forgiven.score, 10);
  EXPECT_EQ(forgiven.status, "passed");
  TestResult fraction = grade_one(off, R"(, "points": 10, "max_bad_fraction": 1)");
  EXPECT_EQ(fraction.status, "passed");
  // A limit that prints as the share that failed it is said in pixels: 100 of 3072 pixels
  // (3.26%) differ, and up to 99.996 may.
  Image hundred = ref;
  for (int i = 0; i < 100; ++i)
    hundred.rgb[i * 3] = static_cast<std::uint8_t>(hundred.rgb[i * 3] < 128 ? 200 : 20);
  TestResult close = grade_one(hundred, R"(, "points": 10, "max_bad_fraction": 0.032551)");
  EXPECT_EQ(close.status, "failed");
  EXPECT_NE(close.message.find("(3.26%; up to 99 pixels may)"), std::string::npos)
      << close.message;
}

// With a scale of credit, full points are a pass whatever max_bad_fraction says (it belongs to
// "all"), and the message does not quote it.
TEST(Grade, FullPointsOnAScaleAreAPass) {
  const Image ref = render_with(kScene, {{"profile", "cpsc102"}});
  Image off = ref;
  off.rgb[0] = static_cast<std::uint8_t>(off.rgb[0] ^ 8);  // one channel of one pixel
  TestResult linear = grade_one(off, R"(, "points": 3, "credit": {"linear": {"metric": "max_abs", "full": 8, "zero": 20}})");
  EXPECT_EQ(linear.score, 3);
  EXPECT_EQ(linear.status, "passed");
  EXPECT_EQ(linear.message.find("may"), std::string::npos) << linear.message;
  TestResult steps = grade_one(off, R"(, "points": 3, "credit": {"metric": "bad_fraction", "steps": [[0.001, 1], [0.02, 0.5]]})");
  EXPECT_EQ(steps.score, 3);
  EXPECT_EQ(steps.status, "passed");
  // A credit a hair under full (8.00004 against full at 8) rounds to the full points: those
  // are what the platform shows, so the test passed.
  TestResult near = grade_one(off, R"(, "points": 2, "credit": {"linear": {"metric": "max_abs", "full": 7.99996, "zero": 10}})");
  EXPECT_EQ(near.score, 2);
  EXPECT_EQ(near.status, "passed");
  // A test of no points on a scale passes on its full credit only (its score is 0 either way).
  TestResult none = grade_one(off, R"(, "points": 0, "credit": {"linear": {"metric": "max_abs", "full": 2, "zero": 10}})");
  EXPECT_EQ(none.status, "failed");
  TestResult all = grade_one(off, R"(, "points": 3)");
  EXPECT_EQ(all.score, 0);
  EXPECT_EQ(all.status, "failed");
  EXPECT_NE(all.message.find("1 of 3072 pixels differ by more than 0 levels (0.03%; none may)"),
            std::string::npos) << all.message;
  // The metrics line says the numbers as the message does (it said 0.033% and a mean of 0).
  GradeResult r;
  r.tests.push_back(all);
  const std::string output =
      Json::parse(write_result(r, Format::gradescope))["tests"][0]["output"].get<std::string>();
  EXPECT_NE(output.find("differing pixels 1 (0.03%), mean difference 0.0008681,"),
            std::string::npos)
      << output;
}

// Points are kept to 1/10000, as scores are: full marks are the points exactly, and an
// assignment worth nothing is all there is to have once every test passes.
TEST(Grade, PointsAreKeptAsScoresAre) {
  const Image ref = render_with(kScene, {{"profile", "cpsc102"}});
  FakeBackend b;
  b.scenes["lab.txt"] = kScene;
  b.images["lab.ppm"] = ref;
  Assignment a = parse_ok(R"({"name": "Lab", "profile": "cpsc102", "tests": [
      {"name": "a", "scene": "lab.txt", "points": 0.3333333333},
      {"name": "b", "scene": "lab.txt", "points": 0.1},
      {"name": "c", "scene": "lab.txt", "points": 0.2}]})");
  EXPECT_EQ(a.tests[0].points, 0.3333);
  GradeResult r = grade(a, b, {});
  for (const TestResult& t : r.tests) {
    EXPECT_EQ(t.status, "passed") << t.name;
    EXPECT_EQ(t.score, t.max_score) << t.name;
  }
  EXPECT_EQ(r.score, r.max_score);
  EXPECT_EQ(r.fraction(), 1);
  Assignment free = parse_ok(R"({"name": "Lab", "profile": "cpsc102", "tests": [
      {"name": "a", "scene": "lab.txt", "points": 0}]})");
  EXPECT_EQ(grade(free, b, {}).fraction(), 1);
  b.images["lab.ppm"] = Image(64, 48);
  EXPECT_EQ(grade(free, b, {}).fraction(), 0);
}

// Each mistake, made: the hint names it.
TEST(Hints, RoundingWhereTheReferenceTruncates) {
  const Image mine = render_with(kScene, {{"profile", "cpsc102"}, {"rounding", "nearest"}});
  TestResult t = grade_one(mine);
  ASSERT_EQ(codes(t), std::vector<std::string>{"rounding"});
  EXPECT_NE(t.hints[0].message.find("exactly the reference made with rounding=nearest"), std::string::npos);
  // A passing test can still carry the hint.
  TestResult passing = grade_one(mine, R"(, "threshold": 1)");
  EXPECT_EQ(passing.status, "passed");
  EXPECT_EQ(codes(passing), std::vector<std::string>{"rounding"});
}

TEST(Hints, TruncatingWhereTheReferenceRounds) {
  const Image mine = render_with(kScene, {{"rounding", "truncate"}});
  EXPECT_EQ(codes(grade_one(mine, "", "lecture")), std::vector<std::string>{"truncation"});
}

// One channel one level off is no rounding convention (that would move many channels): the
// hint says a difference of one level and names no cause.
TEST(Hints, OneChannelOneLevelOffIsNoConvention) {
  const Image ref = render_with(kScene, {{"profile", "cpsc102"}});
  Image mine = ref;
  std::size_t at = 0;
  while (mine.rgb[at] == 255) ++at;
  ++mine.rgb[at];
  EXPECT_EQ(codes(grade_one(mine)), std::vector<std::string>{"off_by_one"});
  const Image lecture = render_with(kScene, {});
  Image dark = lecture;
  at = 0;
  while (dark.rgb[at] == 0) ++at;
  --dark.rgb[at];
  EXPECT_EQ(codes(grade_one(dark, "", "lecture")), std::vector<std::string>{"off_by_one"});
}

TEST(Hints, UpsideDownMirroredAndSwappedChannels) {
  const Image ref = render_with(kScene, {{"profile", "cpsc102"}});
  Image flipped(ref.width, ref.height), mirrored(ref.width, ref.height), bgr = ref;
  for (int y = 0; y < ref.height; ++y)
    for (int x = 0; x < ref.width; ++x)
      for (int c = 0; c < 3; ++c) {
        flipped.row(ref.height - 1 - y)[3 * x + c] = ref.row(y)[3 * x + c];
        mirrored.row(y)[3 * (ref.width - 1 - x) + c] = ref.row(y)[3 * x + c];
      }
  for (size_t i = 0; i < bgr.rgb.size(); i += 3) std::swap(bgr.rgb[i], bgr.rgb[i + 2]);
  EXPECT_EQ(codes(grade_one(flipped)), std::vector<std::string>{"upside_down"});
  EXPECT_EQ(codes(grade_one(mirrored)), std::vector<std::string>{"mirrored"});
  EXPECT_EQ(codes(grade_one(bgr)), std::vector<std::string>{"red_blue_swapped"});
}

TEST(Hints, TheLectureEquationWhereTheCourseProgramIsGraded) {
  const Image mine = render_with(kScene, {{"profile", "lecture"}});
  EXPECT_EQ(codes(grade_one(mine)), std::vector<std::string>{"lecture_profile"});
}

TEST(Hints, NoPathCap) {
  // A polished floor and a far wall: the course's program stops a reflected ray whose path
  // is already longer than 20 units, so the far floor shows no wall.
  std::string scene = kScene;
  const std::string floor = "diffuse .7 .7 .7 }";
  scene.replace(scene.find(floor), floor.size(), "diffuse .7 .7 .7\n  specular .5 .5 .5 }");
  scene += "plane wall\n{ material floor\n  normal 0 0 1\n  point 0 0 -15 }\n";
  const Image mine = render_with(scene, {{"profile", "cpsc102"}, {"max_dist", "unlimited"}});
  EXPECT_EQ(codes(grade_one(mine, "", "cpsc102", scene)), std::vector<std::string>{"path_cap"});
}

// A render that changes nothing explains nothing: on a test passed within its threshold, the
// render without a path cap (no path here is that long, so it is the reference) matched the
// student's image as well as the reference and was named as their mistake.
TEST(Hints, NoneFromARenderNoNearerThanTheReference) {
  const Image ref = render_with(kScene, {{"profile", "cpsc102"}});
  Image near = ref;
  bool up = false;  // two levels either way: not the signature of rounding or arithmetic
  for (size_t i = 0; i < near.rgb.size(); i += 97, up = !up)
    near.rgb[i] = static_cast<std::uint8_t>(up ? (near.rgb[i] < 254 ? near.rgb[i] + 2 : 253)
                                               : (near.rgb[i] > 1 ? near.rgb[i] - 2 : 2));
  TestResult t = grade_one(near, R"(, "threshold": 2)");
  EXPECT_EQ(t.status, "passed");
  EXPECT_EQ(codes(t), std::vector<std::string>{}) << t.hints[0].message;
  // Nor when the test fails: the reference then is no better than the candidate.
  TestResult failing = grade_one(near);
  EXPECT_EQ(failing.status, "failed");
  for (const std::string& code : codes(failing)) EXPECT_NE(code, "path_cap");
}

TEST(Hints, NoReflections) {
  const Image mine = render_with(kScene, {{"profile", "cpsc102"}, {"max_depth", "0"}});
  EXPECT_EQ(codes(grade_one(mine)), std::vector<std::string>{"no_reflections"});
}

TEST(Hints, ABlankImage) {
  const Image ref = render_with(kScene, {{"profile", "cpsc102"}});
  Image black(ref.width, ref.height);
  EXPECT_EQ(codes(grade_one(black)), std::vector<std::string>{"blank_image"});
}

TEST(Hints, ErrorsOnlyInShadows) {
  // No shadow test: the floor under the spheres is lit.
  const Image mine = render_with(kScene, {{"profile", "cpsc102"}, {"shadows", "0"}});
  TestResult t = grade_one(mine);
  EXPECT_TRUE(has(codes(t), "shadows")) << ::testing::PrintToString(codes(t));
}

TEST(Hints, ErrorsOnlyAtHighlights) {
  // The Blinn half vector where the lecture's reflected vector is graded.
  const Image mine = render_with(kScene, {{"highlight", "blinn"}});
  TestResult t = grade_one(mine, "", "lecture");
  EXPECT_TRUE(has(codes(t), "highlights")) << ::testing::PrintToString(codes(t));
}

TEST(Hints, ErrorsOnlyInReflections) {
  // Reflections stopped one bounce early: only what the mirror shows differs.
  std::string scene = kScene;
  const Image mine = render_with(scene, {{"profile", "cpsc102"}, {"max_depth", "1"}});
  const Image ref = render_with(scene, {{"profile", "cpsc102"}});
  ASSERT_NE(mine, ref);
  TestResult t = grade_one(mine);
  EXPECT_TRUE(has(codes(t), "reflections")) << ::testing::PrintToString(codes(t));
}

TEST(Hints, ErrorsOnOneObject) {
  // The red ball's diffuse colour misread (green and blue swapped in its material only).
  std::string scene = kScene;
  const std::string from = "diffuse .8 .2 .2", to = "diffuse .8 .25 .2";
  scene.replace(scene.find(from), from.size(), to);
  const Image mine = render_with(scene, {{"profile", "cpsc102"}});
  TestResult t = grade_one(mine);
  ASSERT_TRUE(has(codes(t), "one_object")) << ::testing::PrintToString(codes(t));
  for (const Hint& h : t.hints)
    if (h.code == "one_object") {
      EXPECT_NE(h.message.find("sphere 'ball'"), std::string::npos);
    }
}

TEST(Hints, SpecklesWhereTheReferenceIsSmooth) {
  // Shadow acne, made for real: the student's shadow rays test the floor they leave (here a
  // second floor in the same place, which the course's program does not skip), and meet it
  // at t near 0 on about every other pixel, by rounding.
  const std::string acne = std::string(kScene) +
                           "plane ground_again\n{ material floor\n  normal 0 1 0\n  point 0 0 0 }\n";
  const Image mine = render_with(acne, {{"profile", "cpsc102"}, {"width", "160"}, {"height", "120"}});
  TestResult t = grade_one(mine, R"(, "options": {"width": 160, "height": 120})");
  ASSERT_FALSE(t.hints.empty());
  EXPECT_EQ(t.hints[0].code, "speckles") << ::testing::PrintToString(codes(t));
}

TEST(Hints, TheBackgroundOnly) {
  const Image mine = render_with(kScene, {{"profile", "cpsc102"}, {"background", "0.2,0.2,0.2"}});
  TestResult t = grade_one(mine);
  EXPECT_TRUE(has(codes(t), "background")) << ::testing::PrintToString(codes(t));
}

GradeResult mixed_result() {
  FakeBackend b;
  b.scenes["lab.txt"] = kScene;
  b.images["good.ppm"] = render_with(kScene, {{"profile", "cpsc102"}});
  b.images["round.ppm"] = render_with(kScene, {{"profile", "cpsc102"}, {"rounding", "nearest"}});
  Assignment a = parse_ok(R"({"name": "Lab <1> & \"co\"", "profile": "cpsc102", "tests": [
      {"name": "good", "scene": "lab.txt", "image": "good.ppm", "points": 2, "problem": "Basics"},
      {"name": "round", "scene": "lab.txt", "image": "round.ppm", "points": 3, "problem": "Basics",
       "visibility": "after_due_date"},
      {"name": "gone", "scene": "lab.txt", "image": "gone.ppm", "points": 1}]})");
  return grade(a, b, {});
}

TEST(Formats, GradescopeResults) {
  Json j = Json::parse(write_result(mixed_result(), Format::gradescope));
  EXPECT_EQ(j["score"], 2);
  ASSERT_EQ(j["tests"].size(), 3u);
  EXPECT_EQ(j["tests"][0]["score"], 2);
  EXPECT_EQ(j["tests"][0]["max_score"], 2);
  EXPECT_EQ(j["tests"][0]["status"], "passed");
  EXPECT_EQ(j["tests"][1]["status"], "failed");
  EXPECT_EQ(j["tests"][1]["visibility"], "after_due_date");
  EXPECT_EQ(j["tests"][1]["output_format"], "md");
  EXPECT_NE(j["tests"][1]["output"].get<std::string>().find("[rounding]"), std::string::npos);
  EXPECT_EQ(j["tests"][2]["score"], 0);
  // The top-level output, which students always see, gives no total while a test is hidden
  // from them (the total less the visible tests would be its score).
  const std::string top = j["output"];
  EXPECT_EQ(top.find("points"), std::string::npos) << top;
  EXPECT_EQ(top.rfind("Lab <1> & \"co\" (rayfarm render version ", 0), 0u) << top;
  GradeResult shown = mixed_result();
  for (TestResult& t : shown.tests) t.visibility = "visible";
  const std::string all = Json::parse(write_result(shown, Format::gradescope))["output"];
  EXPECT_NE(all.find(": 2 / 6 points"), std::string::npos) << all;
}

TEST(Formats, PrairieLearnResults) {
  Json j = Json::parse(write_result(mixed_result(), Format::prairielearn));
  EXPECT_EQ(j["gradable"], true);
  EXPECT_NEAR(j["score"].get<double>(), 2.0 / 6, 1e-4);
  EXPECT_FALSE(j["tests"][0].contains("images"));  // passed: no pictures needed
  ASSERT_TRUE(j["tests"][1].contains("images"));
  ASSERT_EQ(j["tests"][1]["images"].size(), 3u);
  EXPECT_EQ(j["tests"][1]["images"][2]["label"], "Difference");
  const std::string url = j["tests"][1]["images"][0]["url"];
  EXPECT_EQ(url.substr(0, 22), "data:image/png;base64,");
  // The data URL decodes to the reference itself (small images are not shrunk).
  std::string png;
  unsigned bits = 0;
  int n = 0;
  for (char ch : url.substr(22)) {
    const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const char* at = std::strchr(alphabet, ch);
    if (ch == '=' || !at) break;
    bits = (bits << 6) | static_cast<unsigned>(at - alphabet);
    if ((n += 6) >= 8) png += static_cast<char>((bits >> (n -= 8)) & 0xFF);
  }
  std::string error;
  auto decoded = decode_image(png, &error);
  ASSERT_TRUE(decoded) << error;
  EXPECT_EQ(*decoded, render_with(kScene, {{"profile", "cpsc102"}}));
  EXPECT_EQ(j["tests"][1]["points"], 0);
  EXPECT_EQ(j["tests"][1]["max_points"], 3);

  // No readable image at all: not gradable (no attempt used), with the reasons.
  FakeBackend b;
  b.scenes["lab.txt"] = kScene;
  Assignment a = parse_ok(R"({"name": "Lab", "tests": [{"name": "t", "scene": "lab.txt"}]})");
  Json none = Json::parse(write_result(grade(a, b, {}), Format::prairielearn));
  EXPECT_EQ(none["gradable"], false);
  EXPECT_EQ(none["format_errors"][0], "t: your image lab.ppm was not found");
}

TEST(Formats, PrairieLearnStaysUnderItsSizeLimit) {
  // Large failing images are shrunk to share the budget.
  std::string scene = kScene;
  scene.replace(scene.find("pixeldim 64 48"), 14, "pixeldim 800 600");
  FakeBackend b;
  b.scenes["big.txt"] = scene;
  Image noise(800, 600);
  std::uint32_t s = 1;
  for (std::uint8_t& v : noise.rgb) v = static_cast<std::uint8_t>((s = s * 1664525 + 1013904223) >> 24);
  b.images["a.ppm"] = noise;
  b.images["b.ppm"] = noise;
  Assignment a = parse_ok(R"({"name": "Big", "tests": [{"name": "a", "scene": "big.txt", "image": "a.ppm"},
                                                      {"name": "b", "scene": "big.txt", "image": "b.ppm"}]})");
  GradeSettings settings;
  settings.hints = false;
  const std::string text = write_result(grade(a, b, settings), Format::prairielearn);
  EXPECT_LT(text.size(), 1000000u);
  EXPECT_TRUE(Json::parse(text)["tests"][0].contains("images"));
  // The text counts too: 20 failing tests with long names (a program's output is as long)
  // leave the images less room (they took their 700 KB whatever the text was: 1.07 MB).
  std::string many = R"({"name": "Big", "tests": [)";
  for (int i = 0; i < 20; ++i)
    many += std::string(i ? ", " : "") + R"({"name": ")" + std::to_string(i) + std::string(40000, 'n') +
            R"(", "scene": "big.txt", "image": "a.ppm"})";
  const std::string crowded =
      write_result(grade(parse_ok(many + "]}"), b, settings), Format::prairielearn);
  EXPECT_LT(crowded.size(), 1000000u);
  EXPECT_TRUE(Json::parse(crowded)["tests"][0].contains("images"));
  EXPECT_GT(crowded.size(), 20u * 40000);  // every name is there
}

TEST(Formats, AutolabScoreLineComesLast) {
  const std::string text = write_result(mixed_result(), Format::autolab);
  ASSERT_FALSE(text.empty());
  const std::string body = text.substr(0, text.size() - 1);
  const std::string last = body.substr(body.find_last_of('\n') + 1);
  Json j = Json::parse(last);
  EXPECT_EQ(j["scores"]["Basics"], 2);
  EXPECT_EQ(j["scores"]["gone"], 0);
  const std::string before = body.substr(0, body.find_last_of('\n'));
  Json semantic = Json::parse(before.substr(before.find_last_of('\n') + 1));
  EXPECT_EQ(semantic["_presentation"], "semantic");
  EXPECT_EQ(semantic["Images"]["round"]["passed"], false);
}

TEST(Formats, JUnitMarkdownHtmlAndJson) {
  const GradeResult r = mixed_result();
  const std::string xml = write_result(r, Format::junit);
  EXPECT_NE(xml.find("<testsuite name=\"Lab &lt;1&gt; &amp; &quot;co&quot;\" tests=\"3\" failures=\"2\" errors=\"0\""),
            std::string::npos);
  EXPECT_NE(xml.find("<property name=\"score\" value=\"2\"/>"), std::string::npos);
  EXPECT_EQ(std::count(xml.begin(), xml.end(), '<') - std::count(xml.begin(), xml.end(), '>'), 0);
  const std::string md = write_result(r, Format::md);
  EXPECT_NE(md.find("**Score: 2 / 6**"), std::string::npos);
  EXPECT_NE(md.find("| round | 0 / 3 | failed |"), std::string::npos);
  const std::string html = write_result(r, Format::html);
  EXPECT_NE(html.find("<img alt=\"\" src=\"data:image/png;base64,"), std::string::npos);
  EXPECT_EQ(html.find("<1>"), std::string::npos);  // escaped
  Json j = Json::parse(write_result(r, Format::json));
  EXPECT_EQ(j["score"], 2);
  EXPECT_EQ(j["tests"][1]["hints"][0]["code"], "rounding");
  EXPECT_TRUE(j["tests"][0]["metrics"]["psnr"].is_null());
  EXPECT_EQ(j["tests"][0]["metrics"]["identical"], true);
  // Deterministic: grading again writes the same bytes.
  EXPECT_EQ(write_result(mixed_result(), Format::json), write_result(r, Format::json));
}

// A student's program writes what it likes: the report shows it as text, inside its fence.
TEST(Formats, AProgramsOutputCannotBreakTheReport) {
  // Cut inside a character, raw bytes, a terminal escape, a NUL.
  std::string log(3000, 'x');
  for (int i = 0; i < 700; ++i) log += "\xe6\x97\xa5";  // 日, 3 bytes each
  log += "\xff\x1b[2J";
  log.push_back('\0');
  log += "```\n**PASSED 100/100**\n<!-- ";
  const std::string tail = output_tail(log, 2048);
  EXPECT_LE(tail.size(), 2048u + 3 * 8);
  EXPECT_EQ(tail.substr(0, 3), "\xe6\x97\xa5") << "starts on a whole character";
  EXPECT_EQ(tail.find('\x1b'), std::string::npos);
  EXPECT_EQ(tail.find('\0'), std::string::npos);
  EXPECT_EQ(tail.find('\xff'), std::string::npos);
  GradeResult r;
  r.assignment = "Lab";
  TestResult t;
  t.name = "run \xc3";
  t.status = "failed";
  t.message = "your program wrote no image";
  t.log_tail = tail;
  r.tests.push_back(t);
  // Markdown: the fence is longer than any run of backticks in the output.
  for (Format f : {Format::md, Format::gradescope}) {
    const std::string text = write_result(r, f);
    EXPECT_NE(text.find("````"), std::string::npos) << to_string(f);
  }
  // XML: only valid UTF-8 and no control characters but tab and newline.
  const std::string xml = write_result(r, Format::junit);
  for (unsigned char c : xml) EXPECT_TRUE(c >= 0x20 || c == '\n' || c == '\t') << int(c);
  EXPECT_NE(xml.find("run \xef\xbf\xbd"), std::string::npos);
  // A file name the student chose, quoted in a message, is text in the Markdown a platform
  // renders, not a tag.
  r.tests[0].message = "your image a.ppm was not found; a file named '<img src=x onerror=alert(1)>.ppm' is there";
  r.tests[0].hints = {{"missing_image", r.tests[0].message}};
  // (Gradescope's extra_data keeps the message as data; its output is what the page renders.)
  const std::string gradescope =
      Json::parse(write_result(r, Format::gradescope))["tests"][0]["output"].get<std::string>();
  for (const std::string& text : {write_result(r, Format::md), gradescope}) {
    EXPECT_EQ(text.find("<img"), std::string::npos) << text;
    EXPECT_NE(text.find("&lt;img src=x"), std::string::npos) << text;
  }
}

TEST(Formats, BytesThatAreNotUtf8BecomeReplacementCharacters) {
  // A student's file name or a backend message may carry any bytes; JSON output stays JSON.
  GradeResult r;
  r.assignment = "Lab \xff";
  r.error = "cannot read 'shot\xfe.ppm'";
  TestResult t;
  t.name = "t\xc3";  // a truncated two-byte sequence
  t.status = "failed";
  t.message = "your image st\xffu.ppm was not found";
  t.student_missing = true;
  r.tests.push_back(t);
  for (Format f : {Format::gradescope, Format::prairielearn, Format::json}) {
    const std::string text = write_result(r, f);
    Json j;
    ASSERT_NO_THROW(j = Json::parse(text)) << to_string(f);
    EXPECT_NE(text.find("\xef\xbf\xbd"), std::string::npos) << to_string(f);  // U+FFFD
  }
  const std::string autolab = write_result(r, Format::autolab);
  const std::string body = autolab.substr(0, autolab.size() - 1);
  Json last;
  EXPECT_NO_THROW(last = Json::parse(body.substr(body.find_last_of('\n') + 1)));
  // The plain-text reports are UTF-8 throughout too: the student's bytes are replaced.
  for (Format f : {Format::autolab, Format::md}) {
    const std::string text = write_result(r, f);
    EXPECT_EQ(printable_text(text), text) << to_string(f);
    EXPECT_NE(text.find("st\xef\xbf\xbdu.ppm"), std::string::npos) << to_string(f);
  }
}

TEST(Lock, RefusesReferencesThatChanged) {
  const GradeResult r = mixed_result();
  Json lock = lock_json(r);
  EXPECT_TRUE(check_lock(r, lock).empty());
  Json changed = lock;
  changed["tests"]["round"]["reference_sha256"] = std::string(64, '0');
  auto problems = check_lock(r, changed);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("test 'round'"), std::string::npos);
  Json extra = lock;
  extra["tests"]["old"] = {{"reference_sha256", "x"}};
  EXPECT_EQ(check_lock(r, extra).size(), 1u);
  // A lock edited by hand: entries of the wrong type are problems, not a crash.
  for (const Json& entry : {Json(5), Json({{"reference_sha256", 5}}), Json::array(),
                            Json({{"reference_key", 1}})}) {
    Json odd = lock;
    odd["tests"]["round"] = entry;
    std::vector<std::string> found;
    ASSERT_NO_THROW(found = check_lock(r, odd)) << entry.dump();
    ASSERT_EQ(found.size(), 1u) << entry.dump();
    EXPECT_NE(found[0].find("test 'round'"), std::string::npos) << found[0];
  }
}

}  // namespace
}  // namespace rayfarm::grading
