// Tiled, progressive rendering: pass k gives every pixel its sample k, tiles of a pass run
// in any order on any thread, and each pixel sums its samples in sample order, so the bytes
// never depend on the thread count.
#include "rayfarm/render.h"

#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>
#include <thread>

#include "render/prepared_scene.h"
#include "render/sampler.h"
#include "render/tracer.h"

namespace rayfarm {
namespace {

using Clock = std::chrono::steady_clock;

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

std::uint8_t to_byte(double c) {  // SPEC §3 step 7
  c = c > 0 ? (c < 1 ? c : 1.0) : 0.0;
  return static_cast<std::uint8_t>(std::floor(255 * c + 0.5));
}

template <class T>
class TiledRender final : public RenderJob {
 public:
  TiledRender(PreparedScene<T> scene, const RenderOptions& options, double prepare_ms)
      : s_(std::move(scene)),
        options_(options),
        sampler_(s_.spp),
        tiles_x_((s_.width + kTileSize - 1) / kTileSize),
        tiles_y_((s_.height + kTileSize - 1) / kTileSize),
        image_(s_.width, s_.height),
        prepare_ms_(prepare_ms) {
    if (s_.spp > 1) {
      sum_.assign(static_cast<size_t>(s_.width) * s_.height * 3, 0.0);
      sum_sq_.assign(sum_.size(), 0.0);
    }
    tile_error_.assign(tile_count(), 0.0);
  }

  Step run_step() override {
    int tile, pass;
    {
      std::lock_guard lock(mu_);
      if (finished_) return Step::done;
      if (cancel_.load()) {
        finish("canceled");
        return Step::done;
      }
      if (next_tile_ == tile_count()) return Step::wait;
      if (next_tile_ == 0 && passes_done_ == 0) start_ = Clock::now();
      if (next_tile_ == 0) pass_start_ = Clock::now();
      tile = next_tile_++;
      pass = passes_done_;
    }
    std::vector<std::uint8_t> bytes;
    RayCounts counts;
    bool complete = render_tile(tile, pass, bytes, counts);
    std::lock_guard lock(mu_);
    primary_ += counts.primary;
    shadow_ += counts.shadow;
    reflection_ += counts.reflection;
    if (!complete || finished_) return finished_ ? Step::done : Step::ran;
    copy_tile(tile, bytes);
    if (++done_in_pass_ == tile_count()) end_pass();
    return Step::ran;
  }

  void cancel() override { cancel_.store(true); }
  bool canceled() const override { return cancel_.load(); }
  bool finished() const override {
    std::lock_guard lock(mu_);
    return finished_;
  }
  int width() const override { return s_.width; }
  int height() const override { return s_.height; }

  Image image() const override {
    std::lock_guard lock(mu_);
    return image_;
  }

  RenderStats stats() const override {
    std::lock_guard lock(mu_);
    RenderStats st;
    st.primary_rays = primary_;
    st.shadow_rays = shadow_;
    st.reflection_rays = reflection_;
    st.prepare_ms = prepare_ms_;
    if (passes_done_ > 0 || done_in_pass_ > 0 || next_tile_ > 0)
      st.render_ms = ms_between(start_, finished_ ? end_ : Clock::now());
    st.spp_done = passes_done_;
    st.spp_target = s_.spp;
    st.tiles_done = done_in_pass_;
    st.tiles_per_pass = tile_count();
    st.error_estimate = error_;
    st.parts = s_.features.parts();
    st.stop_reason = stop_reason_;
    st.finished = finished_;
    return st;
  }

 private:
  int tile_count() const { return tiles_x_ * tiles_y_; }

  // A tile's columns [x0, x1) and image rows [r0, r1) (row 0 at the top).
  struct TileBounds {
    int x0, x1, r0, r1;
  };
  TileBounds bounds_of(int tile) const {
    const int x0 = (tile % tiles_x_) * kTileSize, r0 = (tile / tiles_x_) * kTileSize;
    return {x0, std::min(x0 + kTileSize, s_.width), r0, std::min(r0 + kTileSize, s_.height)};
  }

  // Renders one tile of one pass into `bytes` (its rows top to bottom). Returns false when
  // canceled part way.
  bool render_tile(int tile, int pass, std::vector<std::uint8_t>& bytes, RayCounts& counts) {
    const auto [x0, x1, r0, r1] = bounds_of(tile);
    bytes.resize(static_cast<size_t>(x1 - x0) * (r1 - r0) * 3);
    Tracer<T> tracer(s_);
    const bool binned = !s_.screen_bins.empty();
    std::vector<PrimaryRay> rays;
    if (binned) first_hits(tile, pass, tracer, rays);
    const bool multi = s_.spp > 1;
    const double n = pass + 1;
    double tile_error = 0;
    std::uint8_t* out = bytes.data();
    for (int r = r0; r < r1; ++r) {
      if (cancel_.load(std::memory_order_relaxed)) return false;
      const int y = s_.height - 1 - r;  // the top image row is world row H-1
      for (int x = x0; x < x1; ++x) {
        Vec3<T> c;
        if (binned) {
          const PrimaryRay& ray = rays[static_cast<size_t>(r - r0) * (x1 - x0) + (x - x0)];
          c = ray.dir ? tracer.primary(*ray.dir, ray.hit) : tracer.primary(pixel_point(x, y, pass));
        } else {
          c = tracer.primary(pixel_point(x, y, pass));
        }
        if (!multi) {
          for (int k = 0; k < 3; ++k) *out++ = to_byte(static_cast<double>(c[k]));
          continue;
        }
        size_t i = (static_cast<size_t>(r) * s_.width + x) * 3;
        for (int k = 0; k < 3; ++k) {
          double ck = static_cast<double>(c[k]);
          sum_[i + k] += ck;
          sum_sq_[i + k] += ck * ck;
          double mean = sum_[i + k] / n;
          *out++ = to_byte(mean);
          if (n >= 2) {
            double var = (sum_sq_[i + k] - sum_[i + k] * mean) / (n - 1);
            tile_error += (var > 0 ? var : 0) / n;
          }
        }
      }
    }
    tile_error_[tile] = tile_error;
    counts = tracer.counts;
    return true;
  }

  struct PrimaryRay {
    std::optional<Vec3<T>> dir;
    Hit<T> hit;
  };

  // The closest hit of every primary ray of the tile, from its screen bin: each sphere is
  // tested only on the pixels of its rectangle, nearest spheres first, and skipped on pixels
  // where something nearer than all of it was already hit. Ties go to the lowest index
  // (spheres before planes), as in Tracer::closest, so the hits are the loop's.
  void first_hits(int tile, int pass, const Tracer<T>& tracer, std::vector<PrimaryRay>& rays) const {
    const auto [x0, x1, r0, r1] = bounds_of(tile);
    const int w = x1 - x0;
    rays.resize(static_cast<size_t>(w) * (r1 - r0));
    const T t_max = s_.max_dist;
    for (int r = r0; r < r1; ++r) {
      for (int x = x0; x < x1; ++x) {
        PrimaryRay& ray = rays[static_cast<size_t>(r - r0) * w + (x - x0)];
        ray = {tracer.primary_direction(pixel_point(x, s_.height - 1 - r, pass)), Hit<T>{}};
        // Planes first, so spheres behind the plane hit are skipped.
        if (ray.dir) tracer.closest_plane(s_.eye, *ray.dir, Origin{}, t_max, ray.hit);
      }
    }
    for (const ScreenBinEntry& e : s_.screen_bins.of_tile(tile)) {
      const PreparedSphere<T>& sp = s_.spheres[e.sphere];
      const double near = e.near;
      const int ex0 = std::max<int>(e.x0, x0), ex1 = std::min<int>(e.x1, x1 - 1);
      const int er0 = std::max<int>(e.r0, r0), er1 = std::min<int>(e.r1, r1 - 1);
      for (int r = er0; r <= er1; ++r) {
        PrimaryRay* ray = rays.data() + static_cast<size_t>(r - r0) * w + (ex0 - x0);
        for (int x = ex0; x <= ex1; ++x, ++ray) {
          Hit<T>& best = ray->hit;
          if (!ray->dir || near > static_cast<double>(best.t)) continue;
          const T t = sphere_t(s_.eye, *ray->dir, sp.centre, sp.radius, e.sphere, Origin{});
          if (t > 0 && t <= t_max && (t < best.t || (t == best.t && e.sphere < best.object)))
            best = {t, e.sphere};
        }
      }
    }
  }

  // The world point of pixel (x, y) in pass `pass` (jittered when supersampling).
  Vec3<T> pixel_point(int x, int y, int pass) const {
    if (s_.spp <= 1) return screen_point(x, y, 0, 0);
    PixelOffset o = sampler_.offset(s_.seed, x, y, pass);
    return screen_point(x, y, o.u, o.v);
  }

  // The world point of pixel (x, y) displaced by (u, v) pixels (SPEC §3 camera mapping).
  Vec3<T> screen_point(int x, int y, double u, double v) const {
    auto fraction = [](int i, int count, double offset) {
      if (count == 1) return T(0.5) + static_cast<T>(offset);
      return (static_cast<T>(i) + static_cast<T>(offset)) / static_cast<T>(count - 1);
    };
    return {fraction(x, s_.width, u) * s_.world_width, fraction(y, s_.height, v) * s_.world_height,
            T(0)};
  }

  void copy_tile(int tile, const std::vector<std::uint8_t>& bytes) {
    const auto [x0, x1, r0, r1] = bounds_of(tile);
    const int w = x1 - x0, rows = r1 - r0;
    for (int r = 0; r < rows; ++r)
      std::copy_n(bytes.data() + static_cast<size_t>(r) * w * 3, w * 3, image_.row(r0 + r) + x0 * 3);
  }

  // Called under the lock by whoever finishes the last tile of a pass.
  void end_pass() {
    ++passes_done_;
    if (passes_done_ >= 2) {
      double total = 0;
      for (double e : tile_error_) total += e;  // tile order: deterministic
      error_ = 255 * std::sqrt(total / (static_cast<double>(s_.width) * s_.height * 3));
    }
    const Clock::time_point now = Clock::now();
    const double pass_ms = ms_between(pass_start_, now);
    if (passes_done_ >= s_.spp) finish("spp");
    else if (options_.target_error > 0 && passes_done_ >= 2 && error_ <= options_.target_error)
      finish("target_error");
    else if (options_.time_limit > 0 &&
             ms_between(start_, now) + pass_ms > options_.time_limit * 1000)
      finish("time_limit");
    else {
      next_tile_ = 0;
      done_in_pass_ = 0;
    }
  }

  void finish(const char* reason) {
    finished_ = true;
    stop_reason_ = reason;
    end_ = Clock::now();
  }

  const PreparedScene<T> s_;
  const RenderOptions options_;
  const StratifiedSampler sampler_;
  const int tiles_x_;
  const int tiles_y_;

  mutable std::mutex mu_;
  Image image_;
  std::vector<double> sum_, sum_sq_;  // per pixel channel, only with spp > 1
  std::vector<double> tile_error_;    // per tile: summed squared standard errors, last pass
  int next_tile_ = 0;
  int done_in_pass_ = 0;
  int passes_done_ = 0;
  bool finished_ = false;
  std::string stop_reason_;
  double error_ = -1;
  std::uint64_t primary_ = 0, shadow_ = 0, reflection_ = 0;
  double prepare_ms_;
  Clock::time_point start_{}, pass_start_{}, end_{};
  std::atomic<bool> cancel_{false};
};

}  // namespace

double RenderStats::progress() const {
  if (finished) return 1.0;
  if (tiles_per_pass == 0 || spp_target == 0) return 0.0;
  return (spp_done + static_cast<double>(tiles_done) / tiles_per_pass) / spp_target;
}

std::unique_ptr<RenderJob> RenderJob::create(const Scene& scene, const RenderOptions& options,
                                             std::string* error) {
  auto camera = scene.find_camera(options.camera);
  if (!camera) {
    if (error) {
      std::string names;
      for (const Camera& c : scene.cameras) names += (names.empty() ? "" : ", ") + c.name;
      *error = "no camera named '" + options.camera + "'" +
               (names.empty() ? "" : " (cameras: " + names + ")");
    }
    return nullptr;
  }
  // Bounds on what one process can hold: the image, and with spp > 1 the per-pixel sums.
  const Camera& cam = scene.cameras[*camera];
  const long long pixels = static_cast<long long>(options.width > 0 ? options.width : cam.width) *
                           (options.height > 0 ? options.height : cam.height);
  const long long limit = options.spp > 1 ? kMaxSupersampledPixels : kMaxPixels;
  if (pixels > limit) {
    if (error)
      *error = "the image has " + std::to_string(pixels) + " pixels; at most " +
               std::to_string(limit) + (options.spp > 1 ? " with spp > 1" : "") + " can be rendered";
    return nullptr;
  }
  const Clock::time_point t0 = Clock::now();
  if (options.precision == Precision::f32) {
    auto prepared = prepare_scene<float>(scene, options, *camera);
    return std::make_unique<TiledRender<float>>(std::move(prepared), options,
                                                ms_between(t0, Clock::now()));
  }
  auto prepared = prepare_scene<double>(scene, options, *camera);
  return std::make_unique<TiledRender<double>>(std::move(prepared), options,
                                               ms_between(t0, Clock::now()));
}

Image render_image(const Scene& scene, const RenderOptions& options, int threads,
                   RenderStats* stats, const std::function<void(const RenderStats&)>& on_progress,
                   const std::atomic<bool>* cancel, std::string* error) {
  auto job = RenderJob::create(scene, options, error);
  if (!job) return {};
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  auto work = [&] {
    for (;;) {
      if (cancel && cancel->load()) job->cancel();
      RenderJob::Step step = job->run_step();
      if (step == RenderJob::Step::done) return;
      if (step == RenderJob::Step::wait) std::this_thread::yield();
      else if (on_progress) on_progress(job->stats());
    }
  };
  std::vector<std::thread> pool;
  for (int i = 1; i < threads; ++i) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (stats) *stats = job->stats();
  return job->image();
}

}  // namespace rayfarm
