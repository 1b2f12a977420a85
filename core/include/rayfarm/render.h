// Rendering a scene: a job cut into tiles and passes (one sample per pixel per pass, so the
// image and its error estimate improve evenly), run by any number of threads. The server
// schedules tiles of many jobs on its pool; render_image() runs one job on threads it owns.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "rayfarm/image.h"
#include "rayfarm/options.h"
#include "rayfarm/scene.h"

namespace rayfarm {

struct RenderStats {
  std::uint64_t primary_rays = 0;
  std::uint64_t shadow_rays = 0;
  std::uint64_t reflection_rays = 0;
  double prepare_ms = 0;
  double render_ms = 0;  // from the first tile to the last
  int spp_done = 0;      // complete passes
  int spp_target = 1;
  int tiles_done = 0;     // in the current pass
  int tiles_per_pass = 0;
  int samples_per_pass = 1;  // the cpsc102 profile takes all of a pixel's samples at once
  double error_estimate = -1;  // standard error of the pixel means, 8-bit levels; -1: n/a
  std::vector<std::string> parts;  // pipeline parts this render runs
  std::string stop_reason;         // "spp", "target_error", "time_limit", "canceled"
  bool finished = false;

  std::uint64_t total_rays() const { return primary_rays + shadow_rays + reflection_rays; }
  double progress() const;  // 0..1
};

// The version of the renderer's output: part of every content key, so a build that renders
// any byte differently never shares cached results with one that does not. Bump it with
// every change to pixels (tests/golden_test.cpp pins the bundled scenes' bytes).
inline constexpr int kRenderVersion = 5;

// The largest images a job accepts (the image, and with spp > 1 also 72 bytes of sums per
// pixel, must fit in memory).
constexpr long long kMaxPixels = 1LL << 28;
constexpr long long kMaxSupersampledPixels = 1LL << 25;

// Why an image of width × height at `spp` samples cannot be rendered ("" when it can).
std::string image_size_error(long long width, long long height, int spp);

// Tiles [first, end) of an image in row-major order (32×32 pixels each, the last row and
// column cut by the image's edge): the part of a job one node of a farm renders
// (render_unit.h). Every pixel's samples depend on its position only, so the tiles of a range
// come out as the same tiles of the whole image would.
struct TileRange {
  int first = 0;
  int end = 0;
  int count() const { return end - first; }
};

// How many tiles an image of this size has.
int tile_count(int width, int height);

class RenderJob {
 public:
  // Prepares the scene for these options. Returns nullptr with `error` set when the options
  // do not fit the scene (unknown camera).
  static std::unique_ptr<RenderJob> create(const Scene& scene, const RenderOptions& options,
                                           std::string* error);
  // Renders only the tiles of `range`, every pass (the rest of image() stays black). A range
  // cannot stop early: target_error and time_limit need the whole image's estimate after
  // each pass, so such a job is refused (one node renders it whole).
  static std::unique_ptr<RenderJob> create(const Scene& scene, const RenderOptions& options,
                                           TileRange range, std::string* error);
  virtual ~RenderJob() = default;

  enum class Step { ran, wait, done };
  // Claims one tile and renders it. `wait`: no tile can start until others of this pass
  // finish. `done`: finished or canceled. Safe to call from many threads.
  virtual Step run_step() = 0;

  virtual void cancel() = 0;
  virtual bool canceled() const = 0;
  virtual bool finished() const = 0;
  virtual RenderStats stats() const = 0;
  // The final image when finished; the image so far otherwise (unrendered tiles black).
  virtual Image image() const = 0;
  // image(), moved out instead of copied once the job has finished (then image() is 0x0).
  virtual Image take_image() = 0;
  virtual int width() const = 0;
  virtual int height() const = 0;
  virtual TileRange range() const = 0;
  // Per tile of range(), in tile order: the summed squared standard errors of its pixels
  // after the last pass (what the whole image's error_estimate adds up, in tile order).
  virtual std::vector<double> tile_errors() const = 0;
  // The pixels of range()'s tiles: each tile's rows top to bottom, tiles in order.
  virtual std::vector<std::uint8_t> range_pixels() const = 0;
};

// A scene prepared for one set of options (its acceleration structures built once), from
// which any number of jobs for ranges of its tiles are made: a farm node renders many units
// of one job. The scene must outlive it.
class PreparedRender {
 public:
  static std::shared_ptr<const PreparedRender> create(const Scene& scene,
                                                      const RenderOptions& options,
                                                      std::string* error);
  // The same, but scene.objects is freed once read (before the acceleration structures are
  // built, which then reuse its memory); the rest of the scene must outlive the result.
  static std::shared_ptr<const PreparedRender> create(Scene&& scene, const RenderOptions& options,
                                                      std::string* error);
  virtual ~PreparedRender() = default;
  // A job for `range` (see RenderJob::create), or nullptr with `error` set.
  virtual std::unique_ptr<RenderJob> job(TileRange range, std::string* error) const = 0;
  virtual int tiles() const = 0;
  virtual double prepare_ms() const = 0;
};

// Renders on `threads` threads of its own (0: all cores). `on_progress` is called from a
// worker after each tile; `cancel` is polled. Returns an empty image with `error` set when
// the job cannot start.
Image render_image(const Scene& scene, const RenderOptions& options, int threads,
                   RenderStats* stats = nullptr,
                   const std::function<void(const RenderStats&)>& on_progress = {},
                   const std::atomic<bool>* cancel = nullptr, std::string* error = nullptr);
// The same for a scene that is not needed afterwards: its objects are freed once read (see
// PreparedRender::create), which spares a large scene fresh memory.
Image render_image(Scene&& scene, const RenderOptions& options, int threads,
                   RenderStats* stats = nullptr,
                   const std::function<void(const RenderStats&)>& on_progress = {},
                   const std::atomic<bool>* cancel = nullptr, std::string* error = nullptr);

}  // namespace rayfarm
