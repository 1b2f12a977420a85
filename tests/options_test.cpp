// Render options: driven from the table itself, so an option added to it is covered here
// without touching this file.
#include "rayfarm/options.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <string>

namespace rayfarm {
namespace {

RenderOptions with(RenderOptions o, std::string_view name, std::string_view value) {
  auto err = apply_option(o, name, value);
  EXPECT_EQ(err, std::nullopt) << name << "=" << value;
  return o;
}

std::string printed(const OptionSpec& spec, const RenderOptions& o) { return spec.print(o); }

// The options as option_pairs describes them: the profile's defaults written out.
RenderOptions resolved(RenderOptions o) {
  o.max_depth = o.effective_max_depth();
  o.max_dist = o.effective_max_dist();
  o.rounding = o.effective_rounding();
  return o;
}

// Reads `option_pairs` back into fresh options, as a server restart does.
RenderOptions read_back(const RenderOptions& o) {
  RenderOptions back;
  for (auto& [name, value] : option_pairs(o)) back = with(back, name, value);
  return back;
}

RenderOptions cpsc102() { return with({}, "profile", "cpsc102"); }

TEST(Options, EveryExampleIsValidAndNotTheDefault) {
  for (const OptionSpec& spec : option_specs()) {
    RenderOptions o = with({}, spec.name, spec.example);
    EXPECT_NE(printed(spec, o), printed(spec, {})) << spec.name;
  }
}

// What keeps the cache correct: an option that can change a pixel is in the key, and one that
// cannot does not split the cache. From each profile, every option's example that changes
// the option's value.
TEST(Options, EveryPixelOptionChangesTheCacheKey) {
  for (const RenderOptions& base : {RenderOptions{}, cpsc102()}) {
    SCOPED_TRACE(to_string(base.profile));
    const std::string key = canonical_string(base);
    for (const OptionSpec& spec : option_specs()) {
      RenderOptions o = with(base, spec.name, spec.example);
      if (printed(spec, o) == printed(spec, base)) continue;  // the example is this default
      EXPECT_EQ(canonical_string(o) != key, spec.affects_pixels) << spec.name;
    }
  }
}

// Leaving the key is the exception that needs a reason: the encoding of the same pixels, a
// switch that never changes a byte, and a server's queue class (when, not what). A new option
// is in the key unless added here.
TEST(Options, OnlyFormatSpecializationAndPriorityLeaveTheKeyAlone) {
  for (const OptionSpec& spec : option_specs())
    EXPECT_EQ(spec.affects_pixels,
              spec.name != "format" && spec.name != "specialize" && spec.name != "priority")
        << spec.name;
}

TEST(Options, PairsPrintEveryOptionInTableOrder) {
  auto pairs = option_pairs({});
  ASSERT_EQ(pairs.size(), option_specs().size());
  for (size_t i = 0; i < pairs.size(); ++i) {
    EXPECT_EQ(pairs[i].first, option_specs()[i].name);
    EXPECT_EQ(find_option(pairs[i].first), &option_specs()[i]);
  }
}

TEST(Options, PrintedOptionsReadBackTheSame) {
  std::vector<RenderOptions> cases = {RenderOptions{}, cpsc102()};
  RenderOptions all;
  for (const OptionSpec& spec : option_specs()) {
    cases.push_back(with({}, spec.name, spec.example));
    cases.push_back(with(cpsc102(), spec.name, spec.example));
    all = with(all, spec.name, spec.example);
  }
  cases.push_back(all);
  cases.push_back(with({}, "max_dist", "0.1"));
  cases.push_back(with({}, "seed", "18446744073709551615"));
  cases.push_back(with({}, "background", "0.1,0.2,0.3"));
  for (const RenderOptions& o : cases) {
    SCOPED_TRACE(canonical_string(o));
    EXPECT_EQ(read_back(o), resolved(o));
    EXPECT_EQ(option_pairs(read_back(o)), option_pairs(o));
  }
}

// Closed lists of words ("phong|blinn", "true|false"): a wrong value's message names each.
TEST(Options, EnumErrorsListTheAcceptedValues) {
  int lists = 0;
  for (const OptionSpec& spec : option_specs()) {
    std::string help(spec.value_help);
    if (help.find('|') == std::string::npos ||
        help.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789|") != std::string::npos)
      continue;
    ++lists;
    RenderOptions o;
    auto err = apply_option(o, spec.name, "nonsense");
    ASSERT_TRUE(err) << spec.name;
    EXPECT_NE(err->find("got 'nonsense'"), std::string::npos) << *err;
    for (size_t start = 0; start <= help.size();) {
      size_t bar = std::min(help.find('|', start), help.size());
      EXPECT_NE(err->find(help.substr(start, bar - start)), std::string::npos) << *err;
      start = bar + 1;
    }
    EXPECT_EQ(o, RenderOptions{}) << "a failed parse leaves the options alone";
  }
  EXPECT_GE(lists, 7);  // highlight, precision, format, profile, rounding, shadows, specialize
  RenderOptions o;
  EXPECT_EQ(apply_option(o, "profile", "cpsc101"), "must be lecture or cpsc102, got 'cpsc101'");
  EXPECT_EQ(apply_option(o, "rounding", "up"), "must be nearest or truncate, got 'up'");
  EXPECT_EQ(apply_option(o, "highlight", "toon"), "must be phong or blinn, got 'toon'");
  EXPECT_EQ(find_option("profile")->value_help, "lecture|cpsc102");
}

TEST(Options, EachProfileHasItsDefaults) {
  RenderOptions lecture;
  EXPECT_EQ(lecture.profile, Profile::lecture);
  EXPECT_EQ(lecture.effective_max_depth(), 8);
  EXPECT_TRUE(std::isinf(lecture.effective_max_dist()));
  EXPECT_EQ(lecture.effective_rounding(), Rounding::nearest);
  RenderOptions course = cpsc102();
  EXPECT_EQ(course.effective_max_depth(), 64);
  EXPECT_EQ(course.effective_max_dist(), 20);
  EXPECT_EQ(course.effective_rounding(), Rounding::truncate);
}

TEST(Options, AnExplicitValueOverridesTheProfileInAnyOrder) {
  RenderOptions before =
      with(with(with({}, "max_depth", "3"), "max_dist", "unlimited"), "rounding", "nearest");
  before = with(before, "profile", "cpsc102");
  RenderOptions after =
      with(with(with(cpsc102(), "max_depth", "3"), "max_dist", "inf"), "rounding", "nearest");
  for (const RenderOptions& o : {before, after}) {
    EXPECT_EQ(o.effective_max_depth(), 3);
    EXPECT_TRUE(std::isinf(o.effective_max_dist()));
    EXPECT_EQ(o.effective_rounding(), Rounding::nearest);
  }
  RenderOptions lecture = with(with({}, "max_dist", "20"), "rounding", "truncate");
  EXPECT_EQ(lecture.effective_max_dist(), 20);
  EXPECT_EQ(lecture.effective_rounding(), Rounding::truncate);
}

TEST(Options, AProfilesDefaultsGivenExplicitlyShareItsCacheKey) {
  RenderOptions spelled = cpsc102();
  for (auto [name, value] :
       {std::pair{"rounding", "truncate"}, {"max_dist", "20"}, {"max_depth", "64"}})
    spelled = with(spelled, name, value);
  EXPECT_EQ(canonical_string(spelled), canonical_string(cpsc102()));
  EXPECT_NE(canonical_string(cpsc102()), canonical_string({}));
  EXPECT_NE(canonical_string(cpsc102()).find("profile=cpsc102;"), std::string::npos);

  RenderOptions lecture =
      with(with(with({}, "rounding", "nearest"), "max_dist", "unlimited"), "max_depth", "8");
  EXPECT_EQ(canonical_string(lecture), canonical_string({}));
  EXPECT_NE(canonical_string({}).find("max_dist=unlimited;"), std::string::npos);
}

// A number option given as -0 is the render of 0: one cache key and one ETag, not two.
TEST(Options, MinusZeroIsZero) {
  for (const OptionSpec& spec : option_specs()) {
    if (spec.name == std::string_view("camera")) continue;  // a name: "-0" is another camera
    RenderOptions minus;
    if (apply_option(minus, spec.name, "-0")) continue;  // not a number option, or 0 refused
    RenderOptions zero = with({}, spec.name, "0");
    EXPECT_EQ(canonical_string(minus), canonical_string(zero)) << spec.name;
    EXPECT_EQ(printed(spec, minus), printed(spec, zero)) << spec.name;
  }
  EXPECT_EQ(canonical_string(with({}, "background", "-0,0,-0.0")),
            canonical_string(with({}, "background", "0")));
  EXPECT_EQ(canonical_string(with({}, "bailout", "-0")), canonical_string({}));
}

// Colours are 0..1: 255 is the usual slip, refused rather than clamped to white.
TEST(Options, ABackgroundAboveOneIsRefusedWithAHint) {
  RenderOptions o;
  EXPECT_EQ(apply_option(o, "background", "255,0,0"),
            "must be at most 1, got 255 (colours are 0..1, not 0..255)");
  EXPECT_EQ(apply_option(o, "background", "1.5"),
            "must be at most 1, got 1.5 (colours are 0..1, not 0..255)");
  EXPECT_EQ(o.background, (std::array<double, 3>{0, 0, 0}));
  EXPECT_EQ(apply_option(o, "background", "1,0.5,0"), std::nullopt);
  EXPECT_EQ(o.background, (std::array<double, 3>{1, 0.5, 0}));
}

TEST(Options, UnknownNamesAreErrors) {
  RenderOptions o;
  EXPECT_EQ(apply_option(o, "profiel", "lecture"), "unknown option 'profiel'");
  Diagnostics diags;
  apply_options(o, {{"profiel", "lecture", {3, 4, ""}}}, diags);
  ASSERT_TRUE(diags.has_errors());
  EXPECT_EQ(diags.first_error()->message,
            "unknown render option 'profiel' (did you mean 'profile'?)");
}

}  // namespace
TEST(Options, TheDocumentedTableHasEveryOptionWithItsValuesAndCacheKey) {
  // docs/rendering.md is where users look the options up: its table must follow this one.
  std::ifstream in(RAYFARM_SOURCE_DIR "/docs/rendering.md");
  const std::string doc(std::istreambuf_iterator<char>(in), {});
  ASSERT_FALSE(doc.empty());
  for (const OptionSpec& spec : option_specs()) {
    const std::string row_start = "| `" + std::string(spec.name) + "` | ";
    const size_t row = doc.find(row_start);
    ASSERT_NE(row, std::string::npos) << spec.name << " has no row in docs/rendering.md";
    const std::string line = doc.substr(row, doc.find('\n', row) - row);
    EXPECT_TRUE(line.ends_with(spec.affects_pixels ? "| yes |" : "| no |")) << line;
  }
}

}  // namespace rayfarm
