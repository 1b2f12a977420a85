// Diagnostics: the error cap, typo suggestions and the clang-style text users read.
#include "rayfarm/diagnostic.h"
#include "rayfarm/load.h"

#include <gtest/gtest.h>

#include <array>
#include <span>
#include <vector>
#include <string>
#include <string_view>

namespace rayfarm {
namespace {

constexpr std::array<std::string_view, 3> kSphereAttrs = {"material", "center", "radius"};
constexpr std::array<std::string_view, 5> kEntities = {"camera", "material", "light", "sphere",
                                                       "plane"};

TEST(NearestWord, SuggestsTheAttributeOneLetterAway) {
  EXPECT_EQ(nearest_word("radious", kSphereAttrs), "radius");
  EXPECT_EQ(nearest_word("centre", kSphereAttrs), "center");
  EXPECT_EQ(nearest_word("sphre", kEntities), "sphere");
  EXPECT_EQ(nearest_word("camra", kEntities), "camera");
}

TEST(NearestWord, CountsASwapOfNeighbouringLettersAsOneTypo) {
  EXPECT_EQ(nearest_word("lihgt", kEntities), "light");
  EXPECT_EQ(nearest_word("shpere", kEntities), "sphere");
  EXPECT_EQ(nearest_word("raduis", kSphereAttrs), "radius");
}

TEST(NearestWord, SuggestsTheLowerCaseKeywordForACapitalisedOne) {
  EXPECT_EQ(nearest_word("Sphere", kEntities), "sphere");
  EXPECT_EQ(nearest_word("CAMERA", kEntities), "camera");
}

TEST(NearestWord, SuggestsAPlausibleMisspellingOfAShortWord) {
  EXPECT_EQ(nearest_word("plain", kEntities), "plane");
}

// Past kMaxHintCandidates names no hint is looked for: a file of 20,000 materials and
// 200,000 references to missing ones took minutes when each looked at every name.
TEST(NearestWord, ManyCandidatesGiveNoHint) {
  std::vector<std::string> owned;
  for (size_t i = 0; i <= kMaxHintCandidates; ++i) owned.push_back("mat" + std::to_string(i));
  std::vector<std::string_view> names(owned.begin(), owned.end());
  const std::span<const std::string_view> all(names);
  EXPECT_EQ(nearest_word("mat7x", all.first(kMaxHintCandidates)), "mat7");
  EXPECT_EQ(nearest_word("mat7x", all), "");

  // Each undefined reference is still an error, without the hint, and the list shows 12.
  auto undefined = [](size_t materials) {
    std::string text = "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n";
    for (size_t i = 0; i < materials; ++i)
      text += "material mat" + std::to_string(i) + " { ambient 1 }\n";
    for (size_t i = 0; i < 2000; ++i)
      text += "sphere { material mat" + std::to_string(i) + "x center 4 3 -4 radius 1 }\n";
    return load_scene(text).diags;
  };
  const Diagnostics few = undefined(50), many = undefined(20000);
  EXPECT_EQ(few.error_count(), 2000u);
  EXPECT_EQ(many.error_count(), 2000u);
  EXPECT_NE(few.items()[0].message.find("(did you mean 'mat0'?); defined: mat0, mat1, mat10"),
            std::string::npos)
      << few.items()[0].message;
  EXPECT_EQ(many.items()[0].message,
            "undefined material 'mat0x' in sphere; defined: mat0, mat1, mat10, mat100, mat1000, "
            "mat10000, mat10001, mat10002, mat10003, mat10004, mat10005, mat10006, ...");
}

TEST(NearestWord, SuggestsNothingForUnrelatedWords) {
  EXPECT_EQ(nearest_word("foo", kSphereAttrs), "");
  EXPECT_EQ(nearest_word("texture", kSphereAttrs), "");
  EXPECT_EQ(nearest_word("triangle", kEntities), "");
  EXPECT_EQ(nearest_word("x", kEntities), "");
}

TEST(NearestWord, SuggestsNothingForEmptyOrHugeInputOrNoCandidates) {
  EXPECT_EQ(nearest_word("", kEntities), "");
  EXPECT_EQ(nearest_word(std::string(100000, 's'), kEntities), "");
  EXPECT_EQ(nearest_word("sphere", std::span<const std::string_view>{}), "");
}

TEST(NearestWord, DoesNotSuggestReplacingAWholeShortName) {
  // Any one-letter name is one edit from any other: that is no hint at all.
  constexpr std::array<std::string_view, 2> names = {"m", "k"};
  EXPECT_EQ(nearest_word("x", names), "");
  EXPECT_EQ(nearest_word("mm", names), "");
  constexpr std::array<std::string_view, 2> words = {"chrome", "floor"};
  EXPECT_EQ(nearest_word("crome", words), "chrome");
}

TEST(Diagnostics, CountsErrorsButKeepsOnlyTheFirstUpToTheCap) {
  Diagnostics diags;
  for (size_t i = 0; i < Diagnostics::kMaxErrors + 10; ++i)
    diags.error("syntax", "error " + std::to_string(i), {static_cast<int>(i) + 1, 1, {}});
  EXPECT_TRUE(diags.has_errors());
  EXPECT_TRUE(diags.truncated());
  EXPECT_EQ(diags.error_count(), Diagnostics::kMaxErrors + 10);
  ASSERT_EQ(diags.items().size(), Diagnostics::kMaxErrors);
  EXPECT_EQ(diags.items().front().message, "error 0");
  EXPECT_EQ(diags.items().back().message, "error " + std::to_string(Diagnostics::kMaxErrors - 1));
}

TEST(Diagnostics, IsNotTruncatedAtExactlyTheCap) {
  Diagnostics diags;
  for (size_t i = 0; i < Diagnostics::kMaxErrors; ++i) diags.error("syntax", "e", {});
  EXPECT_FALSE(diags.truncated());
  EXPECT_EQ(diags.items().size(), Diagnostics::kMaxErrors);
}

TEST(Diagnostics, WarningsAreNotErrors) {
  Diagnostics diags;
  diags.warning("unused-material", "material 'm' is never used", {3, 1, {}});
  EXPECT_FALSE(diags.has_errors());
  EXPECT_EQ(diags.error_count(), 0u);
  EXPECT_EQ(diags.first_error(), nullptr);
  ASSERT_EQ(diags.items().size(), 1u);
  EXPECT_EQ(diags.items()[0].severity, Severity::warning);
}

TEST(Diagnostics, FirstErrorSkipsWarnings) {
  Diagnostics diags;
  diags.warning("w", "a warning", {});
  diags.error("e1", "first", {});
  diags.error("e2", "second", {});
  ASSERT_NE(diags.first_error(), nullptr);
  EXPECT_EQ(diags.first_error()->code, "e1");
}

TEST(Diagnostics, CapsWarningsToo) {
  Diagnostics diags;
  for (int i = 0; i < 10000; ++i) diags.warning("w", "w", {});
  EXPECT_LE(diags.items().size(), 2 * Diagnostics::kMaxErrors);
  EXPECT_TRUE(diags.truncated());
  EXPECT_FALSE(diags.has_errors());
}

TEST(Diagnostics, ReplacesControlCharactersInMessagesAndPaths) {
  Diagnostics diags;
  diags.error("x", "unknown key \"a\nb\x1b[2J\"", {0, 0, "/a\tb"});
  EXPECT_EQ(diags.items()[0].message, "unknown key \"a?b?[2J\"");
  EXPECT_EQ(diags.items()[0].where.path, "/a?b");
}

TEST(Diagnostics, KeepsValidUtf8AndReplacesInvalidBytes) {
  Diagnostics diags;
  diags.error("x", "gr\xc3\xb6\xc3\x9f\xe2\x82\xac", {});
  diags.error("x", "a\xff\xc3x\xed\xa0\x80z\xf0\x9f\x98", {});
  EXPECT_EQ(diags.items()[0].message, "gr\xc3\xb6\xc3\x9f\xe2\x82\xac");
  EXPECT_EQ(diags.items()[1].message, "a??x???z???");
}

TEST(Diagnostics, ShortensHugeMessages) {
  Diagnostics diags;
  diags.warning("x", "name '" + std::string(1 << 20, 'n') + "'", {});
  EXPECT_LE(diags.items()[0].message.size(), 1000u);
  EXPECT_TRUE(diags.items()[0].message.ends_with("..."));
}

TEST(FormatDiagnostic, PrintsPositionMessageSourceLineAndCaret) {
  std::string_view source = "sphere s\n{  radious 1\n}\n";
  Diagnostic d{Severity::error, "unknown-attribute", "unknown attribute 'radious'", {2, 4, {}}};
  EXPECT_EQ(format_diagnostic(d, "scene.txt", source),
            "scene.txt:2:4: error: unknown attribute 'radious'\n"
            "  {  radious 1\n"
            "     ^\n");
}

TEST(FormatDiagnostic, PutsTheCaretUnderColumnOne) {
  Diagnostic d{Severity::error, "unknown-entity", "unknown entity 'sphre'", {1, 1, {}}};
  EXPECT_EQ(format_diagnostic(d, "a.txt", "sphre s {}"),
            "a.txt:1:1: error: unknown entity 'sphre'\n"
            "  sphre s {}\n"
            "  ^\n");
}

TEST(FormatDiagnostic, KeepsTabsSoTheCaretLinesUp) {
  Diagnostic d{Severity::error, "x", "bad", {1, 3, {}}};
  EXPECT_EQ(format_diagnostic(d, "f", "\t\tradius x\n"),
            "f:1:3: error: bad\n"
            "  \t\tradius x\n"
            "  \t\t^\n");
}

// The column counts bytes; the caret goes under the character the line shows there, after
// names in other scripts too (it sat one space right per extra byte).
TEST(FormatDiagnostic, TheCaretCountsCharactersNotBytes) {
  const std::string line = "material caf\xC3\xA9 { diffuse \xE2\x80\x94 }";  // é, then an em dash
  Diagnostic d{Severity::error, "x", "bad", {1, static_cast<int>(line.find("\xE2")) + 1, {}}};
  EXPECT_EQ(d.where.column, 26);  // 24 characters before it, 25 bytes
  EXPECT_EQ(format_diagnostic(d, "f", line),
            "f:1:26: error: bad\n"
            "  " + line + "\n"
            "  " + std::string(24, ' ') + "^\n");
}

TEST(FormatDiagnostic, DropsTheCarriageReturnOfCrlfLines) {
  Diagnostic d{Severity::error, "x", "bad", {2, 2, {}}};
  EXPECT_EQ(format_diagnostic(d, "f", "camera\r\n{ pixeldim\r\n}\r\n"),
            "f:2:2: error: bad\n"
            "  { pixeldim\n"
            "   ^\n");
}

TEST(FormatDiagnostic, PrintsWarningsAsWarnings) {
  Diagnostic d{Severity::warning, "unused-material", "material 'm' is never used", {1, 1, {}}};
  EXPECT_EQ(format_diagnostic(d, "f", "material m {}"),
            "f:1:1: warning: material 'm' is never used\n"
            "  material m {}\n"
            "  ^\n");
}

TEST(FormatDiagnostic, PrintsPathDiagnosticsWithTheirJsonPointer) {
  Diagnostic d{
      Severity::error, "out-of-range", "'radius' must be > 0, got 0", {0, 0, "/objects/0/radius"}};
  EXPECT_EQ(format_diagnostic(d, "scene.json", "{}"),
            "scene.json: error: at /objects/0/radius: 'radius' must be > 0, got 0\n");
}

TEST(FormatDiagnostic, PrintsOnlyTheFileForADiagnosticWithoutAPlace) {
  Diagnostic d{Severity::error, "no-camera", "no camera", {}};
  EXPECT_EQ(format_diagnostic(d, "s.txt", "material m {}\n"), "s.txt: error: no camera\n");
}

TEST(FormatDiagnostic, SurvivesAPositionPastTheEndOfTheSource) {
  Diagnostic d{Severity::error, "x", "bad", {99, 500, {}}};
  EXPECT_EQ(format_diagnostic(d, "f", "one line\n"), "f:99:500: error: bad\n");
  Diagnostic e{Severity::error, "x", "bad", {1, 500, {}}};
  std::string text = format_diagnostic(e, "f", "short");
  EXPECT_EQ(text, "f:1:500: error: bad\n  short\n       ^\n");
}

TEST(FormatDiagnostic, ShowsTheStretchOfAnOverlongLineAroundItsColumn) {
  Diagnostic d{Severity::error, "x", "bad", {1, 1, {}}};
  EXPECT_EQ(format_diagnostic(d, "f", std::string(100000, 'a')),
            "f:1:1: error: bad\n  " + std::string(60, 'a') + "...\n  ^\n");
  // Minified JSON: one long line, the error in its middle.
  std::string line = std::string(500, 'a') + "b" + std::string(500, 'c');
  d.where.column = 501;
  EXPECT_EQ(format_diagnostic(d, "f", line), "f:1:501: error: bad\n  ..." + std::string(60, 'a') +
                                                 "b" + std::string(59, 'c') + "...\n     " +
                                                 std::string(60, ' ') + "^\n");
  // Never inside a UTF-8 character: the cut moves to its start.
  std::string utf8;
  for (int i = 0; i < 300; ++i) utf8 += "\xC3\xA9";  // é
  d.where.column = 301;  // the first byte of the 151st é
  const std::string shown = format_diagnostic(d, "f", utf8);
  EXPECT_NE(shown.find("  ...\xC3\xA9"), std::string::npos) << shown;
}

TEST(FormatDiagnostics, EndsWithANoteWhenErrorsWereDropped) {
  Diagnostics diags;
  for (size_t i = 0; i < Diagnostics::kMaxErrors + 5; ++i) diags.error("x", "bad", {});
  std::string text = format_diagnostics(diags, "f", "");
  EXPECT_NE(
      text.find("f: note: too many errors; " + std::to_string(Diagnostics::kMaxErrors + 5) +
                " in all, only the first " + std::to_string(Diagnostics::kMaxErrors) + " shown\n"),
      std::string::npos);
}

TEST(FormatDiagnostics, PrintsEveryDiagnosticInOrder) {
  Diagnostics diags;
  diags.error("a", "first", {1, 1, {}});
  diags.error("b", "second", {0, 0, "/x"});
  EXPECT_EQ(format_diagnostics(diags, "f", "abc\n"),
            "f:1:1: error: first\n  abc\n  ^\nf: error: at /x: second\n");
}

}  // namespace
}  // namespace rayfarm

namespace rayfarm {
namespace {

TEST(NotAScene, ImagesAndBinaryDataAreNamedNotParsed) {
  const std::pair<std::string, std::string> cases[] = {
      {std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16), "this is a PNG image"},
      {"P6\n2 2\n255\n\x01\x02\x03", "this is a PPM image"},
      {"P3\n# comment\n1 1\n255\n0 0 0\n", "this is a PPM image"},
      {"\xFF\xD8\xFF\xE0", "this is a JPEG image"},
      // UTF-16 as editors save it: with a byte-order mark either way, or without one.
      {std::string("\xFF\xFE" "c\0a\0m\0", 8), "this is UTF-16 text (save the scene as UTF-8)"},
      {std::string("\xFE\xFF\0c\0a", 6), "this is UTF-16 text"},
      {std::string("c\0a\0m\0e\0", 8), "this is UTF-16 text"},
      {std::string("\0{\0\"", 4), "this is UTF-16 text"}};
  for (const auto& [bytes, expected] : cases) {
    LoadedScene loaded = load_scene(bytes);
    ASSERT_FALSE(loaded.scene);
    ASSERT_EQ(loaded.diags.items().size(), 1u) << expected;
    EXPECT_EQ(loaded.diags.items()[0].message.rfind(expected, 0), 0u) << loaded.diags.items()[0].message;
  }
  // A scene that merely starts with a P is a scene.
  EXPECT_FALSE(load_scene("Plane p { }").diags.items().empty());
  EXPECT_NE(load_scene("Plane p { }").diags.items()[0].code, "not-a-scene");
}

TEST(NotAScene, SourceExcerptsNeverCarryControlBytes) {
  const std::string text = "camera c\n\x1b[31mEVIL\x1b[0m \xC3\xA9t\xE9 sphere\n";
  LoadedScene loaded = load_scene(text);
  ASSERT_FALSE(loaded.diags.items().empty());
  const std::string shown = format_diagnostics(loaded.diags, "esc.txt", text);
  EXPECT_EQ(shown.find('\x1b'), std::string::npos);
  EXPECT_NE(shown.find("?[31mEVIL?[0m \xC3\xA9t? sphere"), std::string::npos) << shown;  // UTF-8 kept
}

}  // namespace
}  // namespace rayfarm
