// Converters and lint: model <-> JSON round trips are exact, the POV-Ray export carries the
// scene, and each lint warning fires for the scene that has the problem and no other.
#include <gtest/gtest.h>

#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "rayfarm/json_scene.h"
#include "rayfarm/lint.h"
#include "rayfarm/load.h"
#include "rayfarm/model_parser.h"
#include "rayfarm/render.h"
#include "rayfarm/writers.h"
#include "render/render_checks.h"
#include "test_util.h"

namespace rayfarm {
namespace {

using test::expect_same_scene;

// The lecture scene, as bundled in scenes/.
const std::string kLecture = test::lecture_scene();

std::string dump(const Diagnostics& diags) {
  std::string out;
  for (const Diagnostic& d : diags.items())
    out += d.where.path + " " + std::to_string(d.where.line) + ":" +
           std::to_string(d.where.column) + " " + d.code + ": " + d.message + "\n";
  return out;
}

SceneDesc model_desc(std::string_view text) {
  Diagnostics diags;
  SceneDesc desc = parse_model(text, diags);
  EXPECT_FALSE(diags.has_errors()) << dump(diags) << "in:\n" << text;
  return desc;
}

SceneDesc json_desc(std::string_view text) {
  Diagnostics diags;
  SceneDesc desc = parse_json_scene(text, diags);
  EXPECT_FALSE(diags.has_errors()) << dump(diags) << "in:\n" << text;
  return desc;
}

Scene build(const SceneDesc& desc) {
  Diagnostics diags;
  std::optional<Scene> scene = build_scene(desc, diags);
  EXPECT_TRUE(scene.has_value()) << dump(diags);
  return scene.value_or(Scene{});
}

bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

void expect_same_entity(const EntityDesc& a, const EntityDesc& b) {
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.name, b.name);
  ASSERT_EQ(a.attrs.size(), b.attrs.size()) << a.name;
  for (size_t i = 0; i < a.attrs.size(); ++i) {
    EXPECT_EQ(a.attrs[i].key, b.attrs[i].key);
    EXPECT_EQ(a.attrs[i].word, b.attrs[i].word);
    ASSERT_EQ(a.attrs[i].numbers.size(), b.attrs[i].numbers.size()) << a.attrs[i].key;
    for (size_t k = 0; k < a.attrs[i].numbers.size(); ++k)
      EXPECT_TRUE(same_bits(a.attrs[i].numbers[k], b.attrs[i].numbers[k]))
          << a.name << " " << a.attrs[i].key << "[" << k << "]: " << a.attrs[i].numbers[k] << " vs "
          << b.attrs[i].numbers[k];
  }
}

// Same entities of each kind in the same order (JSON groups entities by kind, so the order
// across kinds may differ), same attributes, bit-identical numbers.
void expect_same_desc(const SceneDesc& a, const SceneDesc& b) {
  for (int k = 0; k < kEntityKinds; ++k) {
    const EntityKind kind = static_cast<EntityKind>(k);
    std::vector<const EntityDesc*> as, bs;
    for (const EntityDesc& e : a.entities)
      if (e.kind == kind) as.push_back(&e);
    for (const EntityDesc& e : b.entities)
      if (e.kind == kind) bs.push_back(&e);
    ASSERT_EQ(as.size(), bs.size()) << static_cast<int>(kind);
    for (size_t i = 0; i < as.size(); ++i) expect_same_entity(*as[i], *bs[i]);
  }
}

bool contains(const std::string& text, std::string_view part) {
  return text.find(part) != std::string::npos;
}

// --- Model <-> JSON -------------------------------------------------------------------------

TEST(Convert, ModelToJsonToModelGivesTheSameDescriptionAndScene) {
  SceneDesc original = model_desc(kLecture);
  SceneDesc via_json = json_desc(write_json(original));
  SceneDesc back = model_desc(write_model(via_json));
  expect_same_desc(original, via_json);
  expect_same_desc(original, back);
  // The lecture file is grouped by kind, so even the order of entities survives.
  ASSERT_EQ(back.entities.size(), original.entities.size());
  for (size_t i = 0; i < back.entities.size(); ++i)
    EXPECT_EQ(back.entities[i].name, original.entities[i].name);
  expect_same_scene(build(original), build(back));
  expect_same_scene(build(original), build(via_json));
}

// Every scene rayfarm ships and every course scene, with every entity kind: model to JSON
// and back gives the same description and the same checked scene (objects keep their file
// order across kinds, since JSON keeps objects in one array), and POV-Ray export writes an
// entry for every object and light.
TEST(Convert, EveryKindRoundTripsThroughJsonAndExportsToPov) {
  std::vector<std::filesystem::path> files;
  for (const char* dir : {"/scenes", "/tests/conformance/course"})
    for (auto& entry : std::filesystem::recursive_directory_iterator(RAYFARM_SOURCE_DIR +
                                                                      std::string(dir)))
      if (entry.path().extension() == ".txt") files.push_back(entry.path());
  std::set<EntityKind> kinds;
  for (const auto& path : files) {
    SCOPED_TRACE(path.string());
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    SceneDesc original = model_desc(text.str());
    for (const EntityDesc& e : original.entities) kinds.insert(e.kind);
    SceneDesc via_json = json_desc(write_json(original));
    SceneDesc back = model_desc(write_model(via_json));
    expect_same_desc(original, via_json);
    expect_same_desc(original, back);
    const Scene a = build(original), b = build(back), c = build(via_json);
    expect_same_scene(a, b);  // all but source positions, which the rewrite moves
    expect_same_scene(a, c);
    for (size_t i = 0; i < a.objects.size(); ++i)
      EXPECT_TRUE(a.objects[i].shape == c.objects[i].shape) << "object " << i;
    const std::string pov = write_pov(a, RenderOptions{});
    size_t entries = 0;
    for (const char* start : {"\nsphere {", "\nplane {", "\npolygon {", "\ntriangle {", "\nsor {",
                              "\nlight_source {"})
      for (size_t at = pov.find(start); at != std::string::npos; at = pov.find(start, at + 1))
        ++entries;
    EXPECT_EQ(entries, a.objects.size() + a.lights.size()) << pov;
  }
  EXPECT_EQ(kinds.size(), static_cast<size_t>(kEntityKinds)) << "some kind is in no scene";
}

TEST(Convert, WritingAModelFileIsAFixedPoint) {
  std::string once = write_model(model_desc(kLecture));
  std::string twice = write_model(json_desc(write_json(model_desc(once))));
  EXPECT_EQ(once, twice);
  EXPECT_TRUE(contains(once,
                       "sphere left\n{\n   material chrome\n   center 1.25 0.75 -4\n"
                       "   radius 0.9\n}\n"))
      << once;
}

TEST(Convert, JsonToModelToJsonGivesTheSameJson) {
  std::string json = write_json(model_desc(kLecture));
  SceneDesc from_json = json_desc(json);
  SceneDesc back = model_desc(write_model(from_json));
  EXPECT_EQ(write_json(back), json);
  expect_same_desc(from_json, back);
  expect_same_scene(build(from_json), build(back));
}

TEST(Convert, KeepsScenesWithInterleavedEntitiesTheSame) {
  constexpr std::string_view text =
      "sphere s { material late center 0 0 -5 radius 1 }\n"
      "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
      "light { location 1 2 3 }\n"
      "material late { diffuse 0.5 }\n"
      "plane { material late normal 0 1 0 point 0 -1 0 }\n"
      "light { location 3 2 1 emissivity 0.5 }\n"
      "sphere { material late center 1 0 -5 radius 2 }\n";
  SceneDesc original = model_desc(text);
  SceneDesc back = model_desc(write_model(json_desc(write_json(original))));
  expect_same_desc(original, back);
  expect_same_scene(build(original), build(back));
}

TEST(Convert, KeepsEveryNumberBitForBit) {
  const double values[] = {0.1,
                           1e-300,
                           123456789.123456789,
                           -0.0,
                           4.9e-324,
                           2.2250738585072014e-308,
                           1.7976931348623157e308,
                           0.30000000000000004,
                           1.0 / 3.0,
                           -2.5e-7,
                           9007199254740993.0,
                           1e16,
                           123456789012345678.0};
  for (double v : values) {
    SCOPED_TRACE(v);
    std::string text = "camera c { pixeldim 8 6 worlddim 8 6 viewpoint " + format_number(v) + " " +
                       format_number(-v) + " " + format_number(v) + " }\n";
    SceneDesc original = model_desc(text);
    ASSERT_TRUE(same_bits(original.entities[0].attrs[2].numbers[0], v));
    std::string json = write_json(original);
    SceneDesc via_json = json_desc(json);
    SceneDesc back = model_desc(write_model(via_json));
    expect_same_desc(original, via_json);
    expect_same_desc(original, back);
  }
}

// Each number in the fewest digits that read back as it (fixed from 1e-6 to 1e15), and a
// double stays a double ("-0.0").
TEST(Convert, WritesJsonNumbersInTheFewestDigits) {
  const std::pair<double, std::string> cases[] = {
      {1e23, "1e+23"},       {8.41e21, "8.41e+21"},  {0.0008, "0.0008"},   {1e-7, "1e-07"},
      {-0.0, "-0.0"},        {0.1, "0.1"},           {-2.5e-7, "-2.5e-07"}, {0.000008, "0.000008"},
      {1.0 / 3.0, "0.3333333333333333"}, {1e16, "1e+16"}, {2.5, "2.5"},   {1e300, "1e+300"}};
  for (const auto& [v, expected] : cases) {
    SCOPED_TRACE(expected);
    const std::string text = "plane p { material m normal 0 1 0 point " + format_number(v) +
                             " 7 7 }\nmaterial m { ambient 1 }\n";
    const std::string json = write_json(model_desc(text));
    EXPECT_NE(json.find("\n        " + expected + ",\n"), std::string::npos) << json;
    const SceneDesc back = json_desc(json);
    EXPECT_TRUE(same_bits(back.entities[0].attrs[2].numbers[0], v));
  }
}

TEST(Convert, KeepsAOneNumberColourAsOneNumber) {
  SceneDesc original = model_desc("material m { ambient 2 diffuse 0.5 0.25 0 }\n");
  std::string json = write_json(original);
  EXPECT_TRUE(contains(json, "\"ambient\": 2,")) << json;
  std::string model = write_model(json_desc(json));
  EXPECT_TRUE(contains(model, "   ambient 2\n")) << model;
  EXPECT_TRUE(contains(model, "   diffuse 0.5 0.25 0\n")) << model;
}

TEST(Convert, WritesOneUnnamedCameraAsCamera) {
  std::string json = write_json(model_desc("camera { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }"));
  EXPECT_TRUE(contains(json, "\"camera\": {")) << json;
  EXPECT_FALSE(contains(json, "\"cameras\"")) << json;
}

TEST(Convert, WritesNamedCamerasUnderCamerasInOrder) {
  SceneDesc original = model_desc(
      "camera front { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
      "camera back { pixeldim 4 3 worlddim 8 6 viewpoint 4 3 -5 }\n");
  std::string json = write_json(original);
  EXPECT_TRUE(contains(json, "\"cameras\": {")) << json;
  Scene s = build(json_desc(json));
  ASSERT_EQ(s.cameras.size(), 2u);
  EXPECT_EQ(s.cameras[0].name, "front");
  EXPECT_EQ(s.cameras[1].name, "back");
}

TEST(Convert, GivesUnnamedCamerasNamesThatClashWithNoOther) {
  SceneDesc original = model_desc(
      "camera { pixeldim 1 1 worlddim 8 6 viewpoint 0 0 1 }\n"
      "camera camera1 { pixeldim 2 2 worlddim 8 6 viewpoint 0 0 2 }\n"
      "camera { pixeldim 3 3 worlddim 8 6 viewpoint 0 0 3 }\n");
  Scene s = build(json_desc(write_json(original)));
  ASSERT_EQ(s.cameras.size(), 3u);
  EXPECT_EQ(s.cameras[0].width, 1);
  EXPECT_EQ(s.cameras[1].name, "camera1");
  EXPECT_EQ(s.cameras[1].width, 2);
  EXPECT_EQ(s.cameras[2].width, 3);
  EXPECT_NE(s.cameras[0].name, s.cameras[2].name);
}

TEST(Convert, KeepsRenderOptionsThroughJson) {
  SceneDesc original = json_desc(R"({"cameras": {
      "a": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
      "b": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 9]}},
      "render": {"spp": 16, "seed": 18446744073709551615, "max_dist": 0.1, "shadows": false,
                 "background": [0.1, 0.2, 0.3], "camera": "b", "highlight": "blinn",
                 "bailout": 1e-3}})");
  std::string json = write_json(original);
  SceneDesc back = json_desc(json);
  RenderOptions a, b;
  Diagnostics diags;
  apply_options(a, original.render, diags);
  apply_options(b, back.render, diags);
  EXPECT_FALSE(diags.has_errors()) << dump(diags);
  EXPECT_EQ(a, b);
  EXPECT_EQ(b.seed, 18446744073709551615u);
  EXPECT_EQ(b.camera, "b");
  EXPECT_EQ(b.max_dist, 0.1);
  EXPECT_EQ(write_json(back), json);
}

TEST(Convert, KeepsA64BitSeedExact) {
  SceneDesc desc;
  desc.render.push_back({"seed", "12345678901234567", {}});
  desc.render.push_back({"background", "0.5 0.25 1", {}});
  SceneDesc back = json_desc(write_json(desc));
  RenderOptions a, b;
  Diagnostics diags;
  apply_options(a, desc.render, diags);
  apply_options(b, back.render, diags);
  EXPECT_FALSE(diags.has_errors()) << dump(diags);
  EXPECT_EQ(b.seed, 12345678901234567u);
  EXPECT_EQ(a, b);
}

TEST(Convert, HandlesFiftyThousandMaterialsInLinearTime) {
  // Once quadratic: ordered_json finds keys by linear search (100,000 materials took 20 s to
  // read and 11 s to write; 50,000 some 8 s). Timed against reading the same scene as a
  // model file, so that sanitizers and machine load mostly cancel out; the margin is wide
  // (AddressSanitizer slows JSON's many small blocks most: 14 times the model file's time on
  // a loaded machine), and a quadratic pass is still far beyond it.
  const int n = 50000;
  std::string text = "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n";
  for (int i = 0; i < n; ++i)
    text += "material m" + std::to_string(i) + " { diffuse 1 }\nsphere { material m" +
            std::to_string(i) + " center 0 0 -5 radius 1 }\n";
  auto start = std::chrono::steady_clock::now();
  SceneDesc desc = model_desc(text);
  auto model_time = std::chrono::steady_clock::now() - start;
  start = std::chrono::steady_clock::now();
  SceneDesc back = json_desc(write_json(desc));
  auto json_time = std::chrono::steady_clock::now() - start;
  EXPECT_LT(json_time, 25 * model_time + std::chrono::seconds(3));
  Scene s = build(back);
  ASSERT_EQ(s.materials.size(), static_cast<size_t>(n));
  EXPECT_EQ(s.materials[n - 1].name, "m" + std::to_string(n - 1));
  EXPECT_EQ(test::nth<Sphere>(s, n - 1).material, n - 1);
}

// --- POV-Ray --------------------------------------------------------------------------------

// A texture's path is a POV-Ray string: escaped, and its image type by its extension.
TEST(Convert, ExportsATexturePathAsAnEscapedPovString) {
  const Scene scene = build(model_desc(std::string(kLecture) +
                                       "texplane wall { material floor normal 0 0 1 point 0 0 -9 "
                                       "xdir 1 0 0 dimensions 4 4 texname a\"b\\c.PNG mode 0 }\n"
                                       "texplane floor2 { material floor normal 0 1 0 point 0 -9 0 "
                                       "xdir 1 0 0 dimensions 4 4 texname plain.ppm mode 0 }\n"));
  const std::string pov = write_pov(scene, RenderOptions{});
  EXPECT_TRUE(contains(pov, R"(image_map { png "a\"b\\c.PNG" once })")) << pov;
  EXPECT_TRUE(contains(pov, R"(image_map { ppm "plain.ppm" once })")) << pov;
}

// Values that overflow on the way to SDL (a highlight from a specular of 1e308, a texture's
// scale from dimensions of 1e149) are written as the largest double, never `inf`, which
// POV-Ray cannot parse.
TEST(Convert, ExportsNoInfiniteNumberToPov) {
  const Scene scene = build(model_desc(
      "camera c { pixeldim 40 30 worlddim 8 6 viewpoint 4 3 5 }\n"
      "material m { diffuse 1 specular 1e308 }\nlight { location 4 3 2 }\n"
      "sphere s { material m center 4 3 -4 radius 2 }\n"
      "texplane t { material m normal 0 0 1 point 0 0 -9 xdir 1 0 0 dimensions 1e149 1e149 "
      "texname a.ppm }\n"));
  const std::string pov = write_pov(scene, RenderOptions{});
  EXPECT_FALSE(contains(pov, "inf")) << pov;
  EXPECT_TRUE(contains(pov, "1.7976931348623157e+308")) << pov;
}

TEST(Convert, ExportsTheCameraToPovWithZNegated) {
  std::string pov = write_pov(build(model_desc(kLecture)), RenderOptions{});
  EXPECT_TRUE(contains(pov, "#version 3.7;")) << pov;
  EXPECT_TRUE(contains(pov,
                       "camera {\n  perspective\n  location <4, 3, -5>\n"
                       "  direction <0, 0, 5>\n"))
      << pov;
  EXPECT_TRUE(contains(pov, "+W800 +H600")) << pov;
}

TEST(Convert, ExportsEverySphereLightAndPlaneToPovWithZNegated) {
  std::string pov = write_pov(build(model_desc(kLecture)), RenderOptions{});
  EXPECT_TRUE(contains(pov, "sphere { <1.25, 0.75, 4>, 0.9 texture { M0 } }")) << pov;
  EXPECT_TRUE(contains(pov, "sphere { <4, 1.2, 5>, 1.2 texture { M1 } }")) << pov;
  EXPECT_TRUE(contains(pov, "sphere { <6.5, 1, 3.5>, 1 texture { M2 } }")) << pov;
  EXPECT_TRUE(contains(pov, "light_source { <2.56, 3.8, 1.5> color rgb <4, 4, 4>")) << pov;
  EXPECT_TRUE(contains(pov, "light_source { <7, 5, -1> color rgb <3, 3, 3>")) << pov;
  EXPECT_TRUE(contains(pov, "plane { <0, 1, 0>, -0.2 texture { M3 } }")) << pov;
}

TEST(Convert, ExportsTheRecursionDepthAsMaxTraceLevel) {
  Scene s = build(model_desc(kLecture));
  EXPECT_TRUE(contains(write_pov(s, RenderOptions{}), "max_trace_level 9 "));
  RenderOptions shallow;
  shallow.max_depth = 0;
  EXPECT_TRUE(contains(write_pov(s, shallow), "max_trace_level 1 "));
}

TEST(Convert, ExportsReflectionOnlyForSpecularMaterials) {
  std::string pov = write_pov(build(model_desc(kLecture)), RenderOptions{});
  auto block = [&](std::string_view name) {
    size_t at = pov.find(std::string("// ") + std::string(name) + "\n");
    EXPECT_NE(at, std::string::npos) << name;
    return pov.substr(at, pov.find("\n}\n", at) - at);
  };
  EXPECT_TRUE(contains(block("chrome"), "reflection { <0.9, 0.9, 0.9> }")) << block("chrome");
  EXPECT_TRUE(contains(block("blue"), "reflection { <0.2, 0.2, 0.2> }")) << block("blue");
  EXPECT_FALSE(contains(block("red"), "reflection")) << block("red");
  EXPECT_FALSE(contains(block("floor"), "reflection")) << block("floor");
}

TEST(Convert, ExportsShadowlessLightsAndTheChosenCamera) {
  Scene s =
      build(model_desc("camera a { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
                       "camera b { pixeldim 8 6 worlddim 8 6 viewpoint 1 2 9 }\n"
                       "light { location 0 0 0 }\n"));
  RenderOptions options;
  options.shadows = false;
  options.camera = "b";
  std::string pov = write_pov(s, options);
  EXPECT_TRUE(contains(pov, "location <1, 2, -9>")) << pov;
  EXPECT_TRUE(contains(pov, " shadowless }")) << pov;
}

// --- Lint -----------------------------------------------------------------------------------

std::vector<Diagnostic> lint(std::string_view text, RenderOptions options = {}) {
  LoadedScene loaded = load_scene(text);
  EXPECT_TRUE(loaded.scene.has_value()) << dump(loaded.diags);
  Diagnostics diags;
  if (loaded.scene) lint_scene(*loaded.scene, options, diags);
  EXPECT_FALSE(diags.has_errors());
  return diags.items();
}

std::vector<std::string> codes(const std::vector<Diagnostic>& ds) {
  std::vector<std::string> out;
  for (const Diagnostic& d : ds) out.push_back(d.code);
  return out;
}

constexpr std::string_view kLitHead =
    "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
    "material m { diffuse 1 }\n"
    "light sun { location 4 10 0 }\n";

std::string lit(std::string_view body) { return std::string(kLitHead) + std::string(body); }

TEST(Lint, FindsNothingWrongWithTheLectureScene) {
  EXPECT_EQ(codes(lint(kLecture)), std::vector<std::string>{});
}

TEST(Lint, WarnsOfALightInsideASphereAtTheLight) {
  auto warnings =
      lint(lit("sphere ball { material m center 4 3 -5 radius 2 }\n"
               "light bulb { location 4 3.5 -5 }\n"));
  ASSERT_EQ(codes(warnings), std::vector<std::string>{"light-inside-sphere"});
  EXPECT_EQ(warnings[0].severity, Severity::warning);
  EXPECT_EQ(warnings[0].where.line, 5);
  EXPECT_EQ(warnings[0].message,
            "light 'bulb' is inside sphere 'ball': it lights only that "
            "sphere's inside");
}

TEST(Lint, WarnsOfTheEyeInsideASphere) {
  auto warnings = lint(lit("sphere dome { material m center 4 3 4 radius 3 }\n"));
  ASSERT_EQ(codes(warnings), std::vector<std::string>{"eye-inside-sphere"});
  EXPECT_EQ(warnings[0].where.line, 4);
  EXPECT_EQ(warnings[0].message, "the eye of camera 'c' is inside sphere 'dome'");
}

TEST(Lint, WarnsOfAnObjectBehindTheEye) {
  auto warnings =
      lint(lit("sphere front { material m center 4 3 -5 radius 1 }\n"
               "sphere back { material m center 4 3 10 radius 1 }\n"));
  ASSERT_EQ(codes(warnings), std::vector<std::string>{"behind-eye"});
  EXPECT_EQ(warnings[0].where.line, 5);
  EXPECT_EQ(warnings[0].message,
            "sphere 'back' is behind the eye of camera 'c' and cannot be seen directly");
}

TEST(Lint, DoesNotCallASphereThatReachesPastTheEyeBehindIt) {
  EXPECT_EQ(codes(lint(lit("sphere big { material m center 4 6 6 radius 3 }\n"))),
            std::vector<std::string>{});
}

TEST(Lint, WarnsOfAnUnusedMaterialAtItsDefinition) {
  auto warnings =
      lint(lit("material gold { specular 1 }\n"
               "sphere s { material m center 4 3 -5 radius 1 }\n"));
  ASSERT_EQ(codes(warnings), std::vector<std::string>{"unused-material"});
  EXPECT_EQ(warnings[0].where.line, 4);
  EXPECT_EQ(warnings[0].message, "material 'gold' is never used");
}

TEST(Lint, WarnsThatNothingIsLitWithoutLightsOrAmbient) {
  auto warnings = lint(
      "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
      "material m { diffuse 1 specular 1 }\n"
      "sphere s { material m center 4 3 -5 radius 1 }\n");
  ASSERT_EQ(codes(warnings), std::vector<std::string>{"black-image"});
  EXPECT_EQ(warnings[0].message,
            "nothing is lit: there are no lights and no ambient colour, "
            "the image is entirely black");
}

TEST(Lint, WarnsThatNothingIsLitWhenEveryLightIsBlack) {
  auto warnings = lint(
      "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
      "material m { diffuse 1 }\n"
      "light { location 0 9 0 emissivity 0 }\n"
      "sphere s { material m center 4 3 -5 radius 1 }\n");
  ASSERT_EQ(codes(warnings), std::vector<std::string>{"black-image"});
  EXPECT_TRUE(contains(warnings[0].message, "every light has zero emissivity"));
}

TEST(Lint, DoesNotWarnOfDarknessWhenAmbientOrBackgroundShows) {
  constexpr std::string_view unlit_ambient =
      "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
      "material m { ambient 1 }\n"
      "sphere s { material m center 4 3 -5 radius 1 }\n";
  EXPECT_EQ(codes(lint(unlit_ambient)), std::vector<std::string>{});
  constexpr std::string_view unlit =
      "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
      "material m { diffuse 1 }\n"
      "sphere s { material m center 4 3 -5 radius 1 }\n";
  RenderOptions grey;
  grey.background = {0.5, 0.5, 0.5};
  EXPECT_EQ(codes(lint(unlit, grey)), std::vector<std::string>{});
}

TEST(Lint, WarnsOfAnEmptyScene) {
  auto warnings = lint("camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n");
  ASSERT_EQ(codes(warnings), std::vector<std::string>{"black-image"});
  EXPECT_TRUE(contains(warnings[0].message, "no objects"));
}

TEST(Lint, WarnsOfACameraOptionNamingNoCamera) {
  RenderOptions options;
  options.camera = "side";
  EXPECT_EQ(codes(lint(kLecture, options)), std::vector<std::string>{"unknown-camera"});
}

TEST(Lint, ChecksTheChosenCamera) {
  std::string text =
      lit("camera inside { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 -5 }\n"
          "sphere s { material m center 4 3 -5 radius 1 }\n");
  EXPECT_EQ(codes(lint(text)), std::vector<std::string>{});
  RenderOptions options;
  options.camera = "inside";
  EXPECT_EQ(codes(lint(text, options)), std::vector<std::string>{"eye-inside-sphere"});
}

// The one lint that is an error: render would refuse the image, so check must not say "ok".
// --precision float holds the lecture scene at 1e17 times its size and loses it past 1e18
// (squares of lengths overflow), and at a window under 1e-18 (they underflow). The warning
// names the entity with the largest length, whatever its kind.
TEST(Lint, WarnsOfLengthsFloatPrecisionCannotSquare) {
  RenderOptions f;
  f.precision = Precision::f32;
  EXPECT_TRUE(lint(lit("sphere s { material m center 1 2 -3 radius 1 }\n"), f).empty());
  const std::string far = lit("sphere s { material m center 1 2 -3 radius 1 }\n"
                              "triangle t { material m vertex1 0 0 -5e18 vertex2 1e18 0 -5e18 "
                              "vertex3 0 1e18 -5e18 }\n");
  const auto ds = lint(far, f);
  ASSERT_EQ(codes(ds), std::vector<std::string>{"float-range"});
  EXPECT_NE(ds[0].message.find("triangle 't' reaches 5e+18"), std::string::npos) << ds[0].message;
  EXPECT_EQ(ds[0].where.line, 5);
  EXPECT_TRUE(lint(far).empty()) << "double precision holds it";
  const std::string light = lit("light far { location 0 0 3e18 }\n"
                                "sphere s { material m center 1 2 -3 radius 1 }\n");
  EXPECT_EQ(codes(lint(light, f)), std::vector<std::string>{"float-range"});
  const auto tiny = lint("camera c { pixeldim 8 6 worlddim 8e-20 6e-20 viewpoint 4e-20 3e-20 "
                         "5e-20 }\nmaterial m { diffuse 1 }\nlight l { location 0 1e-19 0 }\n"
                         "sphere s { material m center 4e-20 3e-20 -5e-20 radius 1e-20 }\n",
                         f);
  ASSERT_EQ(codes(tiny), std::vector<std::string>{"float-range"});
  EXPECT_NE(tiny[0].message.find("6e-20 wide"), std::string::npos) << tiny[0].message;
}

TEST(Lint, AnImageTooLargeToRenderIsAnErrorAtItsCamera) {
  auto errors_of = [](std::string_view text, const RenderOptions& options) {
    LoadedScene loaded = load_scene(text);
    EXPECT_TRUE(loaded.scene.has_value()) << dump(loaded.diags);
    Diagnostics diags;
    if (loaded.scene) lint_scene(*loaded.scene, options, diags);
    std::vector<Diagnostic> out;
    for (const Diagnostic& d : diags.items())
      if (d.severity == Severity::error) out.push_back(d);
    return out;
  };
  const std::string huge = "material m { ambient 1 }\n"
                           "camera wide { pixeldim 65535 65535 worlddim 8 6 viewpoint 4 3 5 }\n"
                           "sphere s { material m center 4 3 -5 radius 1 }\n";
  auto errors = errors_of(huge, {});
  ASSERT_EQ(codes(errors), std::vector<std::string>{"image-too-large"});
  EXPECT_EQ(errors[0].where.line, 2);
  EXPECT_TRUE(contains(errors[0].message, "camera 'wide'")) << errors[0].message;
  EXPECT_TRUE(contains(errors[0].message, "4294836225 pixels (65535 x 65535)")) << errors[0].message;
  EXPECT_TRUE(contains(errors[0].message, "--width and --height")) << errors[0].message;
  // Rendered smaller, the same camera is fine; the limit is render_image's own.
  RenderOptions small;
  small.width = 800;
  small.height = 600;
  EXPECT_TRUE(errors_of(huge, small).empty());
  std::string error;
  EXPECT_FALSE(check_render(*load_scene(huge).scene, {}, &error).has_value());
  EXPECT_TRUE(contains(error, "4294836225 pixels")) << error;
  // With spp above 1 the sums count too: 8000 x 8000 fits alone, not sampled.
  const std::string big = "material m { ambient 1 }\n"
                          "camera c { pixeldim 8000 8000 worlddim 8 6 viewpoint 4 3 5 }\n"
                          "sphere s { material m center 4 3 -5 radius 1 }\n";
  EXPECT_TRUE(errors_of(big, {}).empty());
  RenderOptions sampled;
  sampled.spp = 4;
  ASSERT_EQ(codes(errors_of(big, sampled)), std::vector<std::string>{"image-too-large"});
  EXPECT_TRUE(contains(errors_of(big, sampled)[0].message, "with spp > 1"));
  // Every camera is rendered with --camera: one too large at its own size is an error at it,
  // whichever camera is the default; a size asked for is one error, not one per camera.
  const std::string two = "material m { ambient 1 }\n"
                          "camera a { pixeldim 64 48 worlddim 8 6 viewpoint 4 3 5 }\n"
                          "camera b { pixeldim 65535 65535 worlddim 8 6 viewpoint 4 3 5 }\n"
                          "sphere s { material m center 4 3 -5 radius 1 }\n";
  const auto second = errors_of(two, {});
  ASSERT_EQ(codes(second), std::vector<std::string>{"image-too-large"});
  EXPECT_EQ(second[0].where.line, 3);
  EXPECT_TRUE(contains(second[0].message, "camera 'b'")) << second[0].message;
  EXPECT_TRUE(errors_of(two, small).empty());
  RenderOptions huge_size;
  huge_size.width = huge_size.height = 65535;
  EXPECT_EQ(errors_of(two, huge_size).size(), 1u);

  // A JSON scene's render block that asks for the size is where the error points.
  const std::string json = R"({"camera": {"pixeldim": [40, 30], "worlddim": [8, 6],
      "viewpoint": [4, 3, 5]}, "materials": {"m": {"ambient": 1}},
      "objects": [{"type": "sphere", "material": "m", "center": [4, 3, -5], "radius": 1}],
      "render": {"width": 65535, "height": 60000}})";
  LoadedScene loaded = load_scene(json);
  ASSERT_TRUE(loaded.scene.has_value()) << dump(loaded.diags);
  RenderOptions asked;
  apply_options(asked, loaded.scene->render, loaded.diags);
  const auto from_block = errors_of(json, asked);
  ASSERT_EQ(codes(from_block), std::vector<std::string>{"image-too-large"});
  EXPECT_EQ(from_block[0].where.path, "/render/width");
  // Overridden on the command line, the block's width no longer gives it; its height does.
  asked.width = 65000;
  EXPECT_EQ(errors_of(json, asked)[0].where.path, "/render/height");
  // A block that asks for nothing larger than the default is not the cause.
  std::string plain = json;
  plain.replace(plain.find("\"width\": 65535, \"height\": 60000"), 31, "\"spp\": 1");
  LoadedScene one = load_scene(plain);
  ASSERT_TRUE(one.scene.has_value()) << dump(one.diags) << plain;
  RenderOptions wide;
  apply_options(wide, one.scene->render, one.diags);
  wide.width = wide.height = 65535;
  const auto from_command = errors_of(plain, wide);
  ASSERT_EQ(codes(from_command), std::vector<std::string>{"image-too-large"});
  EXPECT_EQ(from_command[0].where, Where{});
}

}  // namespace
}  // namespace rayfarm
