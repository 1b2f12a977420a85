// The course lint (where the course's reference program would stop or misread): one row per
// rule with its exact position, the reference's own files giving no warning, no cascades.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <string_view>

#include "rayfarm/lint.h"

namespace rayfarm {
namespace {

// A camera and a material on lines 1 and 2, so the text under test starts on line 3.
constexpr std::string_view kHead =
    "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
    "material m { diffuse 1 1 1 }\n";

Diagnostics lint(std::string_view text) {
  Diagnostics diags;
  lint_course(text, diags);
  return diags;
}

std::string dump(const Diagnostics& diags) {
  std::string out;
  for (const Diagnostic& d : diags.items())
    out += std::to_string(d.where.line) + ":" + std::to_string(d.where.column) + " " + d.code +
           ": " + d.message + "\n";
  return out;
}

struct Row {
  std::string_view name;
  std::string_view code;
  int line;
  int column;
  std::string_view text;  // after kHead
};

// Each problem once, at the token where the course's program fails (too few values: at the
// attribute), and nothing else: the lint resynchronises without a cascade.
constexpr Row kRows[] = {
    {"CommentAtTopLevel", "course-comment", 3, 1,
     "# the scene\nsphere s { material m center 0 0 -5 radius 1 }\n"},
    {"CommentAfterAValue", "course-comment", 3, 46,
     "sphere s { material m center 0 0 -5 radius 1 // big\n}\n"},
    {"CommentGluedToAValue", "course-comment", 3, 45,
     "sphere s { material m center 0 0 -5 radius 1#big\n}\n"},
    {"BlockComment", "course-comment", 3, 12,
     "sphere s { /* the ball */ material m center 0 0 -5 radius 1 }\n"},
    {"UnknownEntity", "course-unknown-entity", 3, 1,
     "sphre s { material m center 0 0 -5 radius 1 }\n"},
    {"CapitalisedEntity", "course-unknown-entity", 3, 1,
     "Sphere s { material m center 0 0 -5 radius 1 }\n"},
    {"Pplane", "course-unknown-entity", 3, 1,
     "pplane p { material m normal 0 1 0 point 0 0 0 shader 1 }\n"},
    {"Tri2009", "course-unknown-entity", 3, 1,
     "tri t { material m v0 0 0 -5 v1 1 0 -5 v2 0 1 -5 }\n"},
    {"StrayValueBetweenEntities", "course-unknown-entity", 4, 1,
     "sphere s { material m center 0 0 -5 radius 1 }\n0.5\nlight l { location 0 0 0 "
     "emissivity 1 1 1 }\n"},
    {"UnknownAttribute", "course-unknown-attribute", 3, 37,
     "sphere s { material m center 0 0 -5 radious 1 }\n"},
    {"AttributeOfAnotherEntity", "course-unknown-attribute", 3, 43,
     "light l { location 0 0 0 emissivity 1 1 1 theta 10 }\n"},
    {"Dimension2009", "course-unknown-attribute", 3, 53,
     "tiled_plane t { material m normal 0 1 0 point 0 0 0 dimension 1 1 altmaterial m }\n"},
    {"V0Of2009InATriangle", "course-unknown-attribute", 3, 25,
     "triangle t { material m v0 0 0 -5 v1 1 0 -5 v2 0 1 -5 }\n"},
    {"PointBeforeXdirMissing", "course-order", 3, 36,
     "fplane f { material m normal 0 0 1 xdir 1 0 0 point 0 0 -5 dimensions 1 1 }\n"},
    {"TexnameBeforeXdir", "course-order", 4, 51,
     "texture t { filename a.ppm }\ntexplane p { material m normal 0 0 1 point 0 0 -5 "
     "texname t xdir 1 0 0 dimensions 1 1 mode 0 }\n"},
    {"ThetaBeforeEmissivity", "course-order", 3, 30,
     "spotlight s { location 0 0 0 theta 10 emissivity 1 1 1 point 0 0 -5 }\n"},
    {"PlaneAttributeAfterTheFinitePlaneGroup", "course-order", 3, 60,
     "fplane f { material m normal 0 0 1 point 0 0 -5 xdir 1 0 0 normal 0 0 1 dimensions "
     "1 1 }\n"},
    {"ProjectorPlaneBeforeLight", "course-order", 3, 32,
     "projector p { emissivity 1 1 1 normal 0 0 1 location 0 0 0 point 0 0 -1 xdir 1 0 0 "
     "dimensions 1 1 texname a.ppm mode 0 }\n"},
    {"MaterialNotFirst", "course-material-first", 3, 12,
     "sphere s { center 0 0 -5 material m radius 1 }\n"},
    {"UndefinedMaterial", "course-undefined-material", 3, 21,
     "sphere s { material chrome center 0 0 -5 radius 1 }\n"},
    {"MaterialDefinedLater", "course-undefined-material", 3, 21,
     "sphere s { material red center 0 0 -5 radius 1 }\nmaterial red { diffuse 1 0 0 }\n"},
    {"UndefinedAltmaterial", "course-undefined-material", 3, 91,
     "tiled_plane t { material m normal 0 1 0 point 0 0 0 xdir 1 0 0 dimensions 1 1 "
     "altmaterial mm }\n"},
    {"LongEntityName", "course-name-length", 3, 8,
     "sphere a_name_of_thirty_two_characters_ { material m center 0 0 -5 radius 1 }\n"},
    {"LongMaterialName", "course-name-length", 3, 10,
     "material a_material_named_with_32_chars__ { diffuse 1 1 1 }\n"},
    {"LongTexname", "course-name-length", 3, 85,
     "texplane p { material m normal 0 0 1 point 0 0 -5 xdir 1 0 0 dimensions 1 1 texname "
     "images/xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx.ppm mode 0 }\n"},
    {"TooFewValues", "course-value-count", 3, 23, "sphere s { material m center 0 0 radius 1 }\n"},
    {"OneNumberColour", "course-value-count", 3, 14, "material n { diffuse 1 }\n"},
    {"TooManyValues", "course-value-count", 3, 46,
     "sphere s { material m center 0 0 -5 radius 1 2 }\n"},
    {"Specular2009", "course-value-count", 3, 27, "material n { specular 0.3 0.3 0.3 }\n"},
    {"NoAltmaterialName", "course-value-count", 3, 79,
     "tiled_plane t { material m normal 0 1 0 point 0 0 0 xdir 1 0 0 dimensions 1 1 "
     "altmaterial }\n"},
    {"FractionalPixeldim", "course-number", 3, 21,
     "camera d { pixeldim 640.5 480 worlddim 8 6 viewpoint 4 3 5 }\n"},
    {"FractionalMode", "course-number", 3, 96,
     "texplane p { material m normal 0 0 1 point 0 0 -5 xdir 1 0 0 dimensions 1 1 texname "
     "a.ppm mode 1.0 }\n"},
    {"TwoDecimalPoints", "course-number", 3, 44,
     "sphere s { material m center 0 0 -5 radius 1.5.2 }\n"},
    {"AngleBracketVector", "course-vector-syntax", 3, 30,
     "sphere s { material m center <0,0,-5> radius 1 }\n"},
    {"SpacedAngleBracketVector", "course-vector-syntax", 3, 30,
     "sphere s { material m center <0, 0, -5> radius 1 }\n"},
    {"CommaVector", "course-vector-syntax", 3, 30,
     "sphere s { material m center 0,0,-5 radius 1 }\n"},
    {"BraceGluedToTheName", "course-brace", 3, 9,
     "sphere s{ material m center 0 0 -5 radius 1 }\n"},
    {"BraceGluedToTheKeyword", "course-brace", 3, 6, "light{ location 0 0 0 emissivity 1 1 1 }\n"},
    {"WordGluedAfterTheBrace", "course-brace", 3, 10,
     "sphere s {material m center 0 0 -5 radius 1 }\n"},
    {"WordGluedAfterTheClosingBrace", "course-brace", 3, 46,
     "sphere s { material m center 0 0 -5 radius 1 }light l { location 0 0 0 emissivity 1 "
     "1 1 }\n"},
    {"BraceGluedToAMaterialName", "course-brace", 3, 92,
     "tiled_plane t { material m normal 0 1 0 point 0 0 0 xdir 1 0 0 dimensions 1 1 "
     "altmaterial m}\n"},
    {"BraceGluedToAFileName", "course-brace", 3, 38, "texture t { filename images/brick.ppm}\n"},
    {"NoOpeningBrace", "course-brace", 3, 10, "sphere s material m center 0 0 -5 radius 1 }\n"},
    {"NoClosingBraceBeforeTheNextEntity", "course-brace", 4, 1,
     "sphere s { material m center 0 0 -5 radius 1\nlight l { location 0 0 0 emissivity 1 "
     "1 1 }\n"},
    {"NotClosedAtTheEnd", "course-brace", 3, 1, "sphere s { material m center 0 0 -5 radius 1\n"},
    {"ExtraClosingBrace", "course-brace", 4, 1,
     "sphere s { material m center 0 0 -5 radius 1 }\n}\n"},
    {"NoName", "course-missing-name", 3, 8, "sphere { material m center 0 0 -5 radius 1 }\n"},
    {"MissingRadius", "course-missing-attribute", 3, 37, "sphere s { material m center 0 0 -5 }\n"},
    {"MissingEmissivity", "course-missing-attribute", 3, 26, "light l { location 0 0 0 }\n"},
    {"EmptyMaterial", "course-missing-attribute", 3, 14, "material n { }\n"},
    {"RepeatedPlaneAttribute", "course-duplicate-attribute", 3, 36,
     "fplane f { material m normal 0 0 1 normal 0 0 1 point 0 0 -5 xdir 1 0 0 dimensions "
     "1 1 }\n"},
    {"SecondMaterial", "course-duplicate-attribute", 3, 37,
     "sphere s { material m center 0 0 -5 material m radius 1 }\n"},
    {"UndefinedTexture", "course-undefined-texture", 4, 85,
     "texture brick { filename brick.ppm }\ntexplane p { material m normal 0 0 1 point 0 "
     "0 -5 xdir 1 0 0 dimensions 1 1 texname brik mode 0 }\n"},
};

TEST(CourseLint, ReportsEachRuleOnceAtItsToken) {
  for (const Row& row : kRows) {
    Diagnostics diags = lint(std::string(kHead) + std::string(row.text));
    SCOPED_TRACE(std::string(row.name) + "\n" + dump(diags));
    if (diags.items().size() != 1) {
      ADD_FAILURE() << "expected exactly one warning";
      continue;
    }
    const Diagnostic& d = diags.items()[0];
    EXPECT_EQ(d.severity, Severity::warning);
    EXPECT_EQ(d.code, row.code);
    EXPECT_EQ(d.where.line, row.line);
    EXPECT_EQ(d.where.column, row.column);
    EXPECT_NE(d.message.find("the course's "), std::string::npos);
  }
}

TEST(CourseLint, SaysWhatTheProgramWouldDoAndHowToFixIt) {
  auto message = [](std::string_view body) {
    Diagnostics diags = lint(std::string(kHead) + std::string(body));
    return diags.items().empty() ? std::string() : diags.items()[0].message;
  };
  // texplane6's material, which stopped the reference program.
  EXPECT_EQ(message("material oak_tex { ambient 1.0 1.0 1.0 specular 0.3 0.3 0.3 }\n"),
            "'0.3' is a value too many for specular, which takes 1 number in the 2014-18 "
            "program: the course's program would read '0.3' as an attribute name and stop with "
            "'bad attr 0.3'; write 'specular 0.3' (three numbers were the 2009 program's form)");
  EXPECT_EQ(message("sphere s { material m center 0 0 -5 radious 1 }\n"),
            "sphere 's' has no attribute 'radious' in the course's program: it stops here with "
            "'bad attr radious' (did you mean 'radius'?)");
  EXPECT_EQ(message("fplane f { material m normal 0 0 1 xdir 1 0 0 point 0 0 -5 "
                    "dimensions 1 1 }\n"),
            "the course's program reads the attributes of fplane 'f' in groups (normal and point "
            "first, then xdir and dimensions): with point not yet given it would stop here with "
            "'bad attr xdir'; give point before xdir");
  EXPECT_EQ(message("material n { diffuse 1 }\n"),
            "diffuse takes 3 numbers, given 1: the course's program would try to read '}' as "
            "the next one and stop; give all 3: 'diffuse 1 1 1'");
  EXPECT_NE(message("sphere s { material red center 0 0 -5 radius 1 }\n"
                    "material red { diffuse 1 0 0 }\n")
                .find("(it is defined later, at line 4)"),
            std::string::npos);
  EXPECT_NE(message("tri t { material m v0 0 0 -5 v1 1 0 -5 v2 0 1 -5 }\n").find("2009"),
            std::string::npos);
  EXPECT_NE(message("light l { location 0 0 0 emissivity 1 1 1 theta 10 }\n")
                .find("(theta is an attribute of spotlight)"),
            std::string::npos);
}

TEST(CourseLint, ReportsAByteOrderMarkAtTheStart) {
  Diagnostics diags = lint("\xEF\xBB\xBF" + std::string(kHead));
  ASSERT_EQ(diags.items().size(), 1u) << dump(diags);
  EXPECT_EQ(diags.items()[0].code, "course-unknown-entity");
  EXPECT_EQ(diags.items()[0].where, (Where{1, 1, {}}));
}

TEST(CourseLint, ReportsABlockOfCommentLinesOnce) {
  Diagnostics diags = lint("# a scene\n# of one sphere\n" + std::string(kHead) +
                           "sphere s { material m center 0 0 -5 # in front\n"
                           "           radius 1 }\n");
  ASSERT_EQ(diags.items().size(), 2u) << dump(diags);
  EXPECT_EQ(diags.items()[0].where, (Where{1, 1, {}}));
  EXPECT_EQ(diags.items()[1].where, (Where{5, 37, {}}));
}

TEST(CourseLint, ReportsEveryProblemOfAFileInOrder) {
  // The program stops at the first; the student wants them all.
  Diagnostics diags = lint(std::string(kHead) +
                           "sphere s { material chrome center 0 0 -5 radius 1 }\n"
                           "plane p { normal 0 1 0 point 0 0 0 material m }\n"
                           "material n { specular 1 1 1 }\n");
  ASSERT_EQ(diags.items().size(), 3u) << dump(diags);
  EXPECT_EQ(diags.items()[0].code, "course-undefined-material");
  EXPECT_EQ(diags.items()[1].code, "course-material-first");
  EXPECT_EQ(diags.items()[2].code, "course-value-count");
  EXPECT_EQ(diags.items()[2].where.line, 5);
}

TEST(CourseLint, Reads2009TiledPlaneAsOneProblem) {
  // The 2009 syntax misses xdir and dimensions too: the one warning says so.
  Diagnostics diags = lint(std::string(kHead) + R"(material dark { ambient 1 1 1 }
tiled_plane floor
{
   material m
   normal 0 1 0
   point 0 -0.1 0
   dimension 1.0 2.0
   altmaterial dark
}
)");
  ASSERT_EQ(diags.items().size(), 1u) << dump(diags);
  EXPECT_EQ(diags.items()[0].where, (Where{9, 4, {}}));
  EXPECT_NE(diags.items()[0].message.find("dimensions w h"), std::string::npos);
}

TEST(CourseLint, ResumesOnlyAtAKeywordThatStartsAnEntity) {
  // Prose mentions "plane" and "light" without starting one.
  Diagnostics diags = lint(std::string(kHead) +
                           "A plane and a light make the scene\n"
                           "sphere s { material m center 0 0 -5 radius 1 }\n");
  ASSERT_EQ(diags.items().size(), 1u) << dump(diags);
  EXPECT_EQ(diags.items()[0].code, "course-unknown-entity");
}

TEST(CourseLint, ReportsAGluedKeywordBraceOnceThoughTheNameIsMissing) {
  Diagnostics diags = lint(std::string(kHead) + "light{ location 0 0 0 emissivity 1 1 1 }\n");
  ASSERT_EQ(diags.items().size(), 1u) << dump(diags);
  EXPECT_EQ(diags.items()[0].code, "course-brace");
  EXPECT_NE(diags.items()[0].message.find("'light NAME {'"), std::string::npos);
}

// Files the reference program read (each has a .log of what it parsed): snippets of them, with
// their order, spacing and forms, give no warning.
constexpr std::string_view kReadByTheReference[] = {
    // scene1: the first scene.
    R"(camera cam1
{
  pixeldim  640 480
  worlddim  8 6
  viewpoint 4 3 4
}

material gray
{
   diffuse 7  7 7

}

plane backwall
{
   material gray
   normal 0 0 1
   point  0 0 -4
}

light pinkfront
{
   emissivity 8 5 5
   location 4 3 4
}
)",
    // spotlight: theta before point, inside one group.
    R"(camera cam1
{
  pixeldim  800 600
  worlddim  8 6
  viewpoint 4 3 6
}
material white
{
   ambient 0 0 0
   diffuse 6 6 6
}
plane floor
{
   material white
   normal 0 1 0
   point  0 0 0
}
spotlight red
{
   location 0 4 0
   emissivity 10 0 0
   theta  15
   point 4 0 -3
}
)",
    // proj1: a projector, point before normal, a texture two directories up.
    R"(material white
{
   ambient 1 1  1
   diffuse 4 4 4
}
plane backwall
{
   material white
   point 0 0 -6
   normal 0 0 1
}
texture mike
{
   filename  ../../images/mike.ppm
}
projector front
{
   emissivity 6 6 6
   location   4 3 2

   point      2 1.5 0
   normal     0 0 1

   xdir       1 0 0
   dimensions 4 3

   texname    mike
   mode 0
}
)",
    // texplane5: specular as one number, transparency, dimensions before xdir, a material
    // defined after objects but before its use, revsurf.
    R"(material mike_tex
{
   ambient  4.0 4.0 4.0
   diffuse  4.0 4.0 4.0
   specular 0.0
}
material gold
{
   ambient 1 1 0
   diffuse 4 4 0
   transparency 0.2
   specular 0.4
}
texture oak
{
   filename    ../../images/oak.ppm
}
texplane oak_frame
{
  material  mike_tex
  normal 0 0 1
  point  2.6 4.6 -7.95
  dimensions 6.8 8.8
  xdir 1  0.0 0
  texname oak
  mode 1
}
material see_thru
{
   diffuse 4 4 4
   transparency 0.6
}
sphere left
{
   material see_thru
   center 5 3.5 -3
   radius 2
}
revsurf vase
{
   material gold
   surfer 3
   base -2 0 -5
   direction 0 1 0
   height 6.28
}
)",
    // shiny2: tiled_plane with dimensions, altmaterial, xdir in that order; shininess.
    R"(material red
{
   ambient 1 0 0
   diffuse 5 0 0
   specular 0.5
   shininess 50
}
material gray
{
   ambient 1 1 1
}
tiled_plane floor
{
   material red
   point    0 -1 0
   normal   0 1 0

   dimensions 1 1
   altmaterial gray
   xdir       1 0 1
}
)",
    // translucent3: an fplane, extra spaces between words.
    R"(material green
{
   diffuse 0 8 2
   transparency 0.6
}
fplane  middle
{
   material green
   normal 0 0 1
   point  2 1.5 -5
   xdir   1 0 0
   dimensions   4 3
}
)",
    // tri1 (never run by the reference): a tab, the triangle with its plane.
    "camera cam\n{\n\tviewpoint 4  3  4\n   pixeldim  481  361\n   worlddim 8  6\n}\n"
    "material green\n{\n   ambient  1  7  1\n}\n"
    "triangle tri\n{\n  material green\n  normal 0 0 1\n  point  3 2 -2\n"
    "  vertex1 7 3 -2\n  vertex2 10 10 -2\n  vertex3 14 3 -2\n}\n",
    // scene1 with DOS line endings.
    "camera cam1\r\n{\r\n  pixeldim  640 480\r\n  worlddim  8 6\r\n  viewpoint 4 3 4\r\n}\r\n"
    "material gray\r\n{\r\n   diffuse 7  7 7\r\n}\r\n",
    // What fscanf reads fine: a '}' after a number, a texname that is a path, odd numbers,
    // a name of 31 characters.
    "material m { ambient 1e-1 .5 +2. diffuse 1 1 1}\n"
    "material thirty_one_characters_long_name { diffuse 1 1 1 }\n"
    "sphere s { material thirty_one_characters_long_name center 0 0 -5 radius 1 }\n"
    "texplane wall { material m normal 0 0 1 point -8 -2 -8.00 xdir 1 0 0 dimensions 30 24\n"
    "  texname ../../images/brick8.ppm mode 1 }\n"
    "triangle t { material m vertex1 0 0 -5 vertex2 1 0 -5 vertex3 0 1 -5 }\n",
};

TEST(CourseLint, FindsNothingInFilesTheReferenceProgramRead) {
  for (std::string_view text : kReadByTheReference) {
    Diagnostics diags = lint(text);
    EXPECT_TRUE(diags.items().empty()) << text << "\n" << dump(diags);
  }
}

TEST(CourseLint, FindsNothingInAnEmptyFile) {
  EXPECT_TRUE(lint("").items().empty());
  EXPECT_TRUE(lint(" \n\t\r\n").items().empty());
}

TEST(CourseLint, EndsOnAnyInput) {
  // Random words, braces, numbers and comment starts: no hang, no crash, capped output.
  constexpr std::string_view kPieces[] = {
      "{",         "}",      "{x",       "x}",    "}y",          "sphere", "material",
      "m",         "center", "1",        "1.5.2", "<1,2",        "3>",     "#",
      "//",        "/*",     "*/",       "\n",    " ",           "tri",    "texplane",
      "texname",   "mode",   ",",        "-",     "altmaterial", "normal", "xdir",
      "projector", "camera", "pixeldim", "1e",    "nan(",        "\t"};
  std::mt19937 rng(7);
  for (int round = 0; round < 300; ++round) {
    std::string text;
    for (int i = 0; i < 80; ++i) {
      text += kPieces[rng() % std::size(kPieces)];
      if (rng() % 2) text += ' ';
    }
    Diagnostics diags = lint(text);
    EXPECT_LE(diags.items().size(), 2 * Diagnostics::kMaxErrors);
  }
}

}  // namespace
}  // namespace rayfarm
