// The render job: byte-identical output for any thread count, the spp = 1 point, seeded
// jitter, progressive passes with their stopping rules, cancellation and statistics.
#include <algorithm>
#include <atomic>
#include <new>
#include <thread>

#include "test_util.h"

namespace rayfarm {
namespace {

using test::render;
using test::scene_from;

const std::string kScene = R"(
camera c { pixeldim 67 41 worlddim 8 6 viewpoint 4 3 5 }
material chrome { ambient 3 diffuse .1 specular .9 }
material red { ambient 6 1 1 diffuse .8 .1 .1 }
material floor { ambient 2 diffuse .5 }
light { location 2.56 3.80 -1.5 emissivity 4 }
light { location 7 5 1 emissivity 3 }
sphere { material chrome center 1.25 .75 -4 radius .9 }
sphere { material red center 4 1.2 -5 radius 1.2 }
plane { material floor normal 0 1 0 point 0 -0.2 0 }
)";

TEST(Render, OutputIsByteIdenticalForAnyThreadCount) {
  Scene s = scene_from(kScene);
  for (int spp : {1, 5}) {
    RenderOptions o;
    o.spp = spp;
    Image one = render(s, o, 1);
    for (int threads : {2, 3, 8}) EXPECT_EQ(render(s, o, threads), one) << "spp " << spp;
  }
}

// A failure on a render thread (out of memory, here thrown by the progress callback, which
// runs on whichever thread finished a tile) reaches the caller once every thread has ended:
// no terminate, on any thread count.
TEST(Render, AFailureOnARenderThreadReachesTheCaller) {
  const Scene scene = test::load_file(RAYFARM_SOURCE_DIR "/scenes/cho.txt").scene.value();
  RenderOptions o;
  o.width = 96;
  o.height = 72;
  for (int threads : {1, 2, 4}) {
    std::atomic<int> calls{0};
    EXPECT_THROW(render_image(scene, o, threads, nullptr,
                              [&](const RenderStats&) {
                                if (++calls == 2) throw std::bad_alloc();
                              }),
                 std::bad_alloc)
        << threads;
  }
}

TEST(Render, AConsumedSceneRendersTheSameImageAndLosesOnlyItsObjects) {
  // Enough spheres for the hierarchy and the culling structures, which are built after the
  // objects are freed.
  std::string text = kScene;
  for (int i = 0; i < 60; ++i)
    text += "sphere { material red center " + std::to_string(i % 10 - 1) + " " +
            std::to_string(i / 10 * 0.6) + " -" + std::to_string(6 + i % 7) + " radius .25 }\n";
  const Scene original = scene_from(text);
  const std::pair<Profile, Precision> variants[] = {{Profile::lecture, Precision::f64},
                                                    {Profile::lecture, Precision::f32},
                                                    {Profile::cpsc102, Precision::f64}};
  for (const auto& [profile, precision] : variants) {
    SCOPED_TRACE(std::string(to_string(profile)) + (precision == Precision::f32 ? " float" : ""));
    RenderOptions o;
    o.profile = profile;
    o.precision = precision;
    Scene consumed = original;
    RenderStats kept_stats, consumed_stats;
    const Image kept = render_image(original, o, 2, &kept_stats);
    ASSERT_GT(kept.width, 0);
    EXPECT_EQ(render_image(std::move(consumed), o, 2, &consumed_stats), kept);
    EXPECT_EQ(consumed_stats.parts, kept_stats.parts);
    EXPECT_TRUE(consumed.objects.empty());
    EXPECT_EQ(consumed.cameras, original.cameras);
    EXPECT_EQ(consumed.materials, original.materials);
    EXPECT_EQ(consumed.lights, original.lights);
  }
  Scene bad = original;
  RenderOptions o;
  o.camera = "none";
  std::string error;
  EXPECT_EQ(render_image(std::move(bad), o, 1, nullptr, {}, nullptr, &error).width, 0);
  EXPECT_FALSE(error.empty());
  EXPECT_EQ(bad.objects, original.objects) << "a refused render frees nothing";
}

// A render thread keeps its tile buffers from one render to the next (the primary rays, the
// mirror bounces, the surface-of-revolution batches): scenes rendered one after another on
// one thread, of other sizes and with those structures each, come out as they do on threads
// new to them.
TEST(Render, AThreadRendersEachSceneAsANewThreadDoesWhateverItRenderedBefore) {
  auto busy = [](int width, int height, double shift) {
    std::string text = "camera c { pixeldim " + std::to_string(width) + " " +
                       std::to_string(height) + R"( worlddim 8 6 viewpoint 4 3 5 }
material shiny { ambient 2 diffuse .5 specular .6 }
material gold { ambient 2 1.5 .3 diffuse .9 .7 .2 specular .3 shininess 30 }
light { location 2 8 2 emissivity 6 }
plane { material shiny normal 0 1 0 point 0 0 0 }
revsurf { material gold surfer 3 base 5.5 0 -7 direction 0 1 0 height 3 }
revsurf { material gold surfer 1 base 1 0 -9 direction 0 1 0 height 2 }
)";
    for (int i = 0; i < 60; ++i)
      text += "sphere { material shiny center " + std::to_string(i % 10 - 1 + shift) + " " +
              std::to_string(0.4 + i / 10 * 0.6) + " -" + std::to_string(6 + i % 7) +
              " radius .25 }\n";
    return scene_from(text);
  };
  const Scene scenes[] = {busy(83, 57, 0), busy(67, 41, 0.5), scene_from(kScene)};
  for (Precision precision : {Precision::f64, Precision::f32}) {
    SCOPED_TRACE(precision == Precision::f32 ? "float" : "double");
    RenderOptions o;
    o.precision = precision;
    Image alone[3];
    for (int i = 0; i < 3; ++i) {
      RenderStats stats;
      std::thread([&] { alone[i] = render_image(scenes[i], o, 1, &stats); }).join();
      ASSERT_GT(alone[i].width, 0);
      if (i < 2) {  // the structures whose buffers are kept
        for (const char* part : {"screen-bins", "mirror-bins"})
          EXPECT_TRUE(std::count(stats.parts.begin(), stats.parts.end(), part)) << i << part;
      }
    }
    std::thread([&] {
      for (int i : {0, 1, 2, 0, 2, 1, 1, 0})
        EXPECT_EQ(render(scenes[i], o, 1), alone[i]) << "scene " << i;
    }).join();
  }
}

TEST(Render, RepeatedRendersAreIdenticalAndSeedsChangeOnlyJitteredImages) {
  Scene s = scene_from(kScene);
  RenderOptions o;
  o.spp = 4;
  Image a = render(s, o, 2);
  EXPECT_EQ(render(s, o, 2), a);
  o.seed = 7;
  EXPECT_NE(render(s, o, 2), a);
  RenderOptions one;
  Image b = render(s, one);
  one.seed = 7;
  EXPECT_EQ(render(s, one), b) << "spp = 1 samples the exact point: the seed cannot matter";
}

TEST(Render, SupersamplingChangesEdgesButNotFlatAreas) {
  Scene s = scene_from(kScene);
  RenderOptions o;
  Image sharp = render(s, o);
  o.spp = 16;
  Image smooth = render(s, o);
  int changed = 0;
  for (size_t i = 0; i < sharp.rgb.size(); ++i) changed += sharp.rgb[i] != smooth.rgb[i];
  EXPECT_GT(changed, 0);
  EXPECT_LT(changed, static_cast<int>(sharp.rgb.size()) / 2);
}

TEST(Render, StatsCountRaysAndReportTheErrorEstimate) {
  Scene s = scene_from(kScene);
  RenderStats one, many;
  render(s, RenderOptions{}, 2, &one);
  EXPECT_EQ(one.primary_rays, 67u * 41u);
  EXPECT_GT(one.shadow_rays, 0u);
  EXPECT_GT(one.reflection_rays, 0u);
  EXPECT_EQ(one.error_estimate, -1) << "no estimate from a single sample";
  EXPECT_TRUE(one.finished);
  EXPECT_EQ(one.spp_done, 1);

  RenderOptions o;
  o.spp = 4;
  render(s, o, 2, &many);
  EXPECT_EQ(many.primary_rays, 4u * 67u * 41u);
  EXPECT_GT(many.error_estimate, 0);
  RenderStats more;
  o.spp = 36;
  render(s, o, 2, &more);
  EXPECT_LT(more.error_estimate, many.error_estimate) << "the estimate falls with more samples";
}

TEST(Render, TargetErrorStopsSamplingEarly) {
  Scene s = scene_from(kScene);
  RenderOptions o;
  o.spp = 256;
  o.target_error = 2.0;
  RenderStats st;
  render(s, o, 2, &st);
  EXPECT_EQ(st.stop_reason, "target_error");
  EXPECT_LT(st.spp_done, 256);
  EXPECT_LE(st.error_estimate, 2.0);
}

TEST(Render, TimeLimitStopsAfterWholePasses) {
  Scene s = scene_from(kScene);
  RenderOptions o;
  o.spp = 1 << 20;
  o.time_limit = 0.2;
  RenderStats st;
  Image img = render(s, o, 2, &st);
  EXPECT_EQ(st.stop_reason, "time_limit");
  EXPECT_GE(st.spp_done, 1);
  EXPECT_LT(st.spp_done, 1 << 20);
  EXPECT_EQ(img.width, 67);
}

TEST(Render, CancelStopsARunningRenderPromptly) {
  Scene s = scene_from(kScene);
  RenderOptions o;
  o.spp = 1 << 20;
  std::atomic<bool> cancel{false};
  RenderStats st;
  auto t0 = std::chrono::steady_clock::now();
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    cancel = true;
  });
  render_image(s, o, 2, &st, {}, &cancel);
  stopper.join();
  EXPECT_EQ(st.stop_reason, "canceled");
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(2));
}

TEST(Render, PartialImageFillsTileByTileAndJobsCanBeSteppedByHand) {
  Scene s = scene_from(kScene);
  std::string error;
  auto job = RenderJob::create(s, RenderOptions{}, &error);
  ASSERT_TRUE(job);
  EXPECT_EQ(job->image(), Image(67, 41)) << "nothing rendered yet: black";
  ASSERT_EQ(job->run_step(), RenderJob::Step::ran);
  RenderStats st = job->stats();
  EXPECT_EQ(st.tiles_done, 1);
  EXPECT_GT(st.progress(), 0);
  EXPECT_LT(st.progress(), 1);
  while (job->run_step() != RenderJob::Step::done) {
  }
  EXPECT_TRUE(job->finished());
  EXPECT_EQ(job->image(), render(s));
}

TEST(Render, TinyAndLopsidedImagesRender) {
  Scene s = scene_from(kScene);
  for (auto [w, h] : {std::pair{1, 1}, {1, 37}, {53, 1}, {2, 2}}) {
    RenderOptions o;
    o.width = w;
    o.height = h;
    o.spp = 3;
    Image img = render(s, o, 2);
    EXPECT_EQ(img.width, w);
    EXPECT_EQ(img.height, h);
  }
}

TEST(Render, FloatPrecisionAgreesWithDoubleOnNearlyAllPixels) {
  Scene s = scene_from(kScene);
  Image d = render(s);
  RenderOptions o;
  o.precision = Precision::f32;
  Image f = render(s, o);
  int off = 0;
  for (size_t i = 0; i < d.rgb.size(); ++i) off += std::abs(d.rgb[i] - f.rgb[i]) > 1;
  EXPECT_LT(off, static_cast<int>(d.rgb.size()) / 200);
}

}  // namespace
}  // namespace rayfarm
