// Explained pixels are rendered pixels: every bundled scene's explanations give the render's
// bytes in every profile; a hand-computed scene gives its numbers; the per-pixel records
// agree with the explanations they summarise.
#include <filesystem>

#include "hand_computed.h"
#include "rayfarm/explain.h"

namespace rayfarm {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path> model_scenes() {
  std::vector<fs::path> out;
  for (auto& entry : fs::recursive_directory_iterator(fs::path(RAYFARM_SOURCE_DIR) / "scenes"))
    if (entry.path().extension() == ".txt") out.push_back(entry.path());
  std::sort(out.begin(), out.end());
  return out;
}

// The scene's own options at a small size, in one of the golden test's variants.
RenderOptions options_for(const Scene& scene, const std::string& variant, int spp) {
  RenderOptions o;
  Diagnostics diags;
  apply_options(o, scene.render, diags);
  EXPECT_FALSE(diags.has_errors());
  o.width = 48;
  o.height = 36;
  o.spp = spp;
  if (variant == "cpsc102")
    EXPECT_FALSE(apply_option(o, "profile", "cpsc102"));
  else
    EXPECT_FALSE(apply_option(o, "precision", variant));
  return o;
}

LoadedScene load_bundled(const std::string& relative) {
  LoadedScene loaded = test::load_file(RAYFARM_SOURCE_DIR "/" + relative);
  EXPECT_TRUE(loaded.scene) << relative;
  return loaded;
}

RenderOptions small(Profile profile = Profile::lecture) {
  RenderOptions o;
  o.width = 48;
  o.height = 36;
  o.profile = profile;
  return o;
}

TEST(Explain, EveryPixelOfEveryBundledSceneExplainsToItsRenderedBytes) {
  for (const fs::path& path : model_scenes()) {
    LoadedScene loaded = test::load_file(path.string());
    ASSERT_TRUE(loaded.scene) << path;
    const Scene& scene = *loaded.scene;
    for (const char* variant : {"double", "float", "cpsc102"})
      for (int spp : {1, 4}) {
        SCOPED_TRACE(path.string() + " " + variant + " spp " + std::to_string(spp));
        const RenderOptions o = options_for(scene, variant, spp);
        const Image image = test::render(scene, o, 2);
        std::string error;
        const auto explainer = Explainer::create(scene, o, &error);
        ASSERT_TRUE(explainer) << error;
        ASSERT_EQ(explainer->width(), image.width);
        ASSERT_EQ(explainer->height(), image.height);
        int wrong = 0;
        for (int y = 0; y < image.height; ++y)
          for (int x = 0; x < image.width; ++x) {
            const auto e = explainer->explain(x, y, &error);
            ASSERT_TRUE(e) << error;
            ASSERT_EQ(static_cast<int>(e->samples.size()), spp);
            const std::array<int, 3> want = test::pixel(image, x, y);
            const std::array<int, 3> got = {e->bytes[0], e->bytes[1], e->bytes[2]};
            if (got != want && ++wrong <= 5)
              ADD_FAILURE() << "pixel (" << x << ", " << y << "): explained " << got[0] << " "
                            << got[1] << " " << got[2] << ", rendered " << want[0] << " " << want[1]
                            << " " << want[2];
          }
        EXPECT_EQ(wrong, 0);
      }
  }
}

// A render that target_error stopped early is explained by its first N samples of its spp
// grid (the summary's spp N/M), not by a render of N samples, whose strata differ.
TEST(Explain, ARenderStoppedEarlyIsExplainedByItsFirstSamples) {
  LoadedScene loaded = load_bundled("scenes/cho.txt");
  ASSERT_TRUE(loaded.scene);
  RenderOptions o = small();
  o.spp = 200;
  o.target_error = 1.3;
  RenderStats stats;
  std::string error;
  const Image image = render_image(*loaded.scene, o, 2, &stats, {}, nullptr, &error);
  ASSERT_GT(image.width, 0) << error;
  ASSERT_EQ(stats.stop_reason, "target_error");
  ASSERT_LT(stats.spp_done, 200);
  const auto explainer = Explainer::create(*loaded.scene, o, &error);
  ASSERT_TRUE(explainer) << error;
  RenderOptions fewer = o;
  fewer.spp = stats.spp_done;
  fewer.target_error = 0;
  const auto as_fewer = Explainer::create(*loaded.scene, fewer, &error);
  int wrong = 0, differ_as_fewer = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const auto e = explainer->explain(x, y, &error, stats.spp_done);
      ASSERT_TRUE(e) << error;
      ASSERT_EQ(static_cast<int>(e->samples.size()), stats.spp_done);
      const std::array<int, 3> want = test::pixel(image, x, y);
      wrong += std::array<int, 3>{e->bytes[0], e->bytes[1], e->bytes[2]} != want;
      const auto f = as_fewer->explain(x, y, &error);
      differ_as_fewer += std::array<int, 3>{f->bytes[0], f->bytes[1], f->bytes[2]} != want;
    }
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(differ_as_fewer, 0);  // the grid matters: the test could tell them apart
}

// Past 64 samples a pixel's explanation lists the first 64 and counts the rest in its mean,
// which still gives the rendered bytes (a million samples once took gigabytes).
TEST(Explain, ManySamplesAreCountedNotListed) {
  LoadedScene loaded = load_bundled("scenes/lab.txt");
  ASSERT_TRUE(loaded.scene);
  for (Profile profile : {Profile::lecture, Profile::cpsc102}) {
    RenderOptions o = small(profile);
    o.spp = 100;
    const Image image = test::render(*loaded.scene, o, 2);
    std::string error;
    const auto e = explain_pixel(*loaded.scene, o, 20, 20, &error);
    ASSERT_TRUE(e) << error;
    ASSERT_EQ(e->samples.size(), 100u);
    EXPECT_FALSE(e->samples[kExplainedSamples - 1].hits.empty());
    EXPECT_TRUE(e->samples[kExplainedSamples].hits.empty());
    const std::array<int, 3> got = {e->bytes[0], e->bytes[1], e->bytes[2]};
    EXPECT_EQ(got, test::pixel(image, 20, 20));
    const nlohmann::json j = explanation_json(*e);
    EXPECT_EQ(j["samples"].size(), static_cast<std::size_t>(kExplainedSamples));
    EXPECT_EQ(j["sample_count"], 100);
    const std::string text = explanation_text(*e);
    EXPECT_NE(text.find("Samples 65 to 100 are in the mean below, not listed."), std::string::npos);
    EXPECT_EQ(text.find("Sample 65 of 100"), std::string::npos);
  }
}

TEST(Explain, JsonScenesExplainLikeTheirModelTwins) {
  LoadedScene model = load_bundled("scenes/lab.txt"), json = load_bundled("scenes/lab.json");
  ASSERT_TRUE(model.scene && json.scene);
  for (Profile profile : {Profile::lecture, Profile::cpsc102}) {
    std::string error;
    const auto a = explain_pixel(*model.scene, small(profile), 20, 20, &error);
    const auto b = explain_pixel(*json.scene, small(profile), 20, 20, &error);
    ASSERT_TRUE(a && b) << error;
    EXPECT_EQ(a->bytes, b->bytes);
    EXPECT_EQ(explanation_json(*a), explanation_json(*b));
  }
}

// One sphere behind the centre pixel of a 3×3 camera (its ray is (0, 0, −1) from
// (1, 1, 5)), lit by a lamp at 45° to the right; a second lamp at 45° to the left is hidden
// by a small sphere. The plane, far below, comes first in the file, so the lecture's own
// object numbers (spheres first) differ from the file's.
const std::string kHandScene = test::kCamera + R"(
material glossy { ambient 1 1 1 diffuse .5 .5 .5 specular .5 .5 .5 shininess 4 }
material dark { ambient 0 0 0 diffuse 0 0 0 }
light lamp { location 3 1 -1 emissivity 2 2 2 }
light hidden { location -1 1 -1 emissivity 2 2 2 }
plane floor { material dark normal 0 1 0 point 0 -100 0 }
sphere ball { material glossy center 1 1 -5 radius 2 }
sphere blocker { material dark center 0 1 -2 radius .3 }
)";

// The lecture's highlight raises max(0, R·V): a light past the mirror direction adds no glint,
// and the explanation shows the 0 that was raised, not the negative R·V.
TEST(Explain, TheHighlightBaseIsWhatIsRaised) {
  // A lamp at the eye: N·L = N·V > 0 wherever the ball is seen, and R·V = 2(N·V)² − 1 < 0
  // on its outer ring (the view more than 45° off the normal).
  const Scene scene = test::scene_from(R"(
camera c { pixeldim 24 24 worlddim 8 8 viewpoint 4 4 5 }
material glossy { ambient .2 diffuse .5 specular .5 shininess 4 }
light lamp { location 4 4 5 emissivity 2 }
sphere ball { material glossy center 4 4 -5 radius 3.5 }
)");
  int lit = 0, clamped = 0;
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 24; ++x) {
      std::string error;
      const auto e = explain_pixel(scene, {}, x, y, &error);
      ASSERT_TRUE(e) << error;
      for (const PathHit& h : e->samples[0].hits)
        for (const LightTerm& l : h.lights) {
          if (l.status != "lit") continue;
          ++lit;
          EXPECT_GE(l.highlight_base, 0) << x << "," << y;
          if (l.highlight_base == 0) {
            ++clamped;
            EXPECT_EQ(l.specular, (Triple{0, 0, 0})) << x << "," << y;
          }
        }
    }
  EXPECT_GT(lit, 0);
  EXPECT_GT(clamped, 0) << "no light past a mirror direction: the test shows nothing";
}

TEST(Explain, TheLecturesTermsAreTheHandComputedOnes) {
  const Scene scene = test::scene_from(kHandScene);
  std::string error;
  const auto e = explain_pixel(scene, {}, 1, 1, &error);
  ASSERT_TRUE(e) << error;
  ASSERT_EQ(e->samples.size(), 1u);
  const PathTrace& s = e->samples[0];
  ASSERT_GE(s.hits.size(), 1u);
  const PathHit& h = s.hits[0];
  // The ray meets the sphere's front at z = −3: t = 8, normal +z.
  EXPECT_EQ(h.ray, "primary");
  EXPECT_EQ(h.object, 1);
  EXPECT_EQ(h.object_name, "ball");
  EXPECT_EQ(h.kind, "sphere");
  EXPECT_EQ(h.material, "glossy");
  EXPECT_DOUBLE_EQ(h.t, 8);
  EXPECT_DOUBLE_EQ(h.travelled, 8);
  EXPECT_EQ(h.point, (Triple{1, 1, -3}));
  EXPECT_EQ(h.normal, (Triple{0, 0, 1}));
  EXPECT_EQ(h.ambient, (Triple{1, 1, 1}));
  ASSERT_EQ(h.lights.size(), 2u);

  // The lamp: L = (2, 0, 2)/√8, so N·L = 1/√2, r = √8, E/r = 2/√8 = 1/√2.
  const test::L root2 = std::sqrt(test::L(2));
  const LightTerm& lamp = h.lights[0];
  EXPECT_EQ(lamp.name, "lamp");
  EXPECT_EQ(lamp.status, "lit");
  EXPECT_NEAR(lamp.distance, 2 * root2, 1e-14);
  EXPECT_NEAR(lamp.n_dot_l, 1 / root2, 1e-14);
  EXPECT_NEAR(lamp.emissivity[0], 1 / root2, 1e-14);
  const test::L diffuse = 1 / root2 * 0.5L / root2;  // E/r · diffuse · N·L = 1/4
  EXPECT_NEAR(lamp.diffuse[1], diffuse, 1e-14);
  // Phong: R = 2(N·L)N − L = (−1, 0, 1)/√2 and V = +z, so R·V = 1/√2; (1/√2)^4 = 1/4.
  EXPECT_NEAR(lamp.highlight_base, 1 / root2, 1e-14);
  const test::L glint = 1 / root2 * 0.5L * 0.25L;
  EXPECT_NEAR(lamp.specular[2], glint, 1e-14);

  const LightTerm& hidden = h.lights[1];
  EXPECT_EQ(hidden.status, "shadowed");
  EXPECT_EQ(hidden.blocker, 2);  // file order: the plane is object 0
  EXPECT_EQ(hidden.diffuse, (Triple{0, 0, 0}));

  const test::L local = 1 / 8.0L + diffuse + glint;
  EXPECT_NEAR(h.local[0], local, 1e-14);
  // The reflected ray goes back past the eye and meets nothing: it adds nothing.
  ASSERT_EQ(s.hits.size(), 2u);
  EXPECT_EQ(h.reflected, 1);
  EXPECT_EQ(h.weight, (Triple{.5, .5, .5}));
  EXPECT_EQ(s.hits[1].ray, "reflected");
  EXPECT_EQ(s.hits[1].parent, 0);
  EXPECT_EQ(s.hits[1].depth, 1);
  EXPECT_EQ(s.hits[1].object, -1);
  EXPECT_EQ(s.hits[1].origin, h.point);
  EXPECT_EQ(h.value, h.local);
  EXPECT_EQ(e->bytes[0], test::round_byte(local));
  EXPECT_EQ(e->rounding, "nearest");
}

TEST(Explain, TheCoursesTermsAreTheHandComputedOnes) {
  const Scene scene = test::scene_from(kHandScene);
  RenderOptions o;
  o.profile = Profile::cpsc102;
  std::string error;
  const auto e = explain_pixel(scene, o, 1, 1, &error);
  ASSERT_TRUE(e) << error;
  const PathHit& h = e->samples[0].hits[0];
  EXPECT_EQ(h.object, 1);
  EXPECT_DOUBLE_EQ(h.t, 8);
  EXPECT_EQ(h.point, (Triple{1, 1, -3}));
  ASSERT_EQ(h.lights.size(), 2u);
  const test::L root2 = std::sqrt(test::L(2));
  const LightTerm& lamp = h.lights[0];
  EXPECT_EQ(lamp.status, "lit");
  EXPECT_NEAR(lamp.n_dot_l, 1 / root2, 1e-15);
  EXPECT_EQ(lamp.emissivity, (Triple{2, 2, 2}));  // not divided by the distance here
  // diffuse · E · N·L / d = 0.5 · 2 · (1/√2) / √8 = 1/4.
  EXPECT_NEAR(lamp.diffuse[0], 0.25, 1e-15);
  // Blinn's H = unit(V + L) with V = +z: N·H = cos 22.5°.
  const test::L n_dot_h = std::cos(std::acos(test::L(-1)) / 8);
  EXPECT_NEAR(lamp.highlight_base, n_dot_h, 1e-15);
  const test::L glint = 2 * 0.5L * std::pow(n_dot_h, 4);
  EXPECT_NEAR(lamp.specular[0], glint, 1e-14);
  EXPECT_EQ(h.lights[1].status, "shadowed");
  EXPECT_EQ(h.lights[1].blocker, 2);
  EXPECT_NEAR(h.local[0], (1 + 0.25L + glint) / 8, 1e-15);
  EXPECT_EQ(e->bytes[0], test::trunc_byte(h.value[0]));
  EXPECT_EQ(e->rounding, "truncate");
}

TEST(Explain, AMirrorShowsItsReflectedHit) {
  LoadedScene loaded = load_bundled("scenes/mirrors.txt");
  ASSERT_TRUE(loaded.scene);
  for (Profile profile : {Profile::lecture, Profile::cpsc102}) {
    std::string error;
    // Left of the middle the rays meet the left mirror behind the screen (nearer the edge
    // they meet it in front of the screen, where the course's program ignored hits).
    const auto e = explain_pixel(*loaded.scene, small(profile), 18, 18, &error);
    ASSERT_TRUE(e) << error;
    const std::vector<PathHit>& hits = e->samples[0].hits;
    ASSERT_GE(hits.size(), 2u);
    EXPECT_EQ(hits[0].object_name, "left_mirror");
    EXPECT_EQ(hits[0].reflected, 1);
    EXPECT_EQ(hits[1].ray, "reflected");
    EXPECT_EQ(hits[1].parent, 0);
    EXPECT_EQ(hits[1].depth, 1);
    EXPECT_GE(hits[1].object, 0);
  }
}

TEST(Explain, ATranslucentBallFiltersItsShadowAndShowsItsTransmittedRay) {
  LoadedScene loaded = load_bundled("scenes/lab.txt");
  ASSERT_TRUE(loaded.scene);
  const auto explainer = Explainer::create(*loaded.scene, small(), nullptr);
  ASSERT_TRUE(explainer);
  int filtered = 0, transmitted = 0;
  for (int y = 0; y < 36; ++y)
    for (int x = 0; x < 48; ++x) {
      const auto e = explainer->explain(x, y, nullptr);
      ASSERT_TRUE(e);
      for (const PathHit& h : e->samples[0].hits) {
        for (const LightTerm& l : h.lights)
          if (l.status == "filtered") {
            ++filtered;
            EXPECT_EQ(e->samples[0].hits[0].object >= 0, true);
            EXPECT_EQ(loaded.scene->objects[static_cast<size_t>(l.blocker)].name, "glass_ball");
          }
        if (h.transmitted >= 0) {
          ++transmitted;
          const PathHit& t = e->samples[0].hits[static_cast<size_t>(h.transmitted)];
          EXPECT_EQ(t.ray, "transmitted");
          EXPECT_EQ(&e->samples[0].hits[static_cast<size_t>(t.parent)], &h);
        }
      }
    }
  EXPECT_GT(filtered, 0);
  EXPECT_GT(transmitted, 0);
}

TEST(Explain, RefusesWhatARenderRefusesWithTheSameWords) {
  const Scene scene = test::scene_from(kHandScene);
  RenderOptions o;
  o.camera = "nope";
  std::string render_error, explain_error, record_error;
  render_image(scene, o, 1, nullptr, {}, nullptr, &render_error);
  EXPECT_FALSE(explain_pixel(scene, o, 0, 0, &explain_error));
  EXPECT_FALSE(record_pixels(scene, o, 1, &record_error));
  EXPECT_NE(render_error, "");
  EXPECT_EQ(explain_error, render_error);
  EXPECT_EQ(record_error, render_error);

  o = {};
  o.profile = Profile::cpsc102;
  o.precision = Precision::f32;
  render_image(scene, o, 1, nullptr, {}, nullptr, &render_error);
  EXPECT_FALSE(explain_pixel(scene, o, 0, 0, &explain_error));
  EXPECT_NE(render_error, "");
  EXPECT_EQ(explain_error, render_error);
}

TEST(Explain, APixelOutsideTheImageIsRefusedWithTheImageSize) {
  const Scene scene = test::scene_from(kHandScene);
  std::string error;
  EXPECT_FALSE(explain_pixel(scene, {}, 3, 0, &error));
  EXPECT_NE(error.find("3x3"), std::string::npos) << error;
  EXPECT_FALSE(explain_pixel(scene, {}, 0, -1, &error));
  EXPECT_TRUE(explain_pixel(scene, {}, 2, 2, &error));
}

TEST(Explain, TextShowsEachTermAndTheRoundingAndIsTheSameEveryTime) {
  const Scene scene = test::scene_from(kHandScene);
  const auto e = explain_pixel(scene, {}, 1, 1, nullptr);
  ASSERT_TRUE(e);
  const std::string text = explanation_text(*e);
  EXPECT_EQ(text, explanation_text(*explain_pixel(scene, {}, 1, 1, nullptr)));
  for (const char* part :
       {"hits sphere 'ball' (object 1), material 'glossy', at t = 8",
        "ambient/travelled = (1, 1, 1)/8", "light 0 'lamp': lit",
        "E/r = (2, 2, 2)/2.82843 = (0.707107, 0.707107, 0.707107)",
        "light 1 'hidden': shadowed by sphere 'blocker' (object 2)", "(R·V)^4",
        "reflected ray (#1)", "meets nothing", "× 255 = 118.164 → floor(118.164 + 0.5) = 118"})
    EXPECT_NE(text.find(part), std::string::npos) << part << " not in:\n" << text;
  const nlohmann::json json = explanation_json(*e);
  EXPECT_EQ(json["bytes"], nlohmann::json::array({118, 118, 118}));
  EXPECT_EQ(json["samples"][0]["hits"][0]["lights"][1]["blocker"], 2);
  EXPECT_EQ(json["formula"], e->formula);
}

// A plain light's E/r that overflows is shown as the value it is, not put down to a slide or
// a filter it does not have; a projector's slide is named.
TEST(Explain, AnOverflowingLightIsNoSlide) {
  const Scene scene = test::scene_from(R"(
camera { pixeldim 5 5 worlddim 4 4 viewpoint 2 2 5 }
material grey { diffuse .8 }
light { location 2 2 -1.9 emissivity 1e308 1 1 }
sphere { material grey center 2 2 -4 radius 2 }
)");
  const auto e = explain_pixel(scene, {}, 2, 2, nullptr);
  ASSERT_TRUE(e);
  const std::string text = explanation_text(*e);
  EXPECT_NE(text.find("E/r = (1e+308, 1, 1)/"), std::string::npos) << text;
  EXPECT_NE(text.find(" = (inf, "), std::string::npos) << text;
  EXPECT_EQ(text.find("slide"), std::string::npos) << text;
  EXPECT_EQ(explanation_json(*e)["samples"][0]["hits"][0]["lights"][0]["slide"], false);

  LoadedScene loaded = load_bundled("scenes/textures.txt");
  ASSERT_TRUE(loaded.scene);
  const auto explainer = Explainer::create(*loaded.scene, small(), nullptr);
  ASSERT_TRUE(explainer);
  int slid = 0;
  for (int y = 0; y < 36; y += 3)
    for (int x = 0; x < 48; x += 3) {
      const auto p = explainer->explain(x, y, nullptr);
      ASSERT_TRUE(p);
      for (const LightTerm& l : p->samples[0].hits[0].lights)
        if (l.name == "beamer" && l.status == "lit") {
          EXPECT_TRUE(l.slide);
          slid += explanation_text(*p).find(" · slide = ") != std::string::npos;
        }
    }
  EXPECT_GT(slid, 0);
}

// The record as the explanation of sample 0 shows it.
PixelRecord record_from(const PixelExplanation& e) {
  const std::vector<PathHit>& hits = e.samples[0].hits;
  auto nonzero = [](const Triple& c) { return c[0] != 0 || c[1] != 0 || c[2] != 0; };
  PixelRecord r;
  std::vector<Triple> reach(hits.size(), Triple{1, 1, 1});
  double first_glint = 0;
  for (size_t k = 0; k < hits.size(); ++k) {
    const PathHit& h = hits[k];
    if (h.reflected >= 0 && nonzero(h.weight)) r.flags |= PixelRecord::reflection;
    if (h.transmitted >= 0 && nonzero(h.filter)) r.flags |= PixelRecord::transmission;
    if (h.capped) r.flags |= PixelRecord::capped;
    if (h.parent >= 0) {
      const PathHit& p = hits[static_cast<size_t>(h.parent)];
      for (int c = 0; c < 3; ++c)
        reach[k][c] = reach[static_cast<size_t>(h.parent)][c] *
                      (h.ray == "reflected" ? p.weight[c] : p.filter[c]);
    }
    if (h.object < 0 || !nonzero(reach[k])) continue;
    const double share = e.profile == Profile::cpsc102 ? 1 / h.travelled : 1;
    bool blocked = false;
    double glint = 0;
    for (const LightTerm& l : h.lights) {
      blocked = blocked || l.status == "shadowed" || l.status == "filtered";
      for (int c = 0; c < 3; ++c) glint = std::max(glint, l.specular[c] * share * reach[k][c]);
    }
    if (k == 0) first_glint = glint;
    if (blocked) r.flags |= k == 0 ? PixelRecord::shadow : PixelRecord::later_shadow;
    if (glint >= 0.5 / 255)
      r.flags |= k == 0 ? PixelRecord::highlight : PixelRecord::later_highlight;
  }
  if (hits[0].object >= 0) {
    r.flags |= PixelRecord::hit;
    r.object = hits[0].object;
    r.highlight_level = static_cast<std::uint8_t>(std::min(255.0, std::ceil(first_glint * 255)));
  }
  return r;
}

TEST(Records, AgreeWithTheExplanationOfSampleZero) {
  for (const char* file : {"scenes/cho.txt", "scenes/shadows.txt", "scenes/mirrors.txt",
                           "scenes/lab.txt", "scenes/textures.txt"}) {
    LoadedScene loaded = load_bundled(file);
    ASSERT_TRUE(loaded.scene);
    for (Profile profile : {Profile::lecture, Profile::cpsc102})
      for (int spp : {1, 4}) {
        SCOPED_TRACE(std::string(file) + " " + std::string(to_string(profile)) + " spp " +
                     std::to_string(spp));
        RenderOptions o = small(profile);
        o.spp = spp;
        std::string error;
        const auto records = record_pixels(*loaded.scene, o, 2, &error);
        ASSERT_TRUE(records) << error;
        ASSERT_EQ(records->size(), 48u * 36u);
        const auto explainer = Explainer::create(*loaded.scene, o, &error);
        ASSERT_TRUE(explainer);
        for (int y = 0; y < 36; ++y)
          for (int x = 0; x < 48; ++x) {
            const PixelRecord& r = (*records)[static_cast<size_t>(y) * 48 + x];
            const auto e = explainer->explain(x, y, nullptr);
            ASSERT_TRUE(e);
            const PixelRecord want = record_from(*e);
            ASSERT_EQ(r.flags, want.flags) << "pixel (" << x << ", " << y << ")";
            ASSERT_EQ(r.object, want.object) << "pixel (" << x << ", " << y << ")";
            ASSERT_EQ(r.highlight_level, want.highlight_level)
                << "pixel (" << x << ", " << y << ")";
            const PixelRecord one = explainer->record(x, y);
            ASSERT_EQ(one.flags, r.flags);
            ASSERT_EQ(one.object, r.object);
          }
      }
  }
}

int count(const std::vector<PixelRecord>& records, std::uint8_t flag) {
  int n = 0;
  for (const PixelRecord& r : records) n += (r.flags & flag) != 0;
  return n;
}

TEST(Records, MirrorsMarkTheirReflectingPixels) {
  LoadedScene loaded = load_bundled("scenes/mirrors.txt");
  ASSERT_TRUE(loaded.scene);
  const auto records = record_pixels(*loaded.scene, small(), 0, nullptr);
  ASSERT_TRUE(records);
  // The two mirror walls (objects 0 and 1) reflect wherever they are seen.
  int on_mirrors = 0;
  for (const PixelRecord& r : *records)
    if (r.object == 0 || r.object == 1) {
      ++on_mirrors;
      EXPECT_TRUE(r.flags & PixelRecord::reflection);
    }
  EXPECT_GT(on_mirrors, 100);
  // The green sphere (object 4) has no specular colour: nothing reflects in it.
  for (const PixelRecord& r : *records)
    if (r.object == 4) {
      EXPECT_FALSE(r.flags & PixelRecord::reflection);
    }
}

TEST(Records, AnOccluderMarksTheShadowItCasts) {
  LoadedScene loaded = load_bundled("scenes/shadows.txt");
  ASSERT_TRUE(loaded.scene);
  const auto records = record_pixels(*loaded.scene, small(), 2, nullptr);
  ASSERT_TRUE(records);
  EXPECT_GT(count(*records, PixelRecord::shadow), 50);
  // Each shadowed pixel has a light whose shadow ray met an object.
  const auto explainer = Explainer::create(*loaded.scene, small(), nullptr);
  for (int i = 0; i < 48 * 36; ++i)
    if ((*records)[static_cast<size_t>(i)].flags & PixelRecord::shadow) {
      const auto e = explainer->explain(i % 48, i / 48, nullptr);
      bool blocked = false;
      for (const LightTerm& l : e->samples[0].hits[0].lights)
        blocked = blocked || (l.status == "shadowed" && l.blocker >= 0);
      EXPECT_TRUE(blocked) << "pixel " << i;
    }
}

TEST(Records, BackgroundPixelsHaveNoObject) {
  LoadedScene loaded = load_bundled("scenes/cho.txt");
  ASSERT_TRUE(loaded.scene);
  for (Profile profile : {Profile::lecture, Profile::cpsc102}) {
    const auto records = record_pixels(*loaded.scene, small(profile), 1, nullptr);
    ASSERT_TRUE(records);
    const PixelRecord& sky = (*records)[0];  // the top left corner looks over everything
    EXPECT_EQ(sky.object, -1);
    EXPECT_EQ(sky.flags, 0);
    int hits = 0;
    for (const PixelRecord& r : *records) {
      EXPECT_EQ(r.object >= 0, (r.flags & PixelRecord::hit) != 0);
      hits += r.object >= 0;
    }
    EXPECT_GT(hits, 0);
    EXPECT_LT(hits, 48 * 36);
  }
}

TEST(Records, AShortMaxDistMarksCappedPixels) {
  LoadedScene loaded = load_bundled("scenes/cho.txt");
  ASSERT_TRUE(loaded.scene);
  for (Profile profile : {Profile::lecture, Profile::cpsc102}) {
    // Every point of the chrome sphere is farther than 8.5 from the eye: the lecture does
    // not see it, and the course's program does not follow its reflections.
    RenderOptions o = small(profile);
    o.max_dist = 8.5;
    const auto records = record_pixels(*loaded.scene, o, 2, nullptr);
    ASSERT_TRUE(records);
    EXPECT_GT(count(*records, PixelRecord::capped), 0) << to_string(profile);
    o.max_dist = std::numeric_limits<double>::infinity();
    const auto unlimited = record_pixels(*loaded.scene, o, 2, nullptr);
    EXPECT_EQ(count(*unlimited, PixelRecord::capped), 0);
  }
}

TEST(Records, HighlightsAreMarkedWhereTheGlintShows) {
  const Scene scene = test::scene_from(kHandScene);
  const auto records = record_pixels(scene, {}, 1, nullptr);
  ASSERT_TRUE(records);
  const PixelRecord& centre = (*records)[4];
  EXPECT_TRUE(centre.flags & PixelRecord::highlight);
  EXPECT_EQ(centre.highlight_level, 23);            // 0.0884 · 255 = 22.5, rounded up
  EXPECT_TRUE(centre.flags & PixelRecord::shadow);  // the hidden lamp
  EXPECT_EQ(centre.object, 1);
}

TEST(Records, AShadowSeenInAMirrorIsALaterShadow) {
  // A mirror wall facing the camera shows the floor and the shadow a ball casts on it to
  // the right; the wall itself is lit.
  const Scene scene = test::scene_from(R"(camera c { pixeldim 64 48 worlddim 8 6 viewpoint 4 3 6 }
material floor { ambient 1 1 1 diffuse .7 .7 .7 }
material mirror { ambient .1 .1 .1 diffuse .1 .1 .1 specular .8 .8 .8 }
light l { location -4 6 -3 emissivity 6 6 6 }
plane ground { material floor normal 0 1 0 point 0 0 0 }
plane wall { material mirror normal 0 0 1 point 0 0 -6 }
sphere ball { material floor center 4 1 -3 radius 1 }
)");
  for (Profile profile : {Profile::lecture, Profile::cpsc102}) {
    RenderOptions o;
    o.profile = profile;
    const auto records = record_pixels(scene, o, 2, nullptr);
    ASSERT_TRUE(records);
    int later = 0;
    for (const PixelRecord& r : *records)
      if (r.object == 1) {  // the wall
        EXPECT_FALSE(r.flags & PixelRecord::shadow);
        later += (r.flags & PixelRecord::later_shadow) != 0;
      }
    EXPECT_GT(later, 0) << to_string(profile);
  }
}

}  // namespace
}  // namespace rayfarm
