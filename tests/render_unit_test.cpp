// A job cut into units of tiles, each rendered on its own, shipped as bytes and put back
// together: the same image bytes, error estimate and ray counts as the whole render.
#include <algorithm>
#include <bit>
#include <optional>
#include <random>

#include "rayfarm/render_unit.h"
#include "test_util.h"

namespace rayfarm {
namespace {

using test::load_file;

RenderStats whole(const Scene& scene, const RenderOptions& o, Image* image) {
  RenderStats st;
  *image = render_image(scene, o, 2, &st);
  return st;
}

// Each unit on its own job (all from one prepared scene), encoded and decoded, assembled in a
// shuffled order.
Image by_units(const Scene& scene, const RenderOptions& o, const std::vector<TileRange>& units,
               RenderStats* st) {
  std::vector<std::string> shipped;
  std::string error;
  auto prepared = PreparedRender::create(scene, o, &error);  // one preparation for every unit
  EXPECT_TRUE(prepared) << error;
  if (!prepared) return {};
  for (TileRange range : units) {
    auto job = prepared->job(range, &error);
    EXPECT_TRUE(job) << error;
    if (!job) return {};
    while (job->run_step() != RenderJob::Step::done) {
    }
    shipped.push_back(encode_unit(unit_result(*job)));
  }
  std::mt19937 rng(7);
  std::shuffle(shipped.begin(), shipped.end(), rng);
  std::optional<UnitAssembler> a;
  for (const std::string& bytes : shipped) {
    auto unit = decode_unit(bytes, &error);
    EXPECT_TRUE(unit) << error;
    if (!unit) return {};
    if (!a) a.emplace(unit->width, unit->height);
    EXPECT_TRUE(a->add(*unit, &error)) << error;
  }
  EXPECT_TRUE(a && a->complete());
  if (!a) return {};
  *st = a->stats();
  return a->image();
}

struct Case {
  const char* file;
  Profile profile;
  int spp;
  int width, height;
  Precision precision = Precision::f64;
};

TEST(RenderUnits, AssembledUnitsAreTheWholeRenderToTheByte) {
  const Case cases[] = {
      {"scenes/cho.txt", Profile::lecture, 1, 0, 0},
      {"scenes/cho.txt", Profile::lecture, 1, 100, 90},
      {"scenes/cho.txt", Profile::lecture, 4, 97, 61},
      {"scenes/cho.txt", Profile::lecture, 3, 45, 37, Precision::f32},
      {"scenes/lab.txt", Profile::lecture, 2, 160, 120},
      {"scenes/textures.txt", Profile::lecture, 1, 120, 90},
      {"scenes/lab.txt", Profile::cpsc102, 1, 0, 0},
      {"scenes/lab.txt", Profile::cpsc102, 4, 100, 70},
      {"scenes/grid-8000.txt", Profile::lecture, 1, 300, 200},
      {"scenes/mirrors.txt", Profile::lecture, 5, 64, 33},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.file) + " spp " + std::to_string(c.spp) + " profile " +
                 std::to_string(static_cast<int>(c.profile)));
    LoadedScene loaded = load_file(std::string(RAYFARM_SOURCE_DIR) + "/" + c.file);
    ASSERT_TRUE(loaded.scene) << c.file;
    const Scene& scene = *loaded.scene;
    RenderOptions o;
    o.profile = c.profile;
    o.spp = c.spp;
    o.width = c.width;
    o.height = c.height;
    o.precision = c.precision;
    Image expected;
    const RenderStats want = whole(scene, o, &expected);
    ASSERT_GT(expected.width, 0);
    const int tiles = tile_count(expected.width, expected.height);
    std::vector<int> sizes = {7, tiles / 2 + 1, tiles};  // tiles a unit: uneven, half, all
    if (tiles <= 24) sizes.push_back(1);
    for (int per_unit : sizes) {
      const auto units =
          plan_units(expected.width, expected.height, c.spp, per_unit * 1024.0 * c.spp);
      EXPECT_EQ(units.front().count(), std::min(per_unit, tiles));
      RenderStats got;
      EXPECT_EQ(by_units(scene, o, units, &got), expected) << units.size() << " units";
      EXPECT_EQ(std::bit_cast<std::uint64_t>(got.error_estimate),
                std::bit_cast<std::uint64_t>(want.error_estimate))
          << got.error_estimate << " vs " << want.error_estimate;
      EXPECT_EQ(got.primary_rays, want.primary_rays);
      EXPECT_EQ(got.shadow_rays, want.shadow_rays);
      EXPECT_EQ(got.reflection_rays, want.reflection_rays);
      EXPECT_EQ(got.spp_done, want.spp_done);
      EXPECT_EQ(got.parts, want.parts);
      EXPECT_TRUE(got.finished);
    }
  }
}

TEST(RenderUnits, PlansCoverEveryTileOnceInOrder) {
  for (auto [w, h] : {std::pair{1, 1}, {32, 32}, {33, 1}, {800, 600}, {1000, 7}}) {
    const int tiles = tile_count(w, h);
    for (double work : {0.0, 1.0, 1e5, 1e6, 1e20}) {
      const auto units = plan_units(w, h, 3, work);
      ASSERT_FALSE(units.empty());
      int next = 0;
      for (TileRange r : units) {
        EXPECT_EQ(r.first, next);
        EXPECT_GT(r.count(), 0);
        next = r.end;
      }
      EXPECT_EQ(next, tiles);
    }
  }
  // 800×600 at 3 units of work per pixel, 1e6 per unit: 1e6 / (1024 × 3) → 326 tiles a unit.
  EXPECT_EQ(plan_units(800, 600, 3, 1e6).front().count(), 326);
  EXPECT_EQ(plan_units(800, 600, 3, 1e6).size(), 2u);
}

TEST(RenderUnits, BadRangesAndEarlyStopsAreRefused) {
  Scene scene = test::scene_from(test::lecture_scene());
  RenderOptions o;
  o.width = 64;
  o.height = 64;  // 4 tiles
  std::string error;
  EXPECT_FALSE(RenderJob::create(scene, o, TileRange{2, 5}, &error));
  EXPECT_NE(error.find("not a range"), std::string::npos) << error;
  EXPECT_FALSE(RenderJob::create(scene, o, TileRange{3, 3}, &error));
  EXPECT_FALSE(RenderJob::create(scene, o, TileRange{-1, 2}, &error));
  o.spp = 4;
  o.target_error = 1;
  EXPECT_FALSE(RenderJob::create(scene, o, TileRange{0, 2}, &error));
  EXPECT_NE(error.find("target error"), std::string::npos) << error;
  EXPECT_TRUE(RenderJob::create(scene, o, TileRange{0, 4}, &error)) << "the whole image may";
}

TEST(RenderUnits, AssemblerRefusesOverlapsAndOtherSizes) {
  Scene scene = test::scene_from(test::lecture_scene());
  RenderOptions o;
  o.width = 64;
  o.height = 40;  // 2 × 2 tiles
  auto unit = [&](TileRange r) {
    std::string error;
    auto job = RenderJob::create(scene, o, r, &error);
    while (job->run_step() != RenderJob::Step::done) {
    }
    return unit_result(*job);
  };
  UnitAssembler a(64, 40);
  std::string error;
  ASSERT_TRUE(a.add(unit({0, 3}), &error)) << error;
  EXPECT_FALSE(a.add(unit({2, 4}), &error));
  EXPECT_NE(error.find("tile 2 was already added"), std::string::npos) << error;
  EXPECT_FALSE(a.complete());
  UnitAssembler other(64, 41);
  EXPECT_FALSE(other.add(unit({0, 1}), &error));
  EXPECT_TRUE(a.add(unit({3, 4}), &error)) << error;
  EXPECT_TRUE(a.complete());
  EXPECT_EQ(a.image(), test::render(scene, o));
}

TEST(RenderUnits, DecodingRefusesEveryTruncationAndCorruptHeaders) {
  Scene scene = test::scene_from(test::lecture_scene());
  RenderOptions o;
  o.width = 50;
  o.height = 40;
  o.spp = 2;
  std::string error;
  auto job = RenderJob::create(scene, o, TileRange{1, 3}, &error);
  while (job->run_step() != RenderJob::Step::done) {
  }
  const std::string bytes = encode_unit(unit_result(*job));
  ASSERT_TRUE(decode_unit(bytes, &error)) << error;
  for (size_t n = 0; n < bytes.size(); ++n)
    EXPECT_FALSE(decode_unit(std::string_view(bytes).substr(0, n), &error)) << n;
  EXPECT_FALSE(decode_unit(bytes + "x", &error));
  std::mt19937 rng(3);
  int refused = 0;
  for (int i = 0; i < 2000; ++i) {  // flipped bytes: refused, or decoded within bounds
    std::string bad = bytes;
    bad[rng() % bad.size()] ^= static_cast<char>(1 + rng() % 255);
    auto u = decode_unit(bad, &error);
    if (!u) {
      ++refused;
      EXPECT_FALSE(error.empty());
      continue;
    }
    UnitAssembler a(u->width, u->height);
    a.add(*u, &error);  // must not crash or read out of bounds
  }
  EXPECT_GT(refused, 100);
}

}  // namespace
}  // namespace rayfarm
