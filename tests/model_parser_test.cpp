// The model-file parser and builder (docs/model-format.md): every error with its exact position and
// message, no cascades, the lexical corner cases, and hostile input.
#include "rayfarm/model_parser.h"

#include "test_util.h"
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "rayfarm/load.h"
#include "util/lines.h"

namespace rayfarm {
namespace {

// A camera and a material on lines 1 and 2, so the entity under test starts on line 3.
constexpr std::string_view kHead =
    "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
    "material m { diffuse 1 }\n";

constexpr std::string_view kLecture = R"(# The scene of the lecture notes
camera cam1
{
   pixeldim  800 600
   worlddim  8 6
   viewpoint 4 3 5
}
material chrome
{  ambient  3 3 3
   diffuse  .1 .1 .1
   specular .9 .9 .9
}
material floor
{  ambient  2 2 2
   diffuse  .5 .5 .5
}
light top
{  location   2.56 3.80 -1.5
   emissivity 4 4 4
}
sphere left
{  material chrome
   center   1.25 .75 -4
   radius   .9
}
plane ground
{  material floor
   normal   0 1 0
   point    0 -0.2 0
}
)";

std::string with_head(std::string_view body) { return std::string(kHead) + std::string(body); }

std::string dump(const Diagnostics& diags) {
  std::string out;
  for (const Diagnostic& d : diags.items())
    out += std::to_string(d.where.line) + ":" + std::to_string(d.where.column) + " " + d.code +
           ": " + d.message + "\n";
  return out;
}

std::vector<Diagnostic> errors_of(const Diagnostics& diags) {
  std::vector<Diagnostic> out;
  for (const Diagnostic& d : diags.items())
    if (d.severity == Severity::error) out.push_back(d);
  return out;
}

// The one error of a whole file; a failure (listing them all) when there is not exactly one.
Diagnostic single_error_of_file(std::string_view text) {
  LoadedScene loaded = load_scene(text);
  std::vector<Diagnostic> errors = errors_of(loaded.diags);
  EXPECT_EQ(errors.size(), 1u) << "for input:\n" << text << "\ngot:\n" << dump(loaded.diags);
  EXPECT_FALSE(loaded.scene.has_value());
  return errors.empty() ? Diagnostic{} : errors[0];
}

// The one error of `body` placed after kHead (so it starts on line 3).
Diagnostic single_error(std::string_view body) { return single_error_of_file(with_head(body)); }

// 1-based column of the first `token` in `line`.
int column_of(std::string_view line, std::string_view token) {
  size_t at = line.find(token);
  EXPECT_NE(at, std::string_view::npos) << token;
  return static_cast<int>(at) + 1;
}

::testing::AssertionResult is_diag(const Diagnostic& d, std::string_view code, int line, int column,
                                   std::string_view text) {
  if (d.code == code && d.where.line == line && d.where.column == column &&
      d.message.find(text) != std::string::npos)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "got " << d.where.line << ":" << d.where.column << " " << d.code << ": " << d.message
         << "\nwant " << line << ":" << column << " " << code << ": ..." << text << "...";
}

::testing::AssertionResult has_text(const std::string& message, std::string_view text) {
  if (message.find(text) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "\"" << message << "\" lacks \"" << text << "\"";
}

Scene scene_of(std::string_view text) {
  LoadedScene loaded = load_scene(text);
  EXPECT_TRUE(loaded.scene.has_value()) << dump(loaded.diags);
  EXPECT_FALSE(loaded.diags.has_errors()) << dump(loaded.diags);
  return loaded.scene.value_or(Scene{});
}

// --- Unknown words ------------------------------------------------------------------------

TEST(ModelParser, ReportsAnUnknownEntityAndSuggestsTheNearestKeyword) {
  Diagnostic d = single_error("sphre s { material m center 0 0 -5 radius 1 }\n");
  EXPECT_TRUE(is_diag(d, "unknown-entity", 3, 1, "unknown entity 'sphre'"));
  EXPECT_TRUE(has_text(d.message, "(did you mean 'sphere'?)"));
}

TEST(ModelParser, ReportsAnUnknownEntityWithoutAHintWhenNothingIsClose) {
  Diagnostic d = single_error("cylinder t { a 1 2 3 }\n");
  EXPECT_TRUE(is_diag(d, "unknown-entity", 3, 1,
                      "unknown entity 'cylinder'; expected one of: camera, material, texture, "
                      "light, spotlight, projector, sphere, plane, fplane, tiled_plane, "
                      "texplane, triangle, tri, revsurf"));
  EXPECT_FALSE(has_text(d.message, "did you mean"));
}

TEST(ModelParser, TreatsKeywordsAsCaseSensitive) {
  Diagnostic d = single_error("Sphere s { material m center 0 0 -5 radius 1 }\n");
  EXPECT_TRUE(is_diag(d, "unknown-entity", 3, 1, "did you mean 'sphere'?"));
}

TEST(ModelParser, DoesNotAlsoReportNoCameraForAMisspeltCamera) {
  Diagnostic d = single_error_of_file(
      "camra c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
      "material m { diffuse 1 }\n"
      "sphere s { material m center 0 0 -5 radius 1 }\n");
  EXPECT_TRUE(is_diag(d, "unknown-entity", 1, 1, "did you mean 'camera'?"));
}

TEST(ModelParser, DoesNotAlsoReportUndefinedMaterialForAMisspeltMaterial) {
  Diagnostic d = single_error(
      "materal chrome { diffuse 1 }\n"
      "sphere s { material chrome center 0 0 -5 radius 1 }\n");
  EXPECT_TRUE(is_diag(d, "unknown-entity", 3, 1, "did you mean 'material'?"));
}

TEST(ModelParser, ReportsAStrayValueBetweenEntities) {
  Diagnostic d = single_error("5\n");
  EXPECT_TRUE(is_diag(d, "unknown-entity", 3, 1, "unexpected value '5' outside an entity"));
}

// A stray value or word names no entity: the unnamed camera or light after it is read, and
// its own errors reported.
TEST(ModelParser, AStrayTokenDoesNotSwallowTheEntityAfterIt) {
  for (std::string_view stray : {"1.5", "nan", "foo"}) {
    SCOPED_TRACE(stray);
    LoadedScene loaded = load_scene(
        "material m { ambient 1 }\n" + std::string(stray) +
        "\ncamera { pixeldim 16 12 worlddim 8 6 viewpoint 4 3 5 }\n"
        "light { location 1 2 3 emissivity -1 1 1 }\n");
    std::vector<Diagnostic> errors = errors_of(loaded.diags);
    ASSERT_EQ(errors.size(), 2u) << dump(loaded.diags);
    EXPECT_EQ(errors[0].code, "unknown-entity");
    EXPECT_EQ(errors[0].where.line, 2);
    EXPECT_EQ(errors[1].where.line, 4);  // the light's emissivity; no "no camera"
  }
  // A misspelt keyword still keeps its own name.
  Diagnostic d = single_error("materail shiny { diffuse 1 }\nsphere { material shiny center 0 0 "
                              "-5 radius 1 }\n");
  EXPECT_EQ(d.code, "unknown-entity");
}

// Independent mistakes in one plane-like entity are all reported, not one per fix.
TEST(ModelParser, ReportsEveryMistakeOfAFinitePlane) {
  struct Case {
    std::string entity;
    std::vector<std::string> codes;
  };
  const Case cases[] = {
      {"fplane { material zz normal 0 0 1 point 0 0 0 xdir 1 0 0 dimensions -1 1 }",
       {"undefined-material", "out-of-range"}},
      {"fplane { material m normal 0 0 0 point 0 0 0 xdir 1 0 0 dimensions -1 1 }",
       {"out-of-range", "out-of-range"}},
      {"fplane { material m normal 0 0 1 point 0 0 0 xdir 0 0 1 dimensions -1 1 }",
       {"out-of-range", "out-of-range"}},
      {"tiled_plane { material zz altmaterial m normal 0 1 0 point 0 0 0 dimension -1 1 }",
       {"undefined-material", "out-of-range"}},
      {"texplane { material zz normal 0 0 1 point 0 0 0 xdir 1 0 0 dimensions 0 1 "
       "texname t.ppm }",
       {"undefined-material", "out-of-range"}},
      {"projector { location 0 0 5 emissivity 1 1 1 normal 0 0 0 point 0 0 0 xdir 1 0 0 "
       "dimensions -2 1 texname t.ppm }",
       {"out-of-range", "out-of-range"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.entity);
    LoadedScene loaded = load_scene(with_head(c.entity + "\n"));
    std::vector<std::string> codes;
    for (const Diagnostic& e : errors_of(loaded.diags)) codes.push_back(e.code);
    EXPECT_EQ(codes, c.codes) << dump(loaded.diags);
  }
}

TEST(ModelParser, ReportsAnUnknownAttributeAndSuggestsTheNearestOne) {
  std::string line = "sphere s { material m center 0 0 -5 radious 1 }";
  Diagnostic d = single_error(line + "\n");
  EXPECT_TRUE(is_diag(d, "unknown-attribute", 3, column_of(line, "radious"),
                      "unknown attribute 'radious' for sphere 's' (attributes: material, center, "
                      "radius) (did you mean 'radius'?)"));
}

TEST(ModelParser, ReportsEachOfTwoMisspeltAttributesInARow) {
  std::string line = "sphere s { material m radious 1 centr 0 0 -5 }";
  LoadedScene loaded = load_scene(with_head(line + "\n"));
  std::vector<Diagnostic> errors = errors_of(loaded.diags);
  ASSERT_EQ(errors.size(), 2u) << dump(loaded.diags);
  EXPECT_TRUE(is_diag(errors[0], "unknown-attribute", 3, column_of(line, "radious"),
                      "did you mean 'radius'?"));
  EXPECT_TRUE(is_diag(errors[1], "unknown-attribute", 3, column_of(line, "centr"),
                      "did you mean 'center'?"));
}

TEST(ModelParser, SkipsTheValuesOfAnUnknownAttribute) {
  std::string line = "sphere s { material m texture wood 1 2 center 0 0 -5 radius 1 }";
  Diagnostic d = single_error(line + "\n");
  EXPECT_TRUE(is_diag(d, "unknown-attribute", 3, column_of(line, "texture"),
                      "unknown attribute 'texture' for sphere 's'"));
}

TEST(ModelParser, ReportsAStrayValueInsideAnEntity) {
  std::string line = "sphere s { material m 7 center 0 0 -5 radius 1 }";
  Diagnostic d = single_error(line + "\n");
  EXPECT_TRUE(is_diag(d, "unexpected-value", 3, column_of(line, "7"),
                      "unexpected value '7' in sphere 's'"));
}

TEST(ModelParser, ReportsAnAttributeOfAnotherEntityAsUnknown) {
  std::string line = "light l { location 0 0 0 radius 1 }";
  Diagnostic d = single_error(line + "\n");
  EXPECT_TRUE(is_diag(d, "unknown-attribute", 3, column_of(line, "radius"),
                      "unknown attribute 'radius' for light 'l' (attributes: location, "
                      "emissivity)"));
}

// --- Value counts ---------------------------------------------------------------------------

TEST(ModelParser, ReportsTooFewValuesAtTheAttribute) {
  std::string line = "sphere s { material m center 0 0 radius 1 }";
  Diagnostic d = single_error(line + "\n");
  EXPECT_TRUE(is_diag(d, "value-count", 3, column_of(line, "center"),
                      "'center' takes 3 numbers, got 2 values"));
}

TEST(ModelParser, ReportsTooManyValuesAtTheFirstExtraValue) {
  std::string line = "sphere s { material m center 0 0 -5 radius 1 22 }";
  Diagnostic d = single_error(line + "\n");
  EXPECT_TRUE(is_diag(d, "value-count", 3, column_of(line, "22"),
                      "'radius' takes 1 number > 0, got 2 values"));
}

TEST(ModelParser, ReportsAnAttributeWithNoValue) {
  std::string line = "sphere s { material m center 0 0 -5 radius }";
  Diagnostic d = single_error(line + "\n");
  EXPECT_TRUE(is_diag(d, "value-count", 3, column_of(line, "radius"),
                      "'radius' takes 1 number > 0, got 0 values"));
}

TEST(ModelParser, ReportsOnePixeldimValue) {
  std::string line = "camera c { pixeldim 800 worlddim 8 6 viewpoint 4 3 5 }";
  Diagnostic d = single_error_of_file(line + "\n");
  EXPECT_TRUE(is_diag(d, "value-count", 1, column_of(line, "pixeldim"),
                      "'pixeldim' takes 2 integers >= 1, got 1 value"));
}

TEST(ModelParser, RejectsAColourOfTwoValues) {
  std::string line = "material k { ambient 1 1 }";
  Diagnostic d = single_error(line + "\n");
  EXPECT_TRUE(is_diag(d, "value-count", 3, column_of(line, "ambient"),
                      "'ambient' takes 3 numbers >= 0, or 1 number for all three, got 2 values"));
}

TEST(ModelParser, ReportsAManyValuedAttributeOnceWithoutReadingForever) {
  std::string values;
  for (int i = 0; i < 100000; ++i) values += " 1";
  Diagnostic d = single_error("sphere s { material m center" + values + " radius 1 }\n");
  EXPECT_TRUE(is_diag(d, "value-count", 3, 36, "'center' takes 3 numbers, got 100000 values"));
}

// --- Numbers --------------------------------------------------------------------------------

struct BadNumber {
  const char* token;
  const char* why;
};

TEST(ModelParser, ReportsEveryKindOfNonNumberAtItsToken) {
  const BadNumber cases[] = {
      {"12abc", "unexpected characters after the number"},
      {"nan", "NaN is not allowed"},
      {"NaN", "NaN is not allowed"},
      {"-nan", "NaN is not allowed"},
      {"inf", "infinity is not allowed"},
      {"-inf", "infinity is not allowed"},
      {"+Infinity", "infinity is not allowed"},
      {"0x1p4", "hexadecimal numbers are not allowed"},
      {"0X10", "hexadecimal numbers are not allowed"},
      {"1e400", "number is too large"},
      {"-1e400", "number is too large"},
      {"1.2.3", "unexpected characters after the number"},
      {"1e", "exponent has no digits"},
      {"1e+", "exponent has no digits"},
      {".", "expected a decimal number"},
      {"-", "expected a decimal number"},
      {"--1", "expected a decimal number"},
      {"abc", "expected a decimal number"},
      {"1;5", "unexpected characters after the number"},
      // Pasted from a document: the character is named, since a terminal shows a space.
      {"1\xC2\xA0" "0", "unexpected character U+00A0 (a no-break space) after the number: "
                        "numbers are separated by plain spaces"},
      {"2\xE2\x88\x92" "1", "unexpected character U+2212 (a minus sign; write '-') after the "
                          "number: numbers are separated by plain spaces"},
      {"4\xE2\x80\x8B", "unexpected character U+200B (a zero-width space) after the number: "
                        "numbers are separated by plain spaces"},
      {"3\xE2\x82\xAC", "unexpected character U+20AC after the number: numbers are separated "
                        "by plain spaces"},
  };
  for (const BadNumber& c : cases) {
    SCOPED_TRACE(c.token);
    std::string line = std::string("sphere s { material m center 0 0 -5 radius ") + c.token + " }";
    Diagnostic d = single_error(line + "\n");
    EXPECT_TRUE(is_diag(d, "not-a-number", 3, column_of(line, "radius ") + 7,
                        "'" + std::string(c.token) + "' is not a number: " + c.why));
  }
}

TEST(ModelParser, HintsAtADecimalComma) {
  std::string line = "sphere s { material m center 0 0 -5 radius 1,5 }";
  Diagnostic d = single_error(line + "\n");
  EXPECT_TRUE(is_diag(d, "value-count", 3, column_of(line, "5 }"),
                      "'radius' takes 1 number > 0, got 2 values (a comma separates numbers: if "
                      "'1,5' is one number, write it with a decimal point)"));
  // Vectors may be written with commas: a count that is right needs no hint.
  std::string vector = "sphere s { material m center 0,0,-5 radius 1 }";
  LoadedScene loaded = load_scene(with_head(vector + "\n"));
  EXPECT_TRUE(errors_of(loaded.diags).empty()) << dump(loaded.diags);
}

TEST(ModelParser, ReportsAWordAmongTheNumbersOnce) {
  std::string line = "sphere s { material m center 0 zero -5 radius 1 }";
  Diagnostic d = single_error(line + "\n");
  EXPECT_TRUE(is_diag(d, "not-a-number", 3, column_of(line, "zero"), "'zero' is not a number"));
}

TEST(ParseNumber, NamesNoCharacterForACutOffSequence) {
  std::string why;
  EXPECT_FALSE(parse_number("4\xE2\x82", &why));
  EXPECT_EQ(why, "unexpected characters after the number");
}

TEST(ParseNumber, AcceptsEveryDecimalForm) {
  EXPECT_EQ(parse_number(".5"), 0.5);
  EXPECT_EQ(parse_number("5."), 5.0);
  EXPECT_EQ(parse_number("+1"), 1.0);
  EXPECT_EQ(parse_number("1E0"), 1.0);
  EXPECT_EQ(parse_number("1e-3"), 0.001);
  EXPECT_EQ(parse_number("1e+2"), 100.0);
  EXPECT_EQ(parse_number("-2.5"), -2.5);
  EXPECT_EQ(parse_number("-.25"), -0.25);
  EXPECT_EQ(parse_number("007"), 7.0);
  EXPECT_EQ(parse_number("0.1"), 0.1);
  EXPECT_EQ(parse_number("123456789.123456789"), 123456789.123456789);
  EXPECT_EQ(parse_number("1.7976931348623157e308"), 1.7976931348623157e308);
}

TEST(ParseNumber, KeepsTheSignOfNegativeZero) {
  auto v = parse_number("-0");
  ASSERT_TRUE(v);
  EXPECT_EQ(*v, 0.0);
  EXPECT_TRUE(std::signbit(*v));
}

TEST(ParseNumber, RoundsUnderflowToTheNearestDouble) {
  EXPECT_EQ(parse_number("1e-400"), 0.0);
  EXPECT_EQ(parse_number("4.9e-324"), 4.9e-324);
  EXPECT_EQ(parse_number("1e-300"), 1e-300);
}

TEST(ParseNumber, RejectsWhatTheFormatForbidsWithAReason) {
  std::string why;
  EXPECT_FALSE(parse_number("", &why));
  EXPECT_EQ(why, "empty");
  EXPECT_FALSE(parse_number("nan(0x7)", &why));
  EXPECT_EQ(why, "NaN is not allowed");
  EXPECT_FALSE(parse_number("infinity", &why));
  EXPECT_EQ(why, "infinity is not allowed");
  EXPECT_FALSE(parse_number("0x1p4", &why));
  EXPECT_EQ(why, "hexadecimal numbers are not allowed");
  EXPECT_FALSE(parse_number("1e309", &why));
  EXPECT_EQ(why, "number is too large");
  EXPECT_FALSE(parse_number(" 1", &why));
  EXPECT_FALSE(parse_number("1 ", &why));
  EXPECT_FALSE(parse_number("1e5x", &why));
  EXPECT_EQ(why, "unexpected characters after the number");
}

// --- Ranges ---------------------------------------------------------------------------------

struct OutOfRange {
  std::string line;   // replaces the line under test
  std::string token;  // where the caret goes
  std::string message;
};

TEST(ModelParser, ReportsOutOfRangeValuesAtTheValue) {
  const OutOfRange cases[] = {
      {"sphere s { material m center 0 0 -5 radius 0 }", "0 }", "'radius' must be > 0, got 0"},
      {"sphere s { material m center 0 0 -5 radius -1 }", "-1", "'radius' must be > 0, got -1"},
      // A radius whose square overflows would make the sphere vanish, not fill the view.
      {"sphere s { material m center 0 0 -5 radius 1e151 }", "1e151",
       "'radius' must be at most 1e150 (its square must fit a double), got 1e+151"},
      {"revsurf r { material m surfer 1 base 0 0 -5 direction 0 1 0 height 2e150 }", "2e150",
       "'height' must be at most 1e150"},
      {"material k { ambient 1 -0.5 1 }", "-0.5", "'ambient' values must be >= 0, got -0.5"},
      {"material k { diffuse -1 }", "-1", "'diffuse' values must be >= 0, got -1"},
      {"material k { shininess -1 }", "-1", "'shininess' must be >= 0, got -1"},
      {"light l { location 0 0 0 emissivity 1 1 -2 }", "-2",
       "'emissivity' values must be >= 0, got -2"},
      // Nor may a point lie so far out that a distance's square overflows: an eye or a light
      // there would see, or light, nothing.
      {"light l { location 4 1e155 -4 emissivity 1 }", "1e155",
       "'location' coordinates must be within ±1e150 (the squares of distances must fit a "
       "double), got 1e+155"},
      {"sphere s { material m center -2e150 0 -5 radius 1 }", "-2e150",
       "'center' coordinates must be within ±1e150"},
      // A triangle's vertices too: past that it vanished without a word (or, at 1e308, was
      // called a line).
      {"triangle t { material m vertex1 -10 -10 -1 vertex2 1e156 -10 -1 vertex3 0 1 -1 }",
       "1e156", "'vertex2' coordinates must be within ±1e150"},
      {"tri t { material m v0 -1e308 0 -5 v1 1 0 -5 v2 0 1 -5 }", "-1e308",
       "'v0' coordinates must be within ±1e150"},
  };
  for (const OutOfRange& c : cases) {
    SCOPED_TRACE(c.line);
    Diagnostic d = single_error(c.line + "\n");
    EXPECT_TRUE(is_diag(d, "out-of-range", 3, column_of(c.line, c.token), c.message));
  }
}

TEST(ModelParser, ReportsOutOfRangeCameraValues) {
  const OutOfRange cases[] = {
      {"camera c { pixeldim 0 600 worlddim 8 6 viewpoint 4 3 5 }", "0 600",
       "'pixeldim' values must be integers from 1 to 65535, got 0"},
      {"camera c { pixeldim 800 1.5 worlddim 8 6 viewpoint 4 3 5 }", "1.5",
       "'pixeldim' values must be integers from 1 to 65535, got 1.5"},
      {"camera c { pixeldim 800 -600 worlddim 8 6 viewpoint 4 3 5 }", "-600",
       "'pixeldim' values must be integers from 1 to 65535, got -600"},
      {"camera c { pixeldim 8 6 worlddim 0 6 viewpoint 4 3 5 }", "0 6",
       "'worlddim' values must be > 0, got 0"},
      {"camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 1e155 }", "1e155",
       "'viewpoint' coordinates must be within ±1e150"},
      {"camera c { pixeldim 800 600 worlddim 8 -6 viewpoint 4 3 5 }", "-6",
       "'worlddim' values must be > 0, got -6"},
      // A window so small that lengths across it square to 0: it would render black.
      {"camera c { pixeldim 8 6 worlddim 8e-170 6 viewpoint 4e-170 3e-170 5e-170 }",
       "8e-170", "'worlddim' values must be from 1e-150 to 1e150 (their squares must fit a "
                 "double), got 8e-170"},
      {"camera c { pixeldim 8 6 worlddim 8 2e150 viewpoint 4 3 5 }", "2e150",
       "'worlddim' values must be from 1e-150 to 1e150"},
  };
  for (const OutOfRange& c : cases) {
    SCOPED_TRACE(c.line);
    Diagnostic d = single_error_of_file(c.line + "\n");
    EXPECT_TRUE(is_diag(d, "out-of-range", 1, column_of(c.line, c.token), c.message));
  }
}

TEST(ModelParser, ReportsAZeroNormalAtTheAttribute) {
  std::string line = "plane p { material m normal 0 0 0 point 0 0 0 }";
  Diagnostic d = single_error(line + "\n");
  EXPECT_TRUE(is_diag(d, "out-of-range", 3, column_of(line, "normal"),
                      "'normal' must not be the zero vector"));
}

TEST(ModelParser, AcceptsANormalThatIsNotUnitLength) {
  Scene s = scene_of(with_head("plane p { material m normal 0 -0 7 point 0 0 0 }\n"));
  ASSERT_EQ(s.count<Plane>(), 1u);
  EXPECT_EQ(test::shape<Plane>(s, 0).normal.z, 7.0);
}

TEST(ModelParser, AcceptsAmbientAboveOne) {
  Scene s = scene_of(with_head("material k { ambient 30 }\n"));
  EXPECT_EQ(s.materials[1].ambient.x, 30.0);
}

// --- Required, repeated and duplicate ----------------------------------------------------

TEST(ModelParser, ReportsAMissingRequiredAttributeAtTheEntity) {
  Diagnostic d = single_error("sphere s { material m center 0 0 -5 }\n");
  EXPECT_TRUE(
      is_diag(d, "missing-attribute", 3, 1, "sphere 's' is missing 'radius' (1 number > 0)"));
}

TEST(ModelParser, ReportsEachMissingAttribute) {
  LoadedScene loaded = load_scene("camera { pixeldim 8 6 }\nlight { emissivity 1 }\n");
  std::vector<Diagnostic> errors = errors_of(loaded.diags);
  ASSERT_EQ(errors.size(), 3u) << dump(loaded.diags);
  EXPECT_TRUE(is_diag(errors[0], "missing-attribute", 1, 1,
                      "camera is missing 'worlddim' (2 numbers > 0)"));
  EXPECT_TRUE(
      is_diag(errors[1], "missing-attribute", 1, 1, "camera is missing 'viewpoint' (3 numbers)"));
  EXPECT_TRUE(
      is_diag(errors[2], "missing-attribute", 2, 1, "light is missing 'location' (3 numbers)"));
}

TEST(ModelParser, ReportsAPlaneWithoutItsNormal) {
  Diagnostic d = single_error("plane p { material m point 0 0 0 }\n");
  EXPECT_TRUE(is_diag(d, "missing-attribute", 3, 1,
                      "plane 'p' is missing 'normal' (3 numbers, not all 0)"));
}

TEST(ModelParser, ReportsAnAttributeGivenTwiceAtTheSecond) {
  std::string line = "sphere s { material m center 0 0 -5 radius 1";
  Diagnostic d = single_error(line + "\n   radius 2 }\n");
  EXPECT_TRUE(is_diag(d, "duplicate-attribute", 4, 4,
                      "attribute 'radius' given twice in sphere 's' (first at line 3)"));
}

TEST(ModelParser, ReportsARepeatEvenWhenTheFirstValueWasBad) {
  LoadedScene loaded =
      load_scene(with_head("sphere s { material m center 0 0 -5 radius x1 radius 1 }\n"));
  std::vector<Diagnostic> errors = errors_of(loaded.diags);
  ASSERT_EQ(errors.size(), 2u) << dump(loaded.diags);
  EXPECT_EQ(errors[0].code, "not-a-number");
  EXPECT_EQ(errors[1].code, "duplicate-attribute");
}

TEST(ModelParser, ReportsADuplicateNameOfOneTypeAtTheSecondName) {
  Diagnostic d = single_error(
      "sphere s { material m center 0 0 -5 radius 1 }\n"
      "sphere s { material m center 0 0 -9 radius 1 }\n");
  EXPECT_TRUE(
      is_diag(d, "duplicate-name", 4, 8, "duplicate sphere name 's' (first defined at line 3)"));
}

TEST(ModelParser, ReportsADuplicateMaterialName) {
  Diagnostic d = single_error("material m { diffuse 0.5 }\n");
  EXPECT_TRUE(
      is_diag(d, "duplicate-name", 3, 10, "duplicate material name 'm' (first defined at line 2)"));
}

TEST(ModelParser, LetsASphereAndAPlaneShareAName) {
  Scene s =
      scene_of(with_head("sphere x { material m center 0 0 -5 radius 1 }\n"
                         "plane x { material m normal 0 1 0 point 0 0 0 }\n"
                         "light x { location 1 1 1 }\n"));
  ASSERT_EQ(s.count<Sphere>(), 1u);
  ASSERT_EQ(s.count<Plane>(), 1u);
  EXPECT_EQ(test::nth<Sphere>(s, 0).name, "x");
  EXPECT_EQ(test::nth<Plane>(s, 0).name, "x");
  EXPECT_EQ(s.lights[0].name, "x");
}

TEST(ModelParser, AllowsSeveralUnnamedLightsAndObjects) {
  Scene s =
      scene_of(with_head("light { location 1 1 1 }\nlight { location 2 2 2 }\n"
                         "sphere { material m center 0 0 -5 radius 1 }\n"
                         "sphere { material m center 0 0 -9 radius 1 }\n"));
  EXPECT_EQ(s.lights.size(), 2u);
  EXPECT_EQ(s.count<Sphere>(), 2u);
}

TEST(ModelParser, ReportsAnUndefinedMaterialAtItsNameAndListsTheDefinedOnes) {
  std::string line = "sphere s { material chrme center 0 0 -5 radius 1 }";
  Diagnostic d = single_error("material chrome { specular 1 }\n" + line + "\n");
  EXPECT_TRUE(is_diag(d, "undefined-material", 4, column_of(line, "chrme"),
                      "undefined material 'chrme' in sphere 's' (did you mean 'chrome'?); "
                      "defined: chrome, m"));
}

TEST(ModelParser, SaysSoWhenNoMaterialIsDefined) {
  Diagnostic d = single_error_of_file(
      "camera { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
      "plane { material wood normal 0 1 0 point 0 0 0 }\n");
  EXPECT_TRUE(is_diag(d, "undefined-material", 2, 18,
                      "undefined material 'wood' in plane; no materials are defined"));
}

TEST(ModelParser, DoesNotReportAMaterialThatIsDefinedButBrokenAsUndefined) {
  Diagnostic d = single_error(
      "material k { ambient -1 }\n"
      "sphere s { material k center 0 0 -5 radius 1 }\n");
  EXPECT_EQ(d.code, "out-of-range");
}

TEST(ModelParser, ReportsAMissingMaterialName) {
  std::string line = "sphere s { material }";
  LoadedScene loaded = load_scene(with_head(line + "\n"));
  std::vector<Diagnostic> errors = errors_of(loaded.diags);
  ASSERT_GE(errors.size(), 1u);
  EXPECT_TRUE(is_diag(errors[0], "missing-value", 3, column_of(line, "}"),
                      "'material' needs a material name"));
  for (const Diagnostic& e : errors) EXPECT_FALSE(has_text(e.message, "'material' ("));
}

// Loads `body` (after the usual head) with both loaders: the objects' materials are named
// `names`, in order.
void expect_material_names(const std::string& body, const std::vector<std::string>& names) {
  for (const bool fast : {false, true}) {
    SCOPED_TRACE(fast ? "the fast loader" : "the described scene");
    LoadedScene loaded = load_scene(with_head(body), fast ? LoadDetail::scene : LoadDetail::full);
    ASSERT_TRUE(loaded.scene) << dump(loaded.diags);
    const Scene& scene = *loaded.scene;
    ASSERT_EQ(scene.objects.size(), names.size());
    for (std::size_t i = 0; i < names.size(); ++i)
      EXPECT_EQ(scene.materials[scene.objects[i].material].name, names[i]);
  }
}

// A JSON scene may name a material "radius"; its model file must read back. The word after
// `material` is then the name, unless that word's own value follows it (the name left out).
TEST(ModelParser, AMaterialNamedLikeAnAttributeIsAName) {
  expect_material_names(
      "material radius { ambient 1 }\nmaterial normal { ambient .5 }\n"
      "material texname { ambient .2 }\n"
      "sphere s { material radius center 0 0 -5 radius 1 }\n"
      "plane p { material normal normal 0 1 0 point 0 0 0 }\n"
      "sphere t { center 0 2 -5 radius 1 material texname }\n",
      {"radius", "normal", "texname"});
  // Left out, it is one error, at the attribute that came instead.
  const std::string line = "sphere s { material center 0 0 -5 radius 1 }";
  EXPECT_TRUE(is_diag(single_error(line + "\n"), "missing-value", 3, column_of(line, "center"),
                      "'material' needs a material name"));
}

// "nan" and "inf" are names where a material is named, as they are where one is defined (a
// JSON scene's model file must read back); a number is not.
TEST(ModelParser, AMaterialNamedNanOrInfIsAName) {
  expect_material_names(
      "material nan { ambient 1 }\nmaterial Infinity { ambient .5 }\n"
      "sphere s { material nan center 0 0 -5 radius 1 }\n"
      "tiled_plane p { material Infinity altmaterial nan normal 0 1 0 point 0 0 0 xdir 1 0 0 "
      "dimensions 1 1 }\n",
      {"nan", "Infinity"});
  const std::string line = "sphere s { material 2 center 0 0 -5 radius 1 }";
  EXPECT_TRUE(is_diag(single_error(line + "\n"), "missing-value", 3, column_of(line, "2"),
                      "'material' needs a material name"));
}

// A character that looks like a space or like nothing (pasted from a document) is named, and
// the keyword it spoils is not also "missing": one error for one mistake.
TEST(ModelParser, NamesAnInvisibleCharacterInAKeyword) {
  const struct {
    const char* body;
    const char* code;
    const char* named;
    const char* hint;
  } cases[] = {
      {"sphere s { material m center 0 0 -5 radius\xc2\xa0" "1 }\n", "unknown-attribute",
       "U+00A0 (a no-break space)", "radius"},
      {"sphere s { material m center 0 0 -5 \xe2\x80\x8bradius 1 }\n", "unknown-attribute",
       "U+200B (a zero-width space)", "radius"},
      {"\xef\xbb\xbfsphere s { material m center 0 0 -5 radius 1 }\n", "unknown-entity",
       "U+FEFF (a byte-order mark)", "sphere"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.body);
    const Diagnostic d = single_error(c.body);
    EXPECT_EQ(d.code, c.code);
    EXPECT_TRUE(has_text(d.message, c.named)) << d.message;
    EXPECT_TRUE(has_text(d.message, std::string("(did you mean '") + c.hint + "'?)")) << d.message;
  }
}

TEST(ModelParser, ReportsAMaterialWithoutAName) {
  Diagnostic d = single_error("material { diffuse 1 }\n");
  EXPECT_TRUE(is_diag(d, "missing-name", 3, 1, "material needs a name: material NAME { ... }"));
}

TEST(ModelParser, ReportsAnInvalidName) {
  Diagnostic d = single_error("sphere 1s { material m center 0 0 -5 radius 1 }\n");
  EXPECT_TRUE(is_diag(d, "bad-name", 3, 8, "invalid sphere name '1s'"));
}

TEST(ModelParser, ReportsATexturePathThatIsNotUtf8) {
  // JSON and error bodies carry text: such a path could be neither converted nor quoted.
  Diagnostic d = single_error("texture t { filename bricks\xff.ppm }\n");
  EXPECT_TRUE(is_diag(d, "bad-name", 3, 22, "invalid file name 'bricks?.ppm'"));
  Diagnostic lone = single_error("texture t { filename \xe2\x82.ppm }\n");  // truncated
  EXPECT_EQ(lone.code, "bad-name");
  // Well-formed UTF-8 is a path like any other.
  Diagnostics diags;
  parse_model(with_head("texture t { filename br\xc3\xa9ques.ppm }\n"), diags);
  EXPECT_FALSE(diags.has_errors());
}

TEST(ModelParser, AcceptsNamesWithDigitsDotsAndDashes) {
  Scene s =
      scene_of(with_head("material _Chrome.v2-b { specular 1 }\n"
                         "sphere s.1 { material _Chrome.v2-b center 0 0 -5 radius 1 }\n"));
  EXPECT_EQ(test::nth<Sphere>(s, 0).name, "s.1");
  EXPECT_EQ(s.materials[test::nth<Sphere>(s, 0).material].name, "_Chrome.v2-b");
}

// --- Braces ---------------------------------------------------------------------------------

TEST(ModelParser, ReportsAMissingClosingBraceAtTheEndAtItsOpeningBrace) {
  Diagnostic d = single_error("sphere s { material m center 0 0 -5 radius 1\n\n");
  EXPECT_TRUE(is_diag(d, "unbalanced-brace", 3, 10, "'{' of sphere 's' is never closed"));
}

TEST(ModelParser, ReportsAMissingClosingBraceBeforeTheNextEntityOnce) {
  Diagnostic d = single_error(
      "sphere s { material m center 0 0 -5 radius 1\n"
      "sphere t { material m center 0 0 -9 radius 1 }\n");
  EXPECT_TRUE(is_diag(d, "unbalanced-brace", 3, 10,
                      "'{' of sphere 's' is never closed before the next sphere"));
}

TEST(ModelParser, ReportsAnExtraClosingBrace) {
  std::string line = "sphere s { material m center 0 0 -5 radius 1 } }";
  Diagnostic d = single_error(line + "\n");
  EXPECT_TRUE(is_diag(d, "unbalanced-brace", 3, static_cast<int>(line.size()), "unmatched '}'"));
}

TEST(ModelParser, ReportsAMissingOpeningBraceOnce) {
  std::string line = "sphere s material m center 0 0 -5 radius 1 }";
  Diagnostic d = single_error(line + "\n");
  EXPECT_TRUE(
      is_diag(d, "syntax", 3, column_of(line, "material"), "expected '{' after sphere 's'"));
}

TEST(ModelParser, ReportsAMissingOpeningBraceOfAnUnnamedEntityOnce) {
  Diagnostic d = single_error("light\n  location 1 1 1 }\n");
  EXPECT_TRUE(is_diag(d, "syntax", 4, 3, "expected '{' after light"));
}

TEST(ModelParser, ReportsAnEntityKeywordWithNoBodyOnce) {
  Diagnostic d = single_error("light\nsphere s { material m center 0 0 -5 radius 1 }\n");
  EXPECT_TRUE(is_diag(d, "syntax", 4, 1, "expected '{' after light"));
}

TEST(ModelParser, ReportsABraceWhereAnEntityBelongs) {
  Diagnostic d = single_error("{ radius 1 }\n");
  EXPECT_TRUE(is_diag(d, "syntax", 3, 1, "unexpected '{': expected an entity"));
}

TEST(ModelParser, ReportsANestedBlock) {
  std::string line = "sphere s { material m { x } center 0 0 -5 radius 1 }";
  Diagnostic d = single_error(line + "\n");
  EXPECT_TRUE(is_diag(d, "syntax", 3, column_of(line, "{ x"), "unexpected '{' inside sphere 's'"));
}

// A stray '{' before the entity's own attributes is one error: they are still read as its
// own (they were reported missing, and its '}' as never closed).
TEST(ModelParser, ReportsAStrayBraceBeforeAttributesOnce) {
  for (const auto& [line, stray] :
       {std::pair<std::string, std::string>{"sphere s { material m { center 0 0 -5 radius 1 }",
                                            "{ center"},
        {"sphere s { material m center 0 0 -5 { radius 1 }", "{ radius"},
        // Closed again: the block's attributes are still the entity's, and so are the ones
        // after it.
        {"sphere s { material m { center 0 0 -5 } radius 1 }", "{ center"},
        {"sphere s { material m center 0 0 -5 { radius 1 } }", "{ radius"}}) {
    SCOPED_TRACE(line);
    Diagnostic d = single_error(line + "\n");
    EXPECT_TRUE(
        is_diag(d, "syntax", 3, column_of(line, stray), "unexpected '{' inside sphere 's'"));
  }
}

// --- Whole files ----------------------------------------------------------------------------

TEST(ModelParser, ReportsNoCamera) {
  Diagnostic d = single_error_of_file("material m { diffuse 1 }\n");
  EXPECT_EQ(d.code, "no-camera");
  EXPECT_EQ(d.where.line, 0);
  EXPECT_TRUE(has_text(d.message, "no camera: a scene needs at least one camera"));
}

TEST(ModelParser, ReportsAnEmptyFileAsHavingNoCamera) {
  EXPECT_EQ(single_error_of_file("").code, "no-camera");
  EXPECT_EQ(single_error_of_file(" \n\t\r\n").code, "no-camera");
}

TEST(ModelParser, ReportsAFileOfOnlyCommentsAsHavingNoCamera) {
  EXPECT_EQ(single_error_of_file("# nothing\n// here { either }\n#").code, "no-camera");
}

TEST(ModelParser, ReportsEveryIndependentErrorAndNothingMore) {
  std::string text = with_head(
      "sphere a { material m center 0 0 -5 radious 1 }\n"
      "sphere b { material m center 0 0 -7 radius 0 }\n"
      "sphere c { material nope center 0 0 -9 radius 1 }\n");
  LoadedScene loaded = load_scene(text);
  std::vector<Diagnostic> errors = errors_of(loaded.diags);
  ASSERT_EQ(errors.size(), 3u) << dump(loaded.diags);
  EXPECT_TRUE(is_diag(errors[0], "unknown-attribute", 3, 37, "'radious'"));
  EXPECT_TRUE(is_diag(errors[1], "out-of-range", 4, 44, "'radius' must be > 0"));
  EXPECT_TRUE(is_diag(errors[2], "undefined-material", 5, 21, "undefined material 'nope'"));
  EXPECT_FALSE(loaded.scene.has_value());
}

TEST(ModelParser, StopsAtTheErrorCap) {
  std::string text;
  for (int i = 0; i < 1000; ++i) text += "sphre s { }\n";
  LoadedScene loaded = load_scene(text);
  EXPECT_TRUE(loaded.diags.truncated());
  EXPECT_EQ(loaded.diags.items().size(), Diagnostics::kMaxErrors);
  EXPECT_FALSE(loaded.scene.has_value());
}

TEST(ModelParser, StopsAtTheErrorCapInsideOneHugeEntity) {
  std::string text = "sphere s {";
  for (int i = 0; i < 200000; ++i) text += " radious 1";
  text += " }\n";
  auto start = std::chrono::steady_clock::now();
  LoadedScene loaded = load_scene(text);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  EXPECT_TRUE(loaded.diags.truncated());
  EXPECT_LE(loaded.diags.items().size(), Diagnostics::kMaxErrors);
}

// --- Lexical rules --------------------------------------------------------------------------

TEST(ModelParser, ReadsTheLectureScene) {
  Scene s = scene_of(kLecture);
  ASSERT_EQ(s.cameras.size(), 1u);
  EXPECT_EQ(s.cameras[0].width, 800);
  EXPECT_EQ(s.cameras[0].height, 600);
  EXPECT_EQ(s.cameras[0].world_width, 8.0);
  EXPECT_EQ(s.cameras[0].viewpoint.z, 5.0);
  ASSERT_EQ(s.materials.size(), 2u);
  EXPECT_EQ(s.materials[0].specular.y, 0.9);
  EXPECT_FALSE(s.materials[0].shininess.has_value());  // the profile decides  // the default
  EXPECT_EQ(s.materials[1].specular.x, 0.0);  // the default
  ASSERT_EQ(s.lights.size(), 1u);
  EXPECT_EQ(s.lights[0].location.x, 2.56);
  ASSERT_EQ(s.count<Sphere>(), 1u);
  EXPECT_EQ(test::shape<Sphere>(s, 0).radius, 0.9);
  EXPECT_EQ(test::shape<Sphere>(s, 0).center.y, 0.75);
  ASSERT_EQ(s.count<Plane>(), 1u);
  EXPECT_EQ(test::shape<Plane>(s, 0).point.y, -0.2);
  EXPECT_EQ(s.materials[test::nth<Plane>(s, 0).material].name, "floor");
  EXPECT_EQ(s.cameras[0].where.line, 2);
  EXPECT_EQ(test::nth<Sphere>(s, 0).where.line, 21);
}

TEST(ModelParser, SplitsBracesGluedToWords) {
  Scene s = scene_of(
      "camera c{pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5}material m{diffuse 1}"
      "sphere s{material m center 0 0 -5 radius 1}");
  ASSERT_EQ(s.count<Sphere>(), 1u);
  EXPECT_EQ(test::shape<Sphere>(s, 0).radius, 1.0);
  EXPECT_EQ(test::shape<Sphere>(s, 0).center.z, -5.0);
}

TEST(ModelParser, SkipsHashAndSlashCommentsEvenGluedToATokenOrHoldingBraces) {
  Scene s = scene_of(
      "# a comment with { braces }\n"
      "camera c // another }\n"
      "{ pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
      "material m { diffuse 1#glued\n}\n"
      "sphere s { material m//glued\n center 0 0 -5// glued\n radius 2# }\n}\n");
  ASSERT_EQ(s.count<Sphere>(), 1u);
  EXPECT_EQ(test::shape<Sphere>(s, 0).radius, 2.0);
  EXPECT_EQ(test::shape<Sphere>(s, 0).center.z, -5.0);
}

TEST(ModelParser, ReadsEveryNumberForm) {
  Scene s =
      scene_of(with_head("sphere s { material m center .5 5. +1 radius 1E0 }\n"
                         "light l { location 1e-3 -2.5 1e+2 }\n"));
  EXPECT_EQ(test::shape<Sphere>(s, 0).center.x, 0.5);
  EXPECT_EQ(test::shape<Sphere>(s, 0).center.y, 5.0);
  EXPECT_EQ(test::shape<Sphere>(s, 0).center.z, 1.0);
  EXPECT_EQ(test::shape<Sphere>(s, 0).radius, 1.0);
  EXPECT_EQ(s.lights[0].location.x, 0.001);
  EXPECT_EQ(s.lights[0].location.y, -2.5);
  EXPECT_EQ(s.lights[0].location.z, 100.0);
}

TEST(ModelParser, SpreadsAOneValueColourOverAllThreeChannels) {
  Scene s =
      scene_of(with_head("material k { ambient 2 specular .5 }\nlight { location 0 0 0 "
                         "emissivity 3 }\n"));
  EXPECT_EQ(s.materials[1].ambient, glm::dvec3(2, 2, 2));
  EXPECT_EQ(s.materials[1].specular, glm::dvec3(.5, .5, .5));
  EXPECT_EQ(s.lights[0].emissivity, glm::dvec3(3, 3, 3));
  // The description keeps what was written.
  LoadedScene loaded = load_scene(with_head("material k { ambient 2 }\n"));
  EXPECT_EQ(loaded.desc.entities[2].attrs[0].numbers, std::vector<double>{2});
}

TEST(ModelParser, AppliesTheDefaults) {
  Scene s = scene_of(with_head("material k { }\nlight { location 0 0 0 }\n"));
  EXPECT_EQ(s.materials[1].ambient, glm::dvec3(0));
  EXPECT_EQ(s.materials[1].diffuse, glm::dvec3(0));
  EXPECT_EQ(s.materials[1].specular, glm::dvec3(0));
  EXPECT_FALSE(s.materials[1].shininess.has_value());  // the profile decides
  EXPECT_EQ(s.lights[0].emissivity, glm::dvec3(1));
}

TEST(ModelParser, AcceptsAMaterialUsedBeforeItIsDefined) {
  Scene s = scene_of(
      "sphere s { material late center 0 0 -5 radius 1 }\n"
      "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
      "material early { diffuse 1 }\n"
      "material late { diffuse 0.5 }\n");
  ASSERT_EQ(s.count<Sphere>(), 1u);
  EXPECT_EQ(s.materials[test::nth<Sphere>(s, 0).material].name, "late");
  EXPECT_EQ(s.materials[test::nth<Sphere>(s, 0).material].diffuse.x, 0.5);
}

TEST(ModelParser, ReadsCrlfLineEndingsAndReportsTheirPositions) {
  Scene s = scene_of(
      "camera c\r\n{\r\n pixeldim 8 6\r\n worlddim 8 6\r\n viewpoint 4 3 5\r\n}\r\n"
      "material m # comment\r\n{ diffuse 1 }\r\n");
  EXPECT_EQ(s.cameras[0].viewpoint.z, 5.0);
  Diagnostic d = single_error_of_file(
      "camera c\r\n{\r\n pixeldim 8 6\r\n worlddim 8 6\r\n viewpoint 4 3 5\r\n}\r\n"
      "material m\r\n{ difuse 1 }\r\n");
  EXPECT_TRUE(is_diag(d, "unknown-attribute", 8, 3, "did you mean 'diffuse'?"));
}

// Old Mac files end lines with '\r' alone: a comment ends there, and places count lines.
TEST(ModelParser, ReadsCrOnlyLineEndingsAndReportsTheirPositions) {
  Scene s = scene_of(
      "# a comment\rcamera c\r{\r pixeldim 8 6\r worlddim 8 6\r viewpoint 4 3 5\r}\r"
      "material m # comment\r{ diffuse 1 }\r");
  EXPECT_EQ(s.cameras[0].viewpoint.z, 5.0);
  EXPECT_EQ(s.materials.size(), 1u);
  const std::string text =
      "camera c\r{\r pixeldim 8 6\r worlddim 8 6\r viewpoint 4 3 5\r}\r"
      "material m\r{ difuse 1 }\r";
  Diagnostic d = single_error_of_file(text);
  EXPECT_TRUE(is_diag(d, "unknown-attribute", 8, 3, "did you mean 'diffuse'?"));
  // The excerpt is that line alone.
  EXPECT_TRUE(has_text(format_diagnostic(d, "old.txt", text), "\n  { difuse 1 }\n    ^\n"))
      << format_diagnostic(d, "old.txt", text);
}

TEST(ModelParser, SkipsAByteOrderMarkAndCountsColumnsAfterIt) {
  std::string bom = "\xEF\xBB\xBF";
  Scene s = scene_of(bom + with_head("sphere s { material m center 0 0 -5 radius 1 }\n"));
  EXPECT_EQ(s.count<Sphere>(), 1u);
  Diagnostic d = single_error_of_file(bom + "camra c { }\n");
  EXPECT_TRUE(is_diag(d, "unknown-entity", 1, 1, "unknown entity 'camra'"));
}

TEST(ModelParser, SeparatesTokensWithTabsAndCountsATabAsOneColumn) {
  Scene s = scene_of(with_head("sphere\ts\t{\tmaterial\tm\tcenter\t0\t0\t-5\tradius\t1\t}\n"));
  EXPECT_EQ(s.count<Sphere>(), 1u);
  Diagnostic d = single_error("\t\tsphere s { material m center 0 0 -5 radius 0 }\n");
  EXPECT_TRUE(is_diag(d, "out-of-range", 3, 46, "'radius' must be > 0"));
}

TEST(ModelParser, UsesTheFirstOfSeveralCameras) {
  Scene s = scene_of(
      "camera front { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
      "camera back { pixeldim 4 3 worlddim 8 6 viewpoint 4 3 -5 }\n");
  ASSERT_EQ(s.cameras.size(), 2u);
  EXPECT_EQ(s.find_camera(""), 0);
  EXPECT_EQ(s.find_camera("back"), 1);
  EXPECT_EQ(s.find_camera("side"), std::nullopt);
}

TEST(ModelParser, RecordsTheSourcePositionOfEveryValue) {
  Diagnostics diags;
  SceneDesc desc = parse_model("light top\n{ location 1 2\n   3 }\n", diags);
  ASSERT_FALSE(diags.has_errors()) << dump(diags);
  ASSERT_EQ(desc.entities.size(), 1u);
  const EntityDesc& e = desc.entities[0];
  EXPECT_EQ(e.kind, EntityKind::light);
  EXPECT_EQ(e.name, "top");
  EXPECT_EQ(e.where.line, 1);
  EXPECT_EQ(e.name_where.column, 7);
  ASSERT_EQ(e.attrs.size(), 1u);
  EXPECT_EQ(e.attrs[0].key, "location");
  EXPECT_EQ(e.attrs[0].numbers, (std::vector<double>{1, 2, 3}));
  ASSERT_EQ(e.attrs[0].value_where.size(), 3u);
  EXPECT_EQ(e.attrs[0].value_where[2].line, 3);
  EXPECT_EQ(e.attrs[0].value_where[2].column, 4);
}

// --- What the user sees ---------------------------------------------------------------------

TEST(ModelParser, FormatsAnErrorWithFileLineColumnSourceAndCaret) {
  std::string text = with_head("sphere s\n{  material m\n   center 0 0 -5\n   radious 1\n}\n");
  LoadedScene loaded = load_scene(text);
  EXPECT_EQ(format_diagnostics(loaded.diags, "scene.txt", text),
            "scene.txt:6:4: error: unknown attribute 'radious' for sphere 's' (attributes: "
            "material, center, radius) (did you mean 'radius'?)\n"
            "     radious 1\n"
            "     ^\n");
}

TEST(ModelParser, KeepsControlBytesOutOfMessages) {
  std::string text = with_head("sphere s { material m center 0 0 -5 radius 1\x1b[2J }\n");
  LoadedScene loaded = load_scene(text);
  ASSERT_TRUE(loaded.diags.has_errors());
  for (const Diagnostic& d : loaded.diags.items())
    for (char c : d.message) EXPECT_GE(static_cast<unsigned char>(c), 0x20) << d.message;
}

// --- Hostile input --------------------------------------------------------------------------

// Every diagnostic of `text` points inside it (or nowhere) and is one printable line.
void expect_sane(std::string_view text, const LoadedScene& loaded) {
  const int lines = 1 + static_cast<int>(count_lines(text));  // as util/lines.h counts them
  EXPECT_LE(loaded.diags.items().size(), 2 * Diagnostics::kMaxErrors);
  for (const Diagnostic& d : loaded.diags.items()) {
    EXPECT_FALSE(d.code.empty());
    EXPECT_FALSE(d.message.empty());
    EXPECT_LE(d.message.size(), 1000u);
    EXPECT_EQ(d.message.find('\n'), std::string::npos) << d.message;
    EXPECT_GE(d.where.line, 0);
    EXPECT_LE(d.where.line, lines);
    if (d.where.line > 0) {
      EXPECT_GE(d.where.column, 1);
    }
  }
  EXPECT_EQ(loaded.scene.has_value(), !loaded.diags.has_errors());
}

TEST(ModelParser, SurvivesEveryTruncationOfTheLectureScene) {
  for (size_t n = 0; n <= kLecture.size(); ++n) {
    std::string_view text = kLecture.substr(0, n);
    LoadedScene loaded = load_scene(text);
    expect_sane(text, loaded);
    if (::testing::Test::HasFailure()) {
      ADD_FAILURE() << "at length " << n;
      return;
    }
  }
}

TEST(ModelParser, SurvivesRandomBytes) {
  std::mt19937 rng(20240601);
  for (int round = 0; round < 300; ++round) {
    std::string text(rng() % 400, '\0');
    for (char& c : text) c = static_cast<char>(rng() & 0xff);
    LoadedScene loaded = load_scene(text);
    expect_sane(text, loaded);
    if (::testing::Test::HasFailure()) {
      ADD_FAILURE() << "round " << round;
      return;
    }
  }
}

TEST(ModelParser, SurvivesRandomTokenSoup) {
  const char* tokens[] = {"camera",   "material",   "light",   "sphere",  "plane",    "pixeldim",
                          "worlddim", "viewpoint",  "ambient", "diffuse", "specular", "shininess",
                          "location", "emissivity", "center",  "radius",  "normal",   "point",
                          "{",        "}",          "{",       "}",       "m",        "s",
                          "1",        "-2.5",       ".5",      "0",       "nan",      "1e400",
                          "#",        "//",         "\n",      "\r\n",    "\t",       "x",
                          "12abc",    "}{",         "{}"};
  std::mt19937 rng(7);
  for (int round = 0; round < 2000; ++round) {
    std::string text;
    int n = static_cast<int>(rng() % 60);
    for (int i = 0; i < n; ++i) {
      text += tokens[rng() % std::size(tokens)];
      text += rng() % 4 == 0 ? "" : " ";
    }
    LoadedScene loaded = load_scene(text);
    expect_sane(text, loaded);
    if (::testing::Test::HasFailure()) {
      ADD_FAILURE() << "round " << round << ":\n" << text;
      return;
    }
  }
}

TEST(ModelParser, SurvivesDeepAndLongInput) {
  auto start = std::chrono::steady_clock::now();
  for (std::string text :
       {std::string(200000, '{'), std::string(200000, '}'), std::string(1 << 20, 'a'),
        std::string(1 << 20, '1'), "sphere " + std::string(100000, '{'), std::string(100000, '\0'),
        "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 " + std::string(100000, '{')}) {
    LoadedScene loaded = load_scene(text);
    expect_sane(text, loaded);
    EXPECT_TRUE(loaded.diags.has_errors());
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20));
}

}  // namespace
}  // namespace rayfarm
