// The JSON scene format (docs/json-format.md): the same scene as a model file, errors by JSON path,
// syntax errors by line and column, render options, and hostile input.
#include "rayfarm/json_scene.h"

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "format/json_tree.h"
#include "rayfarm/load.h"
#include "test_util.h"
#include "util/lines.h"

namespace rayfarm {
namespace {

using test::expect_same_scene;

// The lecture scene, as bundled in scenes/.
const std::string kLectureModel = test::lecture_scene();

constexpr std::string_view kLectureJson = R"({
  "cameras": {"cam1": {"pixeldim": [800, 600], "worlddim": [8, 6], "viewpoint": [4, 3, 5]}},
  "materials": {
    "chrome": {"ambient": [3, 3, 3], "diffuse": [0.1, 0.1, 0.1], "specular": [0.9, 0.9, 0.9]},
    "red": {"ambient": [6, 1, 1], "diffuse": [0.8, 0.1, 0.1], "specular": [0, 0, 0]},
    "blue": {"ambient": [1, 1, 6], "diffuse": [0.1, 0.2, 0.8], "specular": [0.2, 0.2, 0.2],
             "shininess": 8},
    "floor": {"ambient": [2, 2, 2], "diffuse": [0.5, 0.5, 0.5]}
  },
  "lights": [{"name": "top", "location": [2.56, 3.8, -1.5], "emissivity": [4, 4, 4]},
             {"name": "side", "location": [7, 5, 1], "emissivity": [3, 3, 3]}],
  "objects": [
    {"type": "sphere", "name": "left", "material": "chrome", "center": [1.25, 0.75, -4],
     "radius": 0.9},
    {"type": "sphere", "name": "middle", "material": "red", "center": [4, 1.2, -5],
     "radius": 1.2},
    {"type": "sphere", "name": "right", "material": "blue", "center": [6.5, 1, -3.5],
     "radius": 1},
    {"type": "plane", "name": "ground", "material": "floor", "normal": [0, 1, 0],
     "point": [0, -0.2, 0]}
  ]
}
)";

// A small valid scene whose one sphere (at /objects/0) the tests spoil.
std::string scene_with_sphere(std::string_view sphere_fields, std::string_view extra = "") {
  return R"({"camera": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
 "materials": {"m": {"diffuse": 1}, "chrome": {"specular": [1, 1, 1]}},
 "objects": [{"type": "sphere", )" +
         std::string(sphere_fields) + "}]" + std::string(extra) + "}\n";
}

constexpr std::string_view kGoodSphere = R"("material": "m", "center": [0, 0, -5], "radius": 1)";

std::string dump(const Diagnostics& diags) {
  std::string out;
  for (const Diagnostic& d : diags.items())
    out += d.where.path + " " + std::to_string(d.where.line) + ":" +
           std::to_string(d.where.column) + " " + d.code + ": " + d.message + "\n";
  return out;
}

std::vector<Diagnostic> errors_of(const Diagnostics& diags) {
  std::vector<Diagnostic> out;
  for (const Diagnostic& d : diags.items())
    if (d.severity == Severity::error) out.push_back(d);
  return out;
}

Diagnostic single_error(std::string_view text) {
  EXPECT_EQ(detect_format(text), SceneFormat::json);
  LoadedScene loaded = load_scene(text);
  std::vector<Diagnostic> errors = errors_of(loaded.diags);
  EXPECT_EQ(errors.size(), 1u) << "for input:\n" << text << "\ngot:\n" << dump(loaded.diags);
  EXPECT_FALSE(loaded.scene.has_value());
  return errors.empty() ? Diagnostic{} : errors[0];
}

::testing::AssertionResult is_diag(const Diagnostic& d, std::string_view code,
                                   std::string_view path, std::string_view text) {
  if (d.code == code && d.where.path == path && d.message.find(text) != std::string::npos)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "got " << d.where.path << " " << d.code << ": " << d.message << "\nwant " << path << " "
         << code << ": ..." << text << "...";
}

Scene scene_of(std::string_view text) {
  LoadedScene loaded = load_scene(text);
  EXPECT_TRUE(loaded.scene.has_value()) << dump(loaded.diags);
  return loaded.scene.value_or(Scene{});
}

// --- The same scene -------------------------------------------------------------------------

TEST(JsonScene, GivesTheSameSceneAsTheModelFile) {
  Scene from_json = scene_of(kLectureJson);
  Scene from_model = scene_of(kLectureModel);
  expect_same_scene(from_json, from_model);
  EXPECT_EQ(from_json.count<Sphere>(), 3u);
  EXPECT_EQ(from_json.materials[2].shininess, 8.0);
}

TEST(JsonScene, DetectsJsonByItsFirstNonBlankCharacter) {
  EXPECT_EQ(detect_format(" \r\n\t{}"), SceneFormat::json);
  EXPECT_EQ(detect_format("camera {"), SceneFormat::model);
  EXPECT_EQ(detect_format("# {\n"), SceneFormat::model);
  EXPECT_EQ(detect_format(""), SceneFormat::model);
  // No model file begins with these: JSON of the wrong shape, refused as such.
  EXPECT_EQ(detect_format(" [{}]"), SceneFormat::json);
  EXPECT_EQ(detect_format("\"camera\""), SceneFormat::json);
  for (std::string_view text : {R"([{"camera": {}}])", R"("a scene")"}) {
    LoadedScene loaded = load_scene(text);
    ASSERT_EQ(loaded.diags.items().size(), 1u) << dump(loaded.diags);
    EXPECT_EQ(loaded.diags.items()[0].code, "json-type");
  }
}

TEST(JsonScene, SkipsAByteOrderMark) {
  std::string bom = "\xEF\xBB\xBF";
  EXPECT_EQ(detect_format(bom + " {}"), SceneFormat::json);
  Scene s = scene_of(bom + scene_with_sphere(kGoodSphere));
  EXPECT_EQ(s.count<Sphere>(), 1u);
  Diagnostic d = single_error(bom + "{,}");
  EXPECT_EQ(d.code, "json-syntax");
  EXPECT_EQ(d.where.line, 1);
  EXPECT_EQ(d.where.column, 2);
}

TEST(JsonScene, ReadsASingleCameraAsUnnamed) {
  Scene s = scene_of(scene_with_sphere(kGoodSphere));
  ASSERT_EQ(s.cameras.size(), 1u);
  EXPECT_EQ(s.cameras[0].name, "");
  EXPECT_EQ(s.cameras[0].width, 8);
}

TEST(JsonScene, KeepsTheOrderOfCamerasSoTheFirstIsTheDefault) {
  Scene s = scene_of(R"({"cameras": {
      "zeta": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
      "alpha": {"pixeldim": [4, 3], "worlddim": [8, 6], "viewpoint": [4, 3, 9]},
      "mid": {"pixeldim": [2, 1], "worlddim": [8, 6], "viewpoint": [4, 3, 7]}}})");
  ASSERT_EQ(s.cameras.size(), 3u);
  EXPECT_EQ(s.cameras[0].name, "zeta");
  EXPECT_EQ(s.cameras[1].name, "alpha");
  EXPECT_EQ(s.cameras[2].name, "mid");
  EXPECT_EQ(s.find_camera(""), 0);
  EXPECT_EQ(s.find_camera("mid"), 2);
}

TEST(JsonScene, AcceptsOneNumberForAColourOrARadius) {
  Scene s = scene_of(scene_with_sphere(R"("material": "m", "center": [0, 0, -5], "radius": [2])"));
  EXPECT_EQ(test::shape<Sphere>(s, 0).radius, 2.0);
  EXPECT_EQ(s.materials[0].diffuse, glm::dvec3(1, 1, 1));
}

TEST(JsonScene, AcceptsIntegersWrittenAsFloats) {
  Scene s = scene_of(R"({"camera": {"pixeldim": [8.0, 6e0], "worlddim": [8, 6],
                         "viewpoint": [4, 3, 5]}})");
  EXPECT_EQ(s.cameras[0].width, 8);
  EXPECT_EQ(s.cameras[0].height, 6);
}

TEST(JsonScene, RecordsTheJsonPathOfEveryEntityAndValue) {
  Diagnostics diags;
  SceneDesc desc = parse_json_scene(scene_with_sphere(kGoodSphere), diags);
  ASSERT_FALSE(diags.has_errors()) << dump(diags);
  ASSERT_EQ(desc.entities.size(), 4u);
  const EntityDesc& sphere = desc.entities[3];
  EXPECT_EQ(sphere.kind, EntityKind::sphere);
  EXPECT_EQ(sphere.where.path, "/objects/0");
  const AttrDesc* center = sphere.find("center");
  ASSERT_NE(center, nullptr);
  EXPECT_EQ(center->where.path, "/objects/0/center");
  ASSERT_EQ(center->value_where.size(), 3u);
  EXPECT_EQ(center->value_at(2).path, "/objects/0/center/2");
  EXPECT_EQ(desc.entities[1].where.path, "/materials/m");
}

// --- Errors by path -------------------------------------------------------------------------

TEST(JsonScene, ReportsAnUnknownKeyWithASuggestionAndNotAlsoTheMissingOne) {
  Diagnostic d =
      single_error(scene_with_sphere(R"("material": "m", "center": [0, 0, -5], "radious": 1)"));
  EXPECT_TRUE(is_diag(d, "unknown-key", "/objects/0/radious", "unknown key \"radious\""));
  EXPECT_TRUE(is_diag(d, "unknown-key", "/objects/0/radious", "did you mean \"radius\"?"));
}

TEST(JsonScene, ListsTheKeysAnEntityAccepts) {
  Diagnostic d =
      single_error(scene_with_sphere(kGoodSphere, R"(, "lights": [{"position": [0, 0, 0]}])"));
  EXPECT_TRUE(is_diag(d, "unknown-key", "/lights/0/position",
                      "(expected one of: location, emissivity, name, type)"));
}

TEST(JsonScene, ReportsAnUnknownTopLevelKey) {
  Diagnostic d = single_error(scene_with_sphere(kGoodSphere, R"(, "light": [])"));
  EXPECT_TRUE(is_diag(d, "unknown-key", "/light", "did you mean \"lights\"?"));
}

// A misspelt "camera" or "materials", or a camera or material that is not an object, is one
// error, as a misspelt keyword is in a model file: not also "no camera" or "undefined
// material" for what it held.
TEST(JsonScene, AMisspeltOrMistypedCameraOrMaterialsIsOneError) {
  const std::string camera = R"({"pixeldim": [4, 3], "worlddim": [8, 6], "viewpoint": [4, 3, 5]})";
  const std::string objects =
      R"("objects": [{"type": "sphere", "material": "m", "center": [4, 3, -4], "radius": 1}])";
  const std::string materials = R"({"m": {"ambient": 1}})";
  struct Case {
    std::string text, code, path, message;
  };
  const Case cases[] = {
      {"{\"camra\": " + camera + ", \"materials\": " + materials + ", " + objects + "}",
       "unknown-key", "/camra", "did you mean \"camera\"?"},
      {"{\"cameras\": {\"a\": []}, \"materials\": " + materials + ", " + objects + "}",
       "json-type", "/cameras/a", "expected an object, got an array"},
      {"{\"camera\": [], \"materials\": " + materials + ", " + objects + "}", "json-type",
       "/camera", "expected an object, got an array"},
      {"{\"camera\": " + camera + ", \"materals\": " + materials + ", " + objects + "}",
       "unknown-key", "/materals", "did you mean \"materials\"?"},
      {"{\"camera\": " + camera + ", \"materials\": {\"m\": 5}, " + objects + "}",
       "json-type", "/materials/m", "expected an object, got a number"},
      // Containers of the wrong type: an array of cameras, materials written as the lights
      // and objects are (an array of named objects).
      {"{\"cameras\": [], \"materials\": " + materials + ", " + objects + "}", "json-type",
       "/cameras", "expected an object of named cameras, got an array"},
      {"{\"camera\": " + camera + ", \"materials\": [{\"name\": \"m\", \"ambient\": 1}], " +
           objects + "}",
       "json-type", "/materials", "expected an object of named materials, got an array"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    EXPECT_TRUE(is_diag(single_error(c.text), c.code, c.path, c.message));
  }
}

TEST(JsonScene, ReportsATypeThatIsNotAString) {
  Diagnostic d = single_error(scene_with_sphere(kGoodSphere, R"(, "lights": [{"type": 5}])"));
  EXPECT_TRUE(is_diag(d, "json-type", "/lights/0/type", "expected a string: \"light\""));
}

TEST(JsonScene, ReportsAValueOfTheWrongType) {
  Diagnostic d =
      single_error(scene_with_sphere(R"("material": "m", "center": [0, 0, -5], "radius": "1")"));
  EXPECT_TRUE(is_diag(d, "json-type", "/objects/0/radius", "expected 1 number > 0, got a string"));
}

TEST(JsonScene, ReportsANumberWhereAnArrayBelongs) {
  Diagnostic d = single_error(scene_with_sphere(R"("material": "m", "center": 5, "radius": 1)"));
  EXPECT_TRUE(is_diag(d, "json-type", "/objects/0/center", "expected 3 numbers, got a number"));
}

TEST(JsonScene, ReportsAWrongElementAtItsIndex) {
  Diagnostic d =
      single_error(scene_with_sphere(R"("material": "m", "center": [0, true, -5], "radius": 1)"));
  EXPECT_TRUE(is_diag(d, "json-type", "/objects/0/center/1", "expected a number, got a boolean"));
}

TEST(JsonScene, ReportsAMaterialThatIsNotAString) {
  Diagnostic d =
      single_error(scene_with_sphere(R"("material": 3, "center": [0, 0, -5], "radius": 1)"));
  EXPECT_TRUE(
      is_diag(d, "json-type", "/objects/0/material", "expected a material name, got a number"));
}

TEST(JsonScene, ReportsASectionOfTheWrongType) {
  Diagnostic d = single_error(scene_with_sphere(kGoodSphere, R"(, "lights": {})"));
  EXPECT_TRUE(is_diag(d, "json-type", "/lights", "expected an array of lights, got an object"));
}

TEST(JsonScene, ReportsARootThatIsNotAnObject) {
  Diagnostics diags;
  parse_json_scene("[1, 2]", diags);
  ASSERT_EQ(diags.items().size(), 1u);
  EXPECT_TRUE(
      is_diag(diags.items()[0], "json-type", "", "a scene must be a JSON object, not an array"));
}

TEST(JsonScene, ReportsAWrongArrayLength) {
  Diagnostic d =
      single_error(scene_with_sphere(R"("material": "m", "center": [0, 0], "radius": 1)"));
  EXPECT_TRUE(
      is_diag(d, "value-count", "/objects/0/center", "\"center\" takes 3 numbers, got 2 values"));
}

TEST(JsonScene, RejectsAColourOfTwoNumbers) {
  Diagnostic d =
      single_error(R"({"camera": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
                                 "materials": {"m": {"ambient": [1, 1]}}})");
  EXPECT_TRUE(is_diag(d, "value-count", "/materials/m/ambient",
                      "takes 3 numbers >= 0, or 1 number for all three, got 2 values"));
}

TEST(JsonScene, ReportsOutOfRangeValuesAtTheirPath) {
  struct Case {
    std::string sphere;
    std::string path;
    std::string message;
  };
  const Case cases[] = {
      {R"("material": "m", "center": [0, 0, -5], "radius": 0)", "/objects/0/radius",
       "'radius' must be > 0, got 0"},
      {R"("material": "m", "center": [0, 0, -5], "radius": -2.5)", "/objects/0/radius",
       "'radius' must be > 0, got -2.5"},
      {R"("material": "m", "center": [0, 0, -5], "radius": [1e-400])", "/objects/0/radius/0",
       "'radius' must be > 0, got 0"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.sphere);
    EXPECT_TRUE(
        is_diag(single_error(scene_with_sphere(c.sphere)), "out-of-range", c.path, c.message));
  }
}

TEST(JsonScene, ReportsOutOfRangeCameraMaterialAndPlaneValues) {
  EXPECT_TRUE(is_diag(
      single_error(
          R"({"camera": {"pixeldim": [0, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]}})"),
      "out-of-range", "/camera/pixeldim/0", "integers from 1 to 65535, got 0"));
  EXPECT_TRUE(is_diag(
      single_error(
          R"({"camera": {"pixeldim": [8, 1.5], "worlddim": [8, 6], "viewpoint": [4, 3, 5]}})"),
      "out-of-range", "/camera/pixeldim/1", "got 1.5"));
  EXPECT_TRUE(is_diag(
      single_error(
          R"({"camera": {"pixeldim": [1e300, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]}})"),
      "out-of-range", "/camera/pixeldim/0", "got 1e+300"));
  EXPECT_TRUE(is_diag(
      single_error(
          R"({"camera": {"pixeldim": [8, 6], "worlddim": [0, 6], "viewpoint": [4, 3, 5]}})"),
      "out-of-range", "/camera/worlddim/0", "'worlddim' values must be > 0, got 0"));
  EXPECT_TRUE(is_diag(
      single_error(R"({"camera": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
                       "materials": {"m": {"ambient": [1, -1, 1]}}})"),
      "out-of-range", "/materials/m/ambient/1", "'ambient' values must be >= 0, got -1"));
  EXPECT_TRUE(is_diag(
      single_error(R"({"camera": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
                       "materials": {"m": {}},
                       "objects": [{"type": "plane", "material": "m", "normal": [0, 0, 0],
                                    "point": [0, 0, 0]}]})"),
      "out-of-range", "/objects/0/normal", "'normal' must not be the zero vector"));
}

TEST(JsonScene, ReportsAMissingAttributeAtTheEntity) {
  Diagnostic d = single_error(scene_with_sphere(R"("material": "m", "center": [0, 0, -5])"));
  EXPECT_TRUE(is_diag(d, "missing-attribute", "/objects/0", "sphere is missing 'radius'"));
}

TEST(JsonScene, ReportsAnUndefinedMaterialListingTheDefinedOnes) {
  Diagnostic d = single_error(
      scene_with_sphere(R"("name": "s", "material": "chrom", "center": [0, 0, -5], "radius": 1)"));
  EXPECT_TRUE(is_diag(d, "undefined-material", "/objects/0/material",
                      "undefined material 'chrom' in sphere 's' (did you mean 'chrome'?); "
                      "defined: chrome, m"));
}

TEST(JsonScene, ReportsADuplicateKeyAtItsPath) {
  Diagnostic d = single_error(
      scene_with_sphere(R"("material": "m", "center": [0, 0, -5], "radius": 1, "radius": 2)"));
  EXPECT_TRUE(is_diag(d, "duplicate-key", "/objects/0/radius", "key given twice"));
}

TEST(JsonScene, ReportsADuplicateMaterialKey) {
  Diagnostic d =
      single_error(R"({"camera": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
                                 "materials": {"m": {}, "k": {}, "m": {"diffuse": 1}}})");
  EXPECT_TRUE(is_diag(d, "duplicate-key", "/materials/m", "key given twice"));
}

TEST(JsonScene, ReportsADuplicateLightName) {
  Diagnostic d = single_error(scene_with_sphere(
      kGoodSphere,
      R"(, "lights": [{"name": "l", "location": [0, 0, 0]}, {"name": "l", "location": [1, 1, 1]}])"));
  EXPECT_TRUE(is_diag(d, "duplicate-name", "/lights/1/name",
                      "duplicate light name 'l' (first defined at /lights/0/name)"));
}

TEST(JsonScene, ReportsCameraAndCamerasTogether) {
  Diagnostic d = single_error(
      R"({"camera": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
          "cameras": {"b": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]}}})");
  EXPECT_TRUE(
      is_diag(d, "json-key", "/cameras", "give either \"camera\" or \"cameras\", not both"));
}

TEST(JsonScene, ReportsAnUnknownObjectTypeWithASuggestion) {
  Diagnostic d =
      single_error(R"({"camera": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
      "objects": [{"type": "sphre", "material": "m", "center": [0, 0, -5], "radius": 1}]})");
  EXPECT_TRUE(is_diag(d, "unknown-entity", "/objects/0/type",
                      "unknown object type \"sphre\" (expected \"sphere\", \"plane\", \"fplane\", "
                      "\"tiled_plane\", \"texplane\", \"triangle\", \"tri\" or \"revsurf\"); "
                      "did you mean \"sphere\"?"));
}

TEST(JsonScene, ReportsAnObjectWithoutAType) {
  Diagnostic d =
      single_error(R"({"camera": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
      "objects": [{"center": [0, 0, -5], "radius": 1}]})");
  EXPECT_TRUE(is_diag(d, "missing-attribute", "/objects/0", "object needs \"type\""));
}

TEST(JsonScene, ReportsAnInvalidMaterialName) {
  Diagnostic d =
      single_error(R"({"camera": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
      "materials": {"1 bad": {}}})");
  EXPECT_TRUE(is_diag(d, "bad-name", "/materials/1 bad", "invalid material name \"1 bad\""));
}

// Only the one camera under "camera" goes unnamed; under "cameras" its key is its name.
TEST(JsonScene, ReportsACameraWithAnEmptyKey) {
  Diagnostic d = single_error(R"({"cameras": {"": {"pixeldim": [8, 6], "worlddim": [8, 6],
      "viewpoint": [4, 3, 5]}}, "materials": {"m": {}}})");
  EXPECT_EQ(d.code, "bad-name");
  EXPECT_EQ(d.where.path, "/cameras/");
}

TEST(JsonScene, EscapesSlashesAndTildesInPaths) {
  Diagnostic d =
      single_error(R"({"camera": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
      "materials": {"a/b~c": {}}})");
  EXPECT_EQ(d.where.path, "/materials/a~1b~0c");
}

TEST(JsonScene, ReportsNoCamera) {
  Diagnostic d = single_error(R"({"materials": {"m": {}}})");
  EXPECT_EQ(d.code, "no-camera");
}

TEST(JsonScene, ReportsEveryIndependentError) {
  LoadedScene loaded =
      load_scene(R"({"camera": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
      "materials": {"m": {"shininess": -1}},
      "objects": [{"type": "sphere", "material": "m", "center": [0, 0], "radius": 1},
                  {"type": "sphere", "material": "x", "center": [0, 0, 0], "radius": 1}]})");
  std::vector<Diagnostic> errors = errors_of(loaded.diags);
  ASSERT_EQ(errors.size(), 3u) << dump(loaded.diags);
  // In the order of the file, whichever pass found each.
  EXPECT_EQ(errors[0].where.path, "/materials/m/shininess");
  EXPECT_EQ(errors[1].where.path, "/objects/0/center");
  EXPECT_EQ(errors[2].where.path, "/objects/1/material");
}

TEST(JsonScene, FormatsAPathErrorForTheUser) {
  std::string text = scene_with_sphere(R"("material": "m", "center": [0, 0, -5], "radius": 0)");
  LoadedScene loaded = load_scene(text);
  EXPECT_EQ(format_diagnostics(loaded.diags, "scene.json", text),
            "scene.json: error: at /objects/0/radius: 'radius' must be > 0, got 0\n");
}

// --- Syntax ---------------------------------------------------------------------------------

// The reader stopped at a NUL byte: the rest of the file, whatever it held, went unread.
TEST(JsonScene, ANulByteIsAnErrorWhereItIs) {
  const std::string text = std::string("{\"camera\": {\"pixeldim\": [4, 3], \"worlddim\": [8, 6], "
                                       "\"viewpoint\": [4, 3, 5]}}\n") +
                           '\0' + " \"objects\": 5, garbage {{{";
  Diagnostic d = single_error(text);
  EXPECT_EQ(d.code, "json-syntax");
  EXPECT_EQ(d.where.line, 2);
  EXPECT_EQ(d.where.column, 1);
  EXPECT_NE(d.message.find("NUL"), std::string::npos) << d.message;
}

// At the start of the token that does not fit, not its last byte.
TEST(JsonScene, PlacesASyntaxErrorAtTheStartOfItsToken) {
  const std::string line = R"(  "camera": {"pixeldim": [400, 300] "worlddim": [8, 6]})";
  Diagnostic d = single_error("{\n" + line + "\n}");
  EXPECT_EQ(d.where.line, 2);
  EXPECT_EQ(d.where.column, static_cast<int>(line.find("\"worlddim")) + 1);
  d = single_error(R"({"camera": {"pixeldim": [0x10, 6]}})");
  EXPECT_EQ(d.where.column, 26);
  d = single_error(R"({"camera": {"pixeldim": [1, 2] "a\"b": 1}})");
  EXPECT_EQ(d.where.column, 32);
}

TEST(JsonScene, ReportsASyntaxErrorWithLineAndColumn) {
  Diagnostic d = single_error("{\n  \"camera\": {,\n}");
  EXPECT_EQ(d.code, "json-syntax");
  EXPECT_EQ(d.where.line, 2);
  EXPECT_EQ(d.where.column, 14);
  EXPECT_TRUE(d.message.starts_with("invalid JSON: ")) << d.message;
}

TEST(JsonScene, ReportsATrailingCommaAtTheClosingBrace) {
  Diagnostic d = single_error("{\"camera\": {},\n }");
  EXPECT_EQ(d.code, "json-syntax");
  EXPECT_EQ(d.where.line, 2);
  EXPECT_EQ(d.where.column, 2);
}

TEST(JsonScene, ReportsTruncatedJsonAtItsEnd) {
  Diagnostic d = single_error("{\"camera\": {\"pixeldim\": [8, ");
  EXPECT_EQ(d.code, "json-syntax");
  EXPECT_EQ(d.where.line, 1);
  EXPECT_EQ(d.where.column, 29);
  EXPECT_NE(d.message.find("unexpected end of input"), std::string::npos) << d.message;
}

TEST(JsonScene, ReportsANumberThatOverflowsAtItsPosition) {
  Diagnostic d =
      single_error("{\"materials\": {\"1e400\": {}},\n \"camera\": {\"pixeldim\": [1e400, 6]}}");
  EXPECT_EQ(d.code, "json-syntax");
  EXPECT_EQ(d.where.line, 2);
  EXPECT_EQ(d.where.column, 26);
  EXPECT_EQ(d.message, "invalid JSON: the number 1e400 is too large for a double");
}

TEST(JsonScene, ReportsNumbersJsonCannotHoldAsSyntaxErrors) {
  for (std::string_view text :
       {R"({"camera": {"pixeldim": [1e400, 6]}})", R"({"camera": {"pixeldim": [-1e400, 6]}})",
        R"({"camera": {"pixeldim": [NaN, 6]}})", R"({"camera": {"pixeldim": [Infinity, 6]}})",
        R"({"camera": {"pixeldim": [0x10, 6]}})"}) {
    SCOPED_TRACE(text);
    Diagnostic d = single_error(text);
    EXPECT_EQ(d.code, "json-syntax");
    EXPECT_EQ(d.where.line, 1);
    EXPECT_GE(d.where.column, 26);
  }
}

// A JSON scene's tree takes some 30 times its text: past 128 MiB it is refused unread.
TEST(JsonScene, RefusesAJsonSceneTooLargeToHold) {
  std::string text = "{\"objects\": [" + std::string(kMaxJsonSceneBytes, ' ') + "]}";
  Diagnostic d = single_error(text);
  EXPECT_EQ(d.code, "json-size");
  EXPECT_NE(d.message.find("over the limit of 128 MiB"), std::string::npos) << d.message;
  // At the limit it is read (and this one is merely empty of cameras).
  text.resize(kMaxJsonSceneBytes - 2);
  text += "]}";
  LoadedScene loaded = load_scene(text);
  for (const Diagnostic& e : loaded.diags.items()) EXPECT_NE(e.code, "json-size");
}

TEST(JsonScene, ReportsDeepNestingCleanly) {
  auto start = std::chrono::steady_clock::now();
  const int n = 100000;
  std::string closed = "{\"objects\": " + std::string(n, '[') + std::string(n, ']') + "}";
  Diagnostic d = single_error(closed);
  EXPECT_EQ(d.code, "json-depth");
  EXPECT_NE(d.message.find("JSON nested deeper than 64 levels"), std::string::npos) << d.message;
  // At the place of the container one too deep: "/objects" and 63 "/0".
  std::string deepest = "/objects";
  for (int i = 0; i < 63; ++i) deepest += "/0";
  EXPECT_EQ(d.where.path, deepest);
  // Unclosed, it is still reported as too deep: parsing stops at the limit.
  Diagnostic open = single_error("{\"objects\": " + std::string(n, '['));
  EXPECT_EQ(open.code, "json-depth");
  Diagnostic objects = single_error([&] {
    std::string s;
    for (int i = 0; i < n; ++i) s += "{\"a\":";
    s += "1";
    s += std::string(n, '}');
    return s;
  }());
  EXPECT_EQ(objects.code, "json-depth");
  Diagnostics diags;
  parse_json_scene(std::string(n, '['), diags);
  EXPECT_TRUE(diags.has_errors());
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20));
}

TEST(JsonScene, AcceptsNestingUpToTheLimit) {
  // The deepest legal scene nests only a few levels; the limit leaves room but stops abuse.
  std::string text = "{\"render\": {\"x\": " + std::string(kMaxJsonDepth - 2, '[') +
                     std::string(kMaxJsonDepth - 2, ']') + "}}";
  Diagnostics diags;
  parse_json_scene(text, diags);
  for (const Diagnostic& d : diags.items()) EXPECT_NE(d.code, "json-depth") << d.message;
}

// --- Render options -------------------------------------------------------------------------

TEST(JsonScene, ReadsRenderOptions) {
  Scene s = scene_of(scene_with_sphere(kGoodSphere, R"(, "render": {
      "spp": 4, "max_depth": 2, "shadows": false, "highlight": "blinn", "max_dist": 12.5,
      "background": [0.1, 0.2, 0.3], "seed": 18446744073709551615, "precision": "float"})"));
  RenderOptions options;
  Diagnostics diags;
  apply_options(options, s.render, diags);
  ASSERT_FALSE(diags.has_errors()) << dump(diags);
  EXPECT_EQ(options.spp, 4);
  EXPECT_EQ(options.max_depth, 2);
  EXPECT_FALSE(options.shadows);
  EXPECT_EQ(options.highlight, Highlight::blinn);
  EXPECT_EQ(options.max_dist, 12.5);
  EXPECT_EQ(options.background, (std::array<double, 3>{0.1, 0.2, 0.3}));
  EXPECT_EQ(options.seed, 18446744073709551615u);
  EXPECT_EQ(options.precision, Precision::f32);
  ASSERT_EQ(s.render.size(), 8u);
  EXPECT_EQ(s.render[0].where.path, "/render/spp");
}

// As the command line reads the same text: an integer option refuses 4.0 and 1e3 as it
// refuses --spp 4.0, so a seed past 2^53 cannot be rounded on its way through a double.
TEST(JsonScene, ReadsRenderNumbersAsTheTextTheyAreWritten) {
  for (std::string_view render : {R"("spp": 4.0)", R"("spp": 1e0)", R"("seed": 1e3)",
                                  R"("seed": 9007199254740993.0)", R"("max_depth": 2.0)"}) {
    SCOPED_TRACE(render);
    Diagnostic d = single_error(scene_with_sphere(kGoodSphere, ", \"render\": {" +
                                                                   std::string(render) + "}"));
    EXPECT_EQ(d.code, "bad-option");
    EXPECT_NE(d.message.find("must be an integer"), std::string::npos) << d.message;
  }
  // A list only where the option takes one.
  Diagnostic d = single_error(scene_with_sphere(kGoodSphere, R"(, "render": {"spp": [4]})"));
  EXPECT_TRUE(is_diag(d, "bad-option", "/render/spp", "wrong type (an array)"));
  Scene s = scene_of(scene_with_sphere(
      kGoodSphere, R"(, "render": {"max_dist": 2.0, "bailout": 1e-3, "background": [0.25]})"));
  RenderOptions options;
  Diagnostics diags;
  apply_options(options, s.render, diags);
  ASSERT_FALSE(diags.has_errors()) << dump(diags);
  EXPECT_EQ(options.max_dist, 2.0);
  EXPECT_EQ(options.bailout, 1e-3);
  EXPECT_EQ(options.background, (std::array<double, 3>{0.25, 0.25, 0.25}));
}

// Errors come from passes by kind; they are listed as the file has them.
TEST(JsonScene, ListsErrorsInTheOrderOfTheFile) {
  LoadedScene loaded = load_scene(R"({
 "render": {"spp": 0},
 "objects": [
   {"type": "sphere", "material": "nope", "center": [1, 1, 1], "radius": 1},
   {"type": "sphere", "material": "m", "center": [1, 1, 1], "radius": -1, "zz": 1}],
 "materials": {"m": {"ambient": -1}},
 "camera": {"pixeldim": [0, 12], "worlddim": [8, 6], "viewpoint": [4, 3, 5]}})");
  std::vector<std::string> paths;
  for (const Diagnostic& d : loaded.diags.items()) paths.push_back(d.where.path);
  EXPECT_EQ(paths, (std::vector<std::string>{"/render/spp", "/objects/0/material",
                                             "/objects/1/radius", "/objects/1/zz",
                                             "/materials/m/ambient", "/camera/pixeldim/0"}))
      << dump(loaded.diags);
}

TEST(JsonPointerOffsets, FindsKeysAndElementsAndFallsBackToTheHolder) {
  const std::string text = "\xEF\xBB\xBF{\"a\": [1, {\"b~/\\u00e9\": 2}], \"c\": {}}";
  const std::vector<std::string> pointers = {"", "/a", "/a/0", "/a/1", "/a/1/b~0~1\xC3\xA9",
                                             "/c/missing", "/zz", "/a/7"};
  const std::vector<size_t> at = json_pointer_offsets(text, pointers);
  ASSERT_EQ(at.size(), pointers.size());
  EXPECT_EQ(at[0], 0u);
  EXPECT_EQ(at[1], text.find("\"a\""));
  EXPECT_EQ(at[2], text.find('1'));
  EXPECT_EQ(at[3], text.find("{\"b"));
  EXPECT_EQ(at[4], text.find("\"b"));
  EXPECT_EQ(at[5], text.find("\"c\""));  // left out: at its object
  EXPECT_EQ(at[6], 0u);                  // nothing holds it but the root
  EXPECT_EQ(at[7], text.find("\"a\""));
  // Not JSON at all: what could be read, never past the text.
  for (std::string_view bad : {"{\"a\": [1, 2", "{\"a", "[[[", "\"", "{\"a\" 1}"})
    for (size_t offset : json_pointer_offsets(bad, {"/a/1", "/a", "/0/0"}))
      EXPECT_LE(offset, bad.size());
}

TEST(JsonScene, ReadsAGreyBackgroundAndACameraChoice) {
  Scene s = scene_of(R"({"cameras": {
      "a": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
      "b": {"pixeldim": [8, 6], "worlddim": [8, 6], "viewpoint": [4, 3, 9]}},
      "render": {"background": 0.5, "camera": "b"}})");
  RenderOptions options;
  Diagnostics diags;
  apply_options(options, s.render, diags);
  EXPECT_EQ(options.background, (std::array<double, 3>{0.5, 0.5, 0.5}));
  EXPECT_EQ(s.find_camera(options.camera), 1);
}

TEST(JsonScene, ReportsBadRenderOptionsAtTheirPath) {
  struct Case {
    std::string render;
    std::string code;
    std::string path;
    std::string message;
  };
  const Case cases[] = {
      {R"("spp": 0)", "bad-option", "/render/spp",
       "option spp must be an integer in 1..1048576, got '0'"},
      {R"("spp": 2.5)", "bad-option", "/render/spp", "got '2.5'"},
      {R"("spp": 1e300)", "bad-option", "/render/spp", "must be an integer"},
      {R"("max_depth": -1)", "bad-option", "/render/max_depth", "must be an integer in 0.."},
      {R"("highlite": "blinn")", "unknown-option", "/render/highlite",
       "unknown render option 'highlite' (did you mean 'highlight'?)"},
      {R"("shadows": "maybe")", "bad-option", "/render/shadows", "must be true or false"},
      {R"("shadows": {})", "bad-option", "/render/shadows",
       "render option \"shadows\" has a value of the wrong type (an object)"},
      {R"("background": [1, 2])", "bad-option", "/render/background", "must be 3 numbers"},
      {R"("background": [1, -2, 3])", "bad-option", "/render/background", "must be >= 0"},
      {R"("highlight": "toon")", "bad-option", "/render/highlight", "must be phong or blinn"},
      {R"("max_dist": 0)", "bad-option", "/render/max_dist", "must be > 0"},
      {R"("camera": "nope")", "unknown-camera", "/render/camera",
       "render option camera names no camera 'nope'"},
      // Options the scene's own profile cannot take: at the option (render would refuse them).
      {R"("profile": "cpsc102", "max_depth": 5000)", "bad-option", "/render/max_depth",
       "the cpsc102 profile follows rays at most 1000 bounces deep; max_depth 5000 is more"},
      {R"("precision": "float", "profile": "cpsc102")", "bad-option", "/render/precision",
       "precision float is not available in the cpsc102 profile"},
      {R"("profile": "cpsc102", "seed": 4294967296)", "bad-option", "/render/seed",
       "seed must be below 2^32"},
      // Its samples come in one pass: a limit between passes would never stop it.
      {R"("profile": "cpsc102", "spp": 64, "time_limit": 0.5)", "bad-option", "/render/time_limit",
       "time_limit is not available in the cpsc102 profile"},
      {R"("profile": "cpsc102", "target_error": 2)", "bad-option", "/render/target_error",
       "target_error is not available in the cpsc102 profile"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.render);
    EXPECT_TRUE(
        is_diag(single_error(scene_with_sphere(kGoodSphere, ", \"render\": {" + c.render + "}")),
                c.code, c.path, c.message));
  }
}

TEST(JsonScene, ReportsARenderSectionThatIsNotAnObject) {
  Diagnostic d = single_error(scene_with_sphere(kGoodSphere, R"(, "render": [1])"));
  EXPECT_TRUE(is_diag(d, "json-type", "/render", "expected an object of render options"));
}

// --- Hostile input --------------------------------------------------------------------------

void expect_sane(std::string_view text, const LoadedScene& loaded) {
  const int lines = 1 + static_cast<int>(count_lines(text));  // as util/lines.h counts them
  EXPECT_LE(loaded.diags.items().size(), 2 * Diagnostics::kMaxErrors);
  for (const Diagnostic& d : loaded.diags.items()) {
    EXPECT_FALSE(d.code.empty());
    EXPECT_FALSE(d.message.empty());
    EXPECT_LE(d.message.size(), 2000u);
    for (char c : d.message) EXPECT_GE(static_cast<unsigned char>(c), 0x20) << d.message;
    EXPECT_LE(d.where.line, lines);
  }
  EXPECT_EQ(loaded.scene.has_value(), !loaded.diags.has_errors());
}

TEST(JsonScene, SurvivesEveryTruncationOfTheLectureScene) {
  for (size_t n = 1; n <= kLectureJson.size(); ++n) {
    std::string_view text = kLectureJson.substr(0, n);
    expect_sane(text, load_scene(text));
    if (::testing::Test::HasFailure()) {
      ADD_FAILURE() << "at length " << n;
      return;
    }
  }
}

TEST(JsonScene, SurvivesRandomEditsOfTheLectureScene) {
  std::mt19937 rng(99);
  const char alphabet[] = "{}[]\",:0123456789.-eE \n\\tufnlarsu\x01\xff";
  for (int round = 0; round < 1500; ++round) {
    std::string text(kLectureJson);
    int edits = 1 + static_cast<int>(rng() % 6);
    for (int i = 0; i < edits; ++i) {
      size_t at = 1 + rng() % (text.size() - 1);
      switch (rng() % 3) {
        case 0:
          text[at] = alphabet[rng() % (sizeof alphabet - 1)];
          break;
        case 1:
          text.erase(at, 1 + rng() % 8);
          break;
        default:
          text.insert(at, 1, alphabet[rng() % (sizeof alphabet - 1)]);
          break;
      }
    }
    expect_sane(text, load_scene(text));
    if (::testing::Test::HasFailure()) {
      ADD_FAILURE() << "round " << round << ":\n" << text;
      return;
    }
  }
}

TEST(JsonScene, KeepsControlCharactersOutOfMessages) {
  LoadedScene loaded = load_scene(scene_with_sphere(
      kGoodSphere, R"(, "bad\u001b[2J\nkey": 1, "render": {"x\ny": 1, "camera": "a\nb"})"));
  ASSERT_TRUE(loaded.diags.has_errors());
  expect_sane("", loaded);
}

}  // namespace
}  // namespace rayfarm
