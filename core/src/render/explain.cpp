// A pixel followed through the profile's own pipeline with a recorder attached to its
// tracer (recorder.h): the same preparation, sample points and film as a render, so the
// explained bytes are the rendered ones. Also the per-pixel records grading hints read.
#include "rayfarm/explain.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <mutex>
#include <thread>

#include "rayfarm/schema.h"
#include "render/cpsc102/reference_pipeline.h"
#include "render/film.h"
#include "render/lecture_pipeline.h"
#include "render/recorder.h"
#include "render/render_checks.h"

namespace rayfarm {

// One thread's tracer: traces sample k of pixel (x, image row r) into a recorder.
struct SampleTracer {
  virtual ~SampleTracer() = default;
  virtual Triple trace(int x, int r, int k, Recorder& rec) = 0;
};

struct Explainer::Backend {
  virtual ~Backend() = default;
  virtual int width() const = 0;
  virtual int height() const = 0;
  virtual int spp() const = 0;
  virtual std::unique_ptr<SampleTracer> tracer() const = 0;
  // The index in the scene's objects of the tracer's object number.
  virtual int file_index(int object) const = 0;
  // The pixel's mean and bytes from its samples' colours, as the render's film makes them.
  virtual void finish(PixelExplanation& e) const = 0;
};

namespace {

template <class T>
class LectureBackend final : public Explainer::Backend {
 public:
  LectureBackend(PreparedScene<T> scene, std::vector<int> sources, Film film)
      : p_(std::move(scene)), sources_(std::move(sources)), film_(film) {}

  int width() const override { return p_.width(); }
  int height() const override { return p_.height(); }
  int spp() const override { return p_.spp(); }
  int file_index(int object) const override { return sources_[static_cast<std::size_t>(object)]; }

  std::unique_ptr<SampleTracer> tracer() const override { return std::make_unique<Tracing>(p_); }

  void finish(PixelExplanation& e) const override {
    if (e.samples.size() == 1) {  // one pass: the film's bytes of the sample itself
      e.mean = e.samples[0].colour;
      film_.to_bytes(e.mean.data(), 3, e.bytes.data());
      return;
    }
    // One sample per pass, summed in pass order.
    Triple sum{}, comp{};
    for (const PathTrace& s : e.samples)
      for (int i = 0; i < 3; ++i) film_.accumulate(sum[i], comp[i], s.colour[i]);
    for (int i = 0; i < 3; ++i) {
      e.mean[i] = film_.mean(sum[i], comp[i], static_cast<int>(e.samples.size()));
      e.bytes[i] = film_.to_byte(e.mean[i]);
    }
  }

 private:
  struct Tracing final : SampleTracer {
    explicit Tracing(const LecturePipeline<T>& pipeline) : p(pipeline), tracer(p.scene()) {}
    Triple trace(int x, int r, int k, Recorder& rec) override {
      rec.clear();
      const Vec3<T> point = p.screen_point_of(x, r, k);
      rec.screen_point = triple(point);
      tracer.record(&rec);
      return triple(glm::dvec3(tracer.primary(point)));
    }
    const LecturePipeline<T>& p;
    Tracer<T, true> tracer;
  };

  LecturePipeline<T> p_;
  std::vector<int> sources_;  // per object number
  Film film_;
};

class ReferenceBackend final : public Explainer::Backend {
 public:
  ReferenceBackend(cpsc102::RefScene scene, Film film) : p_(std::move(scene)), film_(film) {}

  int width() const override { return p_.width(); }
  int height() const override { return p_.height(); }
  int spp() const override { return p_.spp(); }
  int file_index(int object) const override { return object; }  // file order already

  std::unique_ptr<SampleTracer> tracer() const override { return std::make_unique<Tracing>(p_); }

  void finish(PixelExplanation& e) const override {
    if (e.samples.size() == 1) {
      e.mean = e.samples[0].colour;
    } else {
      cpsc102::V3 sum;
      for (const PathTrace& s : e.samples)
        sum = cpsc102::add(sum, {s.colour[0], s.colour[1], s.colour[2]});
      const cpsc102::V3 mean = p_.mean_of(sum);
      e.mean = {mean.x, mean.y, mean.z};
    }
    film_.to_bytes(e.mean.data(), 3, e.bytes.data());
  }

 private:
  struct Tracing final : SampleTracer {
    explicit Tracing(const cpsc102::ReferencePipeline& pipeline) : p(pipeline), tracer(p.scene()) {}
    Triple trace(int x, int r, int k, Recorder& rec) override {
      if (x != pixel_x || r != pixel_r) {  // a pixel's points come from one run of its stream
        points = p.sample_points(x, r);
        pixel_x = x;
        pixel_r = r;
      }
      const std::array<double, 2>& w = points.at(static_cast<std::size_t>(k));
      rec.clear();
      rec.screen_point = {w[0], w[1], 0};
      tracer.record(&rec);
      const cpsc102::V3 c = tracer.primary(w[0], w[1]);
      return {c.x, c.y, c.z};
    }
    const cpsc102::ReferencePipeline& p;
    cpsc102::ReferenceTracer<true> tracer;
    std::vector<std::array<double, 2>> points;  // of pixel (pixel_x, pixel_r)
    int pixel_x = -1, pixel_r = -1;
  };

  cpsc102::ReferencePipeline p_;
  Film film_;
};

const char* status_name(RecordedLight::Status s) {
  switch (s) {
    case RecordedLight::lit: return "lit";
    case RecordedLight::filtered: return "filtered";
    case RecordedLight::shadowed: return "shadowed";
    case RecordedLight::faces_away: return "faces_away";
    case RecordedLight::outside_cone: return "outside_cone";
    case RecordedLight::off_slide: return "off_slide";
    case RecordedLight::at_point: return "at_point";
  }
  return "lit";
}

const char* ray_name(RecordedHit::Ray r) {
  switch (r) {
    case RecordedHit::Ray::reflected: return "reflected";
    case RecordedHit::Ray::transmitted: return "transmitted";
    default: return "primary";
  }
}

std::string formula_of(const RenderOptions& o) {
  if (o.profile == Profile::cpsc102)
    return "c = (ambient + Σ_lights [diffuse · E · N·L / d + E · specular · (N·H)^shininess]) / "
           "travelled, the highlight only where shininess is given; then, for a translucent "
           "object, c = (1 − transparency) · c + filter · transmitted; then, for one with a "
           "specular colour, c = c + specular · reflected. E is the light's emissivity (through "
           "any filters), d its distance, N the object's own normal, travelled the path length "
           "from the eye; nothing is clamped until the byte";
  const char* glint = o.highlight == Highlight::blinn ? "(N·H)" : "(R·V)";
  return std::string(
             "c = clamp01(ambient / travelled + Σ_lights E/r · (diffuse · N·L + specular · ") +
         glint +
         "^shininess)); then, for a translucent object, c = (1 − transparency) · c + filter · "
         "transmitted; then, for one with a specular colour, c = clamp01(c + specular · "
         "reflected). E is the light's emissivity (through any filters), r its distance, N the "
         "normal turned towards the ray, travelled the path length from the eye";
}

PathTrace path_of(const Recorder& rec, const Triple& colour, const Explainer::Backend& b,
                  const Scene& scene) {
  PathTrace out;
  out.screen_point = rec.screen_point;
  out.colour = colour;
  auto file_index = [&](int object) { return object < 0 ? -1 : b.file_index(object); };
  for (const RecordedHit& h : rec.hits) {
    PathHit& p = out.hits.emplace_back();
    p.ray = ray_name(h.ray);
    p.parent = h.parent;
    p.depth = h.depth;
    p.origin = h.origin;
    p.direction = h.direction;
    p.object = file_index(h.object);
    if (p.object >= 0) {
      const Object& o = scene.objects[static_cast<std::size_t>(p.object)];
      p.object_name = o.name;
      p.kind = std::string(entity_spec(o.kind).keyword);
      p.material = scene.materials[static_cast<std::size_t>(o.material)].name;
    }
    p.t = h.t;
    p.travelled = h.travelled;
    p.point = h.point;
    p.normal = h.normal;
    p.ambient = h.ambient;
    p.diffuse_colour = h.diffuse_colour;
    p.specular = h.specular;
    p.shininess = h.shininess;
    for (int i = h.first_light; i < h.first_light + h.light_count; ++i) {
      const RecordedLight& l = rec.lights[static_cast<std::size_t>(i)];
      LightTerm& t = p.lights.emplace_back();
      t.light = l.light;
      const Light& light = scene.lights[static_cast<std::size_t>(l.light)];
      t.name = light.name;
      t.source = {light.emissivity.x, light.emissivity.y, light.emissivity.z};
      t.slide = light.kind == LightKind::projector;
      t.status = status_name(l.status);
      t.blocker = file_index(l.blocker);
      if (t.blocker >= 0) {
        const Object& o = scene.objects[static_cast<std::size_t>(t.blocker)];
        t.blocker_name = o.name;
        t.blocker_kind = std::string(entity_spec(o.kind).keyword);
      }
      t.distance = l.distance;
      t.n_dot_l = l.n_dot_l;
      t.emissivity = l.emissivity;
      t.diffuse = l.diffuse;
      t.specular = l.specular;
      t.highlight_base = l.highlight_base;
      t.diffuse_distance = l.diffuse_distance;
    }
    p.local = h.local;
    p.value = h.value;
    p.capped = h.capped;
    p.reflected = h.reflected;
    p.transmitted = h.transmitted;
    p.weight = h.weight;
    p.filter = h.filter;
    p.keep = h.keep;
  }
  return out;
}

bool nonzero(const Triple& c) { return c[0] != 0 || c[1] != 0 || c[2] != 0; }

// `reach` is scratch space: per hit, how much of its colour reaches the pixel (the
// reflection weights and filters on the way, unclamped).
PixelRecord record_of(const Recorder& rec, const Explainer::Backend& b, Profile profile,
                      std::vector<Triple>& reach) {
  PixelRecord out;
  if (rec.hits.empty()) return out;
  reach.assign(rec.hits.size(), Triple{1, 1, 1});
  double first_glint = 0;
  for (std::size_t k = 0; k < rec.hits.size(); ++k) {
    const RecordedHit& h = rec.hits[k];
    if (h.reflected >= 0 && nonzero(h.weight)) out.flags |= PixelRecord::reflection;
    if (h.transmitted >= 0 && nonzero(h.filter)) out.flags |= PixelRecord::transmission;
    if (h.capped) out.flags |= PixelRecord::capped;
    if (h.parent >= 0) {  // parents come first
      const RecordedHit& p = rec.hits[static_cast<std::size_t>(h.parent)];
      const Triple& by = h.ray == RecordedHit::Ray::reflected ? p.weight : p.filter;
      for (int c = 0; c < 3; ++c)
        reach[k][c] = reach[static_cast<std::size_t>(h.parent)][c] * by[c];
    }
    if (h.object < 0 || !nonzero(reach[k])) continue;
    // cpsc102 divides the lights' terms by travelled with the ambient colour.
    const double share = profile == Profile::cpsc102 ? 1 / h.travelled : 1;
    bool blocked = false;
    double glint = 0;
    for (int i = h.first_light; i < h.first_light + h.light_count; ++i) {
      const RecordedLight& l = rec.lights[static_cast<std::size_t>(i)];
      blocked =
          blocked || l.status == RecordedLight::shadowed || l.status == RecordedLight::filtered;
      for (int c = 0; c < 3; ++c) glint = std::max(glint, l.specular[c] * share * reach[k][c]);
    }
    if (k == 0) {
      first_glint = glint;
      if (blocked) out.flags |= PixelRecord::shadow;
      if (glint >= 0.5 / 255) out.flags |= PixelRecord::highlight;
    } else {
      if (blocked) out.flags |= PixelRecord::later_shadow;
      if (glint >= 0.5 / 255) out.flags |= PixelRecord::later_highlight;
    }
  }
  const RecordedHit& first = rec.hits.front();
  if (first.object < 0) return out;
  out.flags |= PixelRecord::hit;
  out.object = b.file_index(first.object);
  out.highlight_level = static_cast<std::uint8_t>(std::min(255.0, std::ceil(first_glint * 255)));
  return out;
}

}  // namespace

Explainer::Explainer(const Scene& scene, const RenderOptions& options,
                     std::unique_ptr<Backend> backend)
    : scene_(scene), options_(options), backend_(std::move(backend)) {}

Explainer::~Explainer() = default;

std::unique_ptr<Explainer> Explainer::create(const Scene& scene, const RenderOptions& options,
                                             std::string* error) {
  const std::optional<int> camera = check_render(scene, options, error);
  if (!camera) return nullptr;
  const Film film{options.effective_rounding(), options.profile == Profile::cpsc102};
  std::unique_ptr<Backend> backend;
  if (options.profile == Profile::cpsc102)
    backend = std::make_unique<ReferenceBackend>(
        cpsc102::prepare_reference(scene, options, *camera), film);
  else if (options.precision == Precision::f32)
    backend = std::make_unique<LectureBackend<float>>(prepare_scene<float>(scene, options, *camera),
                                                      object_sources(scene), film);
  else
    backend = std::make_unique<LectureBackend<double>>(
        prepare_scene<double>(scene, options, *camera), object_sources(scene), film);
  return std::unique_ptr<Explainer>(new Explainer(scene, options, std::move(backend)));
}

int Explainer::width() const { return backend_->width(); }
int Explainer::height() const { return backend_->height(); }

std::optional<PixelExplanation> Explainer::explain(int x, int y, std::string* error,
                                                   int samples) const {
  if (x < 0 || y < 0 || x >= width() || y >= height()) {
    if (error)
      *error = "pixel (" + std::to_string(x) + ", " + std::to_string(y) +
               ") is outside the image: it has " + std::to_string(width()) + "x" +
               std::to_string(height()) + " pixels, (0, 0) at the top left";
    return std::nullopt;
  }
  PixelExplanation e;
  e.x = x;
  e.y = y;
  e.width = width();
  e.height = height();
  e.profile = options_.profile;
  e.precision = options_.precision;
  e.highlight = options_.highlight;
  e.max_dist = options_.effective_max_dist();
  e.formula = formula_of(options_);
  e.rounding = std::string(to_string(options_.effective_rounding()));
  const std::unique_ptr<SampleTracer> tracer = backend_->tracer();
  Recorder rec;
  const int spp = std::max(1, backend_->spp());
  for (int k = 0; k < (samples > 0 ? std::min(samples, spp) : spp); ++k) {
    // Past the listed samples only the colour counts: no blockers named, no hits copied.
    if (k == kExplainedSamples) rec.blockers = false;
    const Triple colour = tracer->trace(x, y, k, rec);
    if (k < kExplainedSamples) {
      e.samples.push_back(path_of(rec, colour, *backend_, scene_));
    } else {
      PathTrace& sample = e.samples.emplace_back();
      sample.screen_point = rec.screen_point;
      sample.colour = colour;
    }
  }
  backend_->finish(e);
  return e;
}

PixelRecord Explainer::record(int x, int y) const {
  Recorder rec;
  rec.blockers = false;
  backend_->tracer()->trace(x, y, 0, rec);
  std::vector<Triple> reach;
  return record_of(rec, *backend_, options_.profile, reach);
}

std::vector<PixelRecord> Explainer::record_all(int threads) const {
  const int w = width(), h = height();
  std::vector<PixelRecord> out(static_cast<std::size_t>(w) * h);
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  threads = std::max(1, std::min(threads, h));
  std::atomic<int> next_row{0};
  std::mutex mu;
  std::exception_ptr failure;  // (out of memory) rethrown here, not on a worker
  auto work = [&] {
    try {
      const std::unique_ptr<SampleTracer> tracer = backend_->tracer();
      Recorder rec;
      rec.blockers = false;
      std::vector<Triple> reach;
      for (int r; (r = next_row.fetch_add(1)) < h;)
        for (int x = 0; x < w; ++x) {
          tracer->trace(x, r, 0, rec);
          out[static_cast<std::size_t>(r) * w + x] =
              record_of(rec, *backend_, options_.profile, reach);
        }
    } catch (...) {
      std::lock_guard lock(mu);
      if (!failure) failure = std::current_exception();
      next_row.store(h);
    }
  };
  std::vector<std::thread> pool;
  for (int i = 1; i < threads; ++i) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
  return out;
}

std::optional<PixelExplanation> explain_pixel(const Scene& scene, const RenderOptions& options,
                                              int x, int y, std::string* error) {
  const std::unique_ptr<Explainer> explainer = Explainer::create(scene, options, error);
  if (!explainer) return std::nullopt;
  return explainer->explain(x, y, error);
}

std::optional<std::vector<PixelRecord>> record_pixels(const Scene& scene,
                                                      const RenderOptions& options, int threads,
                                                      std::string* error) {
  const std::unique_ptr<Explainer> explainer = Explainer::create(scene, options, error);
  if (!explainer) return std::nullopt;
  return explainer->record_all(threads);
}

}  // namespace rayfarm
