// Tiled, progressive rendering: pass k gives every pixel its sample k, tiles of a pass run
// in any order on any thread, and each pixel sums its samples in sample order, so the bytes
// never depend on the thread count. The profile decides the pipeline and the film.
#include "rayfarm/render.h"

#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <optional>
#include <system_error>
#include <thread>

#include "render/cpsc102/reference_pipeline.h"
#include "render/film.h"
#include "render/lecture_pipeline.h"
#include "render/render_checks.h"

namespace rayfarm {
namespace {

using Clock = std::chrono::steady_clock;

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// Tiles and passes of any pipeline (lecture_pipeline.h, cpsc102/reference_pipeline.h): a
// pass gives every pixel its next samples; the film (film.h) turns their sums into bytes.
template <class Pipeline>
class TiledRender final : public RenderJob {
 public:
  TiledRender(std::shared_ptr<const Pipeline> pipeline, const RenderOptions& options, Film film,
              TileRange range, double prepare_ms)
      : pipeline_(std::move(pipeline)),
        p_(*pipeline_),
        options_(options),
        film_(film),
        grid_(p_.width(), p_.height()),
        range_(range),
        row0_(grid_.bounds(range.first).r0),
        row1_(grid_.bounds(range.end - 1).r1),
        passes_(std::max(1, p_.spp() / p_.samples_per_pass())),
        image_(p_.width(), row1_ - row0_),
        next_tile_(range.first),
        prepare_ms_(prepare_ms) {
    if (passes_ > 1) {
      sum_.assign(static_cast<size_t>(p_.width()) * (row1_ - row0_) * 3, 0.0);
      comp_.assign(sum_.size(), 0.0);
      sum_sq_.assign(sum_.size(), 0.0);
    }
    tile_error_.assign(grid_.count(), 0.0);
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
      if (next_tile_ == range_.end) return Step::wait;
      if (next_tile_ == range_.first && passes_done_ == 0) start_ = Clock::now();
      if (next_tile_ == range_.first) pass_start_ = Clock::now();
      tile = next_tile_++;
      pass = passes_done_;
    }
    // Per render thread, reused from tile to tile, as the pipelines' buffers are (malloc's
    // lock: lecture_pipeline.h).
    thread_local std::vector<std::uint8_t> bytes;
    RayCounts counts;
    bool complete = render_tile(tile, pass, bytes, counts);
    std::lock_guard lock(mu_);
    primary_ += counts.primary;
    shadow_ += counts.shadow;
    reflection_ += counts.reflection;
    if (!complete || finished_) return finished_ ? Step::done : Step::ran;
    copy_tile(tile, bytes);
    if (++done_in_pass_ == range_.count()) end_pass();
    return Step::ran;
  }

  void cancel() override { cancel_.store(true); }
  bool canceled() const override { return cancel_.load(); }
  bool finished() const override {
    std::lock_guard lock(mu_);
    return finished_;
  }
  int width() const override { return p_.width(); }
  int height() const override { return p_.height(); }
  TileRange range() const override { return range_; }
  std::vector<double> tile_errors() const override {
    std::lock_guard lock(mu_);
    return {tile_error_.begin() + range_.first, tile_error_.begin() + range_.end};
  }

  Image image() const override {
    std::lock_guard lock(mu_);
    if (row0_ == 0 && row1_ == p_.height()) return image_;
    Image full(p_.width(), p_.height());
    std::copy(image_.rgb.begin(), image_.rgb.end(), full.row(row0_));
    return full;
  }

  Image take_image() override {
    {
      std::lock_guard lock(mu_);
      if (finished_ && row0_ == 0 && row1_ == p_.height()) {
        Image out = std::move(image_);
        image_ = Image();
        return out;
      }
    }
    return image();
  }

  std::vector<std::uint8_t> range_pixels() const override {
    std::lock_guard lock(mu_);
    std::vector<std::uint8_t> out;
    for (int t = range_.first; t < range_.end; ++t) {
      const TileBounds b = grid_.bounds(t);
      for (int r = b.r0; r < b.r1; ++r)
        out.insert(out.end(), image_.row(r - row0_) + b.x0 * 3, image_.row(r - row0_) + b.x1 * 3);
    }
    return out;
  }

  RenderStats stats() const override {
    std::lock_guard lock(mu_);
    RenderStats st;
    st.primary_rays = primary_;
    st.shadow_rays = shadow_;
    st.reflection_rays = reflection_;
    st.prepare_ms = prepare_ms_;
    if (passes_done_ > 0 || done_in_pass_ > 0 || next_tile_ > range_.first)
      st.render_ms = ms_between(start_, finished_ ? end_ : Clock::now());
    st.spp_done = passes_done_ * p_.samples_per_pass();
    st.spp_target = p_.spp();
    st.tiles_done = done_in_pass_;
    st.tiles_per_pass = range_.count();
    st.error_estimate = error_;
    st.parts = p_.parts();
    st.stop_reason = stop_reason_;
    st.finished = finished_;
    st.samples_per_pass = p_.samples_per_pass();
    return st;
  }

 private:
  // Renders one tile of one pass into `bytes` (its rows top to bottom). Returns false when
  // canceled part way.
  bool render_tile(int tile, int pass, std::vector<std::uint8_t>& bytes, RayCounts& counts) {
    const TileBounds b = grid_.bounds(tile);
    thread_local std::vector<glm::dvec3> colours;
    double tile_error = 0;
    if (!p_.render_tile(b, pass, colours, counts, tile_error,
                        [&] { return cancel_.load(std::memory_order_relaxed); }))
      return false;
    bytes.resize(colours.size() * 3);
    std::uint8_t* out = bytes.data();
    const glm::dvec3* c = colours.data();
    if (passes_ == 1) {
      film_.to_bytes(&colours[0][0], colours.size() * 3, out);
      tile_error_[tile] = tile_error;
      return true;
    }
    const double n = pass + 1;
    for (int r = b.r0; r < b.r1; ++r)
      for (int x = b.x0; x < b.x1; ++x, ++c) {
        size_t i = (static_cast<size_t>(r - row0_) * p_.width() + x) * 3;
        for (int k = 0; k < 3; ++k) {
          double ck = (*c)[k];
          film_.accumulate(sum_[i + k], comp_[i + k], ck);
          sum_sq_[i + k] += ck * ck;
          double mean = film_.mean(sum_[i + k], comp_[i + k], pass + 1);
          *out++ = film_.to_byte(mean);
          if (n >= 2) {
            double var = (sum_sq_[i + k] - sum_[i + k] * (sum_[i + k] / n)) / (n - 1);
            tile_error += (var > 0 ? var : 0) / n;
          }
        }
      }
    tile_error_[tile] = tile_error;
    return true;
  }

  void copy_tile(int tile, const std::vector<std::uint8_t>& bytes) {
    const TileBounds b = grid_.bounds(tile);
    const int w = b.width(), rows = b.rows();
    for (int r = 0; r < rows; ++r)
      std::copy_n(bytes.data() + static_cast<size_t>(r) * w * 3, w * 3, image_.row(b.r0 - row0_ + r) + b.x0 * 3);
  }

  // Called under the lock by whoever finishes the last tile of a pass.
  void end_pass() {
    ++passes_done_;
    const bool estimate = passes_done_ >= 2 || (p_.samples_per_pass() > 1 && p_.spp() > 1);
    if (estimate) {
      double total = 0;
      for (double e : tile_error_) total += e;  // tile order: deterministic
      error_ = 255 * std::sqrt(total / (static_cast<double>(p_.width()) * p_.height() * 3));
    }
    const Clock::time_point now = Clock::now();
    const double pass_ms = ms_between(pass_start_, now);
    if (passes_done_ >= passes_) finish("spp");
    else if (options_.target_error > 0 && passes_done_ >= 2 && error_ <= options_.target_error)
      finish("target_error");
    else if (options_.time_limit > 0 &&
             ms_between(start_, now) + pass_ms > options_.time_limit * 1000)
      finish("time_limit");
    else {
      next_tile_ = range_.first;
      done_in_pass_ = 0;
    }
  }

  void finish(const char* reason) {
    finished_ = true;
    stop_reason_ = reason;
    end_ = Clock::now();
  }

  const std::shared_ptr<const Pipeline> pipeline_;  // shared by the jobs of one PreparedRender
  const Pipeline& p_;
  const RenderOptions options_;
  const Film film_;
  const TileGrid grid_;
  const TileRange range_;
  const int row0_, row1_;  // the rows the range's tiles span: the image and sums kept
  const int passes_;

  mutable std::mutex mu_;
  Image image_;                       // rows row0_ to row1_
  // Per pixel channel of those rows, only with several passes: the sum (film.h), its
  // compensation, and the sum of squares (the error estimate).
  std::vector<double> sum_, comp_, sum_sq_;
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
  return (spp_done + static_cast<double>(tiles_done) / tiles_per_pass * samples_per_pass) /
         spp_target;
}

std::string image_size_error(long long width, long long height, int spp) {
  const long long pixels = width * height;
  const long long limit = spp > 1 ? kMaxSupersampledPixels : kMaxPixels;
  if (pixels <= limit) return {};
  return "the image has " + std::to_string(pixels) + " pixels (" + std::to_string(width) + " x " +
         std::to_string(height) + "); at most " + std::to_string(limit) +
         (spp > 1 ? " with spp > 1" : "") + " can be rendered";
}

std::optional<int> check_render(const Scene& scene, const RenderOptions& options,
                                std::string* error) {
  auto camera = scene.find_camera(options.camera);
  if (!camera) {
    if (error) {
      const std::string names = scene.camera_names();
      *error = "no camera named '" + options.camera + "'" +
               (names.empty() ? "" : " (cameras: " + names + ")");
    }
    return std::nullopt;
  }
  // Bounds on what one process can hold: the image, and with spp > 1 the per-pixel sums.
  const Camera& cam = scene.cameras[*camera];
  if (std::string size = image_size_error(options.width > 0 ? options.width : cam.width,
                                          options.height > 0 ? options.height : cam.height,
                                          options.spp);
      !size.empty()) {
    if (error) *error = std::move(size);
    return std::nullopt;
  }
  for (const Texture& t : scene.textures)
    if (!t.image) {
      if (error)
        *error = "texture '" + (t.name.empty() ? t.path : t.name) + "' ('" + t.path +
                 "') was not provided: textures are read with the scene";
      return std::nullopt;
    }
  if (std::string conflict = profile_conflict(options); !conflict.empty()) {
    if (error) *error = conflict;
    return std::nullopt;
  }
  return camera;
}

int tile_count(int width, int height) { return TileGrid(width, height).count(); }

std::unique_ptr<RenderJob> RenderJob::create(const Scene& scene, const RenderOptions& options,
                                             std::string* error) {
  return create(scene, options, TileRange{0, -1}, error);
}

namespace {

template <class Pipeline>
class PreparedPipeline final : public PreparedRender {
 public:
  PreparedPipeline(Pipeline pipeline, const RenderOptions& options, double prepare_ms)
      : pipeline_(std::make_shared<const Pipeline>(std::move(pipeline))),
        options_(options),
        film_{options.effective_rounding(), options.profile == Profile::cpsc102},
        tiles_(tile_count(pipeline_->width(), pipeline_->height())),
        prepare_ms_(prepare_ms) {}

  std::unique_ptr<RenderJob> job(TileRange range, std::string* error) const override {
    if (range.first < 0 || range.first >= range.end || range.end > tiles_) {
      if (error)
        *error = "tiles " + std::to_string(range.first) + " to " + std::to_string(range.end) +
                 " are not a range of the image's " + std::to_string(tiles_) + " tiles";
      return nullptr;
    }
    if (range.count() < tiles_ && (options_.target_error > 0 || options_.time_limit > 0)) {
      if (error)
        *error = "a part of an image cannot stop at a target error or a time limit: those "
                 "decide on the whole image after each pass";
      return nullptr;
    }
    return std::make_unique<TiledRender<Pipeline>>(pipeline_, options_, film_, range, prepare_ms_);
  }
  int tiles() const override { return tiles_; }
  double prepare_ms() const override { return prepare_ms_; }

 private:
  std::shared_ptr<const Pipeline> pipeline_;
  RenderOptions options_;
  Film film_;
  int tiles_;
  double prepare_ms_;
};

template <class Pipeline>
std::shared_ptr<const PreparedRender> prepared(Pipeline pipeline, const RenderOptions& options,
                                               Clock::time_point t0) {
  return std::make_shared<PreparedPipeline<Pipeline>>(std::move(pipeline), options,
                                                      ms_between(t0, Clock::now()));
}

// PreparedRender::create; `spent` (optional) is scene.objects, freed once read.
std::shared_ptr<const PreparedRender> create_prepared(const Scene& scene,
                                                      const RenderOptions& options,
                                                      std::string* error,
                                                      std::vector<Object>* spent) {
  const std::optional<int> camera = check_render(scene, options, error);
  if (!camera) return nullptr;
  const Clock::time_point t0 = Clock::now();
  if (options.profile == Profile::cpsc102) {
    auto p =
        prepared(cpsc102::ReferencePipeline(cpsc102::prepare_reference(scene, options, *camera)),
                 options, t0);
    if (spent) std::vector<Object>().swap(*spent);
    return p;
  }
  if (options.precision == Precision::f32)
    return prepared(LecturePipeline<float>(prepare_scene<float>(scene, options, *camera, 0, spent)),
                    options, t0);
  return prepared(LecturePipeline<double>(prepare_scene<double>(scene, options, *camera, 0, spent)),
                  options, t0);
}

}  // namespace

std::shared_ptr<const PreparedRender> PreparedRender::create(const Scene& scene,
                                                             const RenderOptions& options,
                                                             std::string* error) {
  return create_prepared(scene, options, error, nullptr);
}

std::shared_ptr<const PreparedRender> PreparedRender::create(Scene&& scene,
                                                             const RenderOptions& options,
                                                             std::string* error) {
  return create_prepared(scene, options, error, &scene.objects);
}

std::unique_ptr<RenderJob> RenderJob::create(const Scene& scene, const RenderOptions& options,
                                             TileRange range, std::string* error) {
  auto prepared = PreparedRender::create(scene, options, error);
  if (!prepared) return nullptr;
  if (range.first == 0 && range.end == -1) range.end = prepared->tiles();
  return prepared->job(range, error);
}

namespace {

// Runs a job on `threads` threads of its own (render_image).
Image run_job(std::unique_ptr<RenderJob> job, int threads, RenderStats* stats,
              const std::function<void(const RenderStats&)>& on_progress,
              const std::atomic<bool>* cancel) {
  if (!job) return {};
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  // A failure on any thread (out of memory) stops the job and is rethrown here, once every
  // thread has ended: never a terminate from a worker or from a joinable thread unwound.
  std::mutex failed_mu;
  std::exception_ptr failure;
  auto work = [&] {
    try {
      for (;;) {
        if (cancel && cancel->load()) job->cancel();
        RenderJob::Step step = job->run_step();
        if (step == RenderJob::Step::done) return;
        if (step == RenderJob::Step::wait) std::this_thread::yield();
        else if (on_progress) on_progress(job->stats());
      }
    } catch (...) {
      {
        std::lock_guard lock(failed_mu);
        if (!failure) failure = std::current_exception();
      }
      job->cancel();
    }
  };
  std::vector<std::thread> pool;
  try {
    for (int i = 1; i < threads; ++i) pool.emplace_back(work);
  } catch (const std::system_error&) {
    // No more threads to be had (a process limit): the ones started share the work.
  }
  work();
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
  if (stats) *stats = job->stats();
  return job->take_image();
}

}  // namespace

Image render_image(const Scene& scene, const RenderOptions& options, int threads,
                   RenderStats* stats, const std::function<void(const RenderStats&)>& on_progress,
                   const std::atomic<bool>* cancel, std::string* error) {
  return run_job(RenderJob::create(scene, options, error), threads, stats, on_progress, cancel);
}

Image render_image(Scene&& scene, const RenderOptions& options, int threads, RenderStats* stats,
                   const std::function<void(const RenderStats&)>& on_progress,
                   const std::atomic<bool>* cancel, std::string* error) {
  auto prepared = PreparedRender::create(std::move(scene), options, error);
  return run_job(prepared ? prepared->job({0, prepared->tiles()}, error) : nullptr, threads, stats,
                 on_progress, cancel);
}

}  // namespace rayfarm
