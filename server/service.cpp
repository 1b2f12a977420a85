// The render service: submission, job table, results, expiry.
#include "service.h"

#include <fstream>
#include <set>
#include <random>
#include <sstream>

#include "rayfarm/image_io.h"
#include "rayfarm/load.h"
#include "rayfarm/sha256.h"
#include "rayfarm/writers.h"

namespace rayfarm::server {
namespace fs = std::filesystem;

nlohmann::json ApiError::body() const {
  nlohmann::json e = {{"code", code}, {"message", message}};
  if (line > 0) {
    e["line"] = line;
    e["column"] = column;
  }
  if (!path.empty()) e["path"] = path;
  if (!limit.empty()) e["limit"] = limit;
  if (!details.is_null()) e["errors"] = details;
  return {{"error", e}};
}

std::string random_id() {
  static thread_local std::random_device device;
  static const char* kHex = "0123456789abcdef";
  std::string id;
  for (int i = 0; i < 4; ++i) {
    std::uint32_t v = device();
    for (int s = 28; s >= 0; s -= 4) id += kHex[(v >> s) & 15];
  }
  return id;
}

namespace {

ApiError error(int status, std::string code, std::string message) {
  ApiError e;
  e.status = status;
  e.code = std::move(code);
  e.message = std::move(message);
  return e;
}

ApiError limit_error(const std::string& limit, const std::string& message) {
  ApiError e = error(422, "limit_exceeded", message);
  e.limit = limit;
  return e;
}

ApiError scene_error(const Diagnostics& diags) {
  const Diagnostic* first = diags.first_error();
  ApiError e = error(400, "invalid_scene", first ? first->message : "invalid scene");
  if (first) {
    e.line = first->where.line;
    e.column = first->where.column;
    e.path = first->where.path;
  }
  e.details = nlohmann::json::array();
  for (const Diagnostic& d : diags.items()) {
    if (d.severity != Severity::error) continue;
    nlohmann::json item = {{"code", d.code}, {"message", d.message}};
    if (d.where.line > 0) {
      item["line"] = d.where.line;
      item["column"] = d.where.column;
    }
    if (!d.where.path.empty()) item["path"] = d.where.path;
    e.details.push_back(item);
  }
  return e;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The cache key: the scene as parsed (so layout and comments do not matter, and a model file
// and its JSON twin share results) and every option that changes pixels.
std::string content_key(const SceneDesc& desc, RenderOptions options) {
  options.format = ImageFormat::png;
  return sha256_hex(write_json(desc) + "\n" + canonical_string(options)).substr(0, 40);
}

}  // namespace

Service::Service(Settings settings)
    : settings_(std::move(settings)),
      store_(settings_.results_dir),
      cache_(settings_.cache_bytes) {
  int workers = settings_.workers > 0 ? settings_.workers
                                      : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  Scheduler::Hooks hooks;
  hooks.started = [this](Job& job) { persist(job); };
  hooks.finished = [this](Job& job, RenderJob* render) { on_finished(job, render); };
  scheduler_ = std::make_unique<Scheduler>(workers, 4, settings_.job_timeout, std::move(hooks));
  load_samples();
  restore();
  janitor_ = std::thread([this] {
    while (!stop_janitor_) {
      for (int i = 0; i < 100 && !stop_janitor_; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (!stop_janitor_) expire();
    }
  });
}

Service::~Service() {
  stop_janitor_ = true;
  if (janitor_.joinable()) janitor_.join();
  scheduler_->stop();
}

std::shared_ptr<Job> Service::new_job(const std::string& client) {
  auto job = std::make_shared<Job>();
  job->id = random_id();
  job->client = client;
  job->created_ms = now_ms();
  std::lock_guard lock(mu_);
  job->sequence = ++sequence_;
  return job;
}

Submitted Service::submit(const std::string& scene_text, const Params& params,
                          const std::string& client) {
  if (shutting_down_) {
    ApiError e = error(503, "shutting_down", "the server is shutting down; try again shortly");
    e.retry_after = 5;
    return {nullptr, e};
  }
  if (scheduler_->waiting() + scheduler_->active() >=
      static_cast<size_t>(settings_.queue_capacity)) {
    metrics_.rejected("queue_full");
    ApiError e = error(429, "queue_full",
                       "the render queue is full (" + std::to_string(settings_.queue_capacity) +
                           " jobs); try again later");
    e.retry_after = 2;
    return {nullptr, e};
  }
  {
    std::lock_guard lock(mu_);
    int mine = 0;
    for (auto& [id, j] : jobs_) {
      std::lock_guard jl(j->mu);
      mine += j->client == client && !is_final(j->state);
    }
    if (mine >= settings_.max_jobs_per_client) {
      metrics_.rejected("client_limit");
      ApiError e = error(429, "too_many_jobs",
                         "you have " + std::to_string(mine) +
                             " jobs queued or running; wait for some to finish");
      e.retry_after = 2;
      return {nullptr, e};
    }
  }

  LoadedScene loaded = load_scene(scene_text);
  if (!loaded.scene) return {nullptr, scene_error(loaded.diags)};
  auto scene = std::make_shared<const Scene>(std::move(*loaded.scene));

  RenderOptions options;
  Diagnostics diags;
  apply_options(options, scene->render, diags);
  OptionSet query;
  for (auto& [k, v] : params) query.push_back({k, v, {0, 0, k}});
  apply_options(options, query, diags);
  if (diags.has_errors()) {
    const Diagnostic* d = diags.first_error();
    ApiError e = error(400, "invalid_option", d->message);
    e.path = d->where.path;
    return {nullptr, e};
  }
  auto camera = scene->find_camera(options.camera);
  if (!camera) return {nullptr, error(400, "invalid_option", "no camera named '" + options.camera + "'")};
  const Camera& cam = scene->cameras[*camera];
  int width = options.width > 0 ? options.width : cam.width;
  int height = options.height > 0 ? options.height : cam.height;
  if (ApiError e = check_limits(*scene, options, width, height)) {
    metrics_.rejected(e.limit);
    return {nullptr, e};
  }

  auto job = new_job(client);
  job->scene_text = scene_text;
  job->scene = scene;
  job->options = options;
  job->width = width;
  job->height = height;
  // A time limit makes the result depend on the machine's speed: never shared.
  if (options.time_limit == 0) job->cache_key = content_key(loaded.desc, options);
  job->image_name = job->cache_key.empty() ? job->id : job->cache_key;

  bool hit = !job->cache_key.empty() &&
             (cache_.get(job->cache_key) || store_.has_image(job->cache_key));
  if (hit) {
    std::lock_guard jl(job->mu);
    job->state = JobState::done;
    job->cache_hit = true;
    job->started_ms = job->finished_ms = job->created_ms;
    job->stats.finished = true;
    job->stats.spp_target = job->stats.spp_done = options.spp;
  }
  if (!job->cache_key.empty()) metrics_.cache(hit);
  try {
    if (!hit) store_.save_scene(job->id, scene_text);
    store_.save_record(*job);
  } catch (const std::exception& ex) {
    ApiError e = error(503, "storage_error", std::string("cannot store the job: ") + ex.what());
    e.retry_after = 10;
    return {nullptr, e};
  }
  {
    std::lock_guard lock(mu_);
    jobs_[job->id] = job;
  }
  if (!hit) scheduler_->submit(job);
  return {job, {}};
}

ApiError Service::check_limits(const Scene& scene, const RenderOptions& o, int width, int height) {
  const Settings& s = settings_;
  long long pixels = static_cast<long long>(width) * height;
  if (pixels > s.max_pixels)
    return limit_error("max_pixels", "the image has " + std::to_string(pixels) +
                                         " pixels; the limit is " + std::to_string(s.max_pixels));
  if (o.spp > s.max_spp)
    return limit_error("max_spp", "spp " + std::to_string(o.spp) + " is over the limit of " +
                                      std::to_string(s.max_spp));
  if (o.max_depth > s.max_depth)
    return limit_error("max_depth", "max_depth " + std::to_string(o.max_depth) +
                                        " is over the limit of " + std::to_string(s.max_depth));
  size_t objects = scene.spheres.size() + scene.planes.size();
  if (objects > static_cast<size_t>(s.max_objects))
    return limit_error("max_objects", "the scene has " + std::to_string(objects) +
                                          " objects; the limit is " + std::to_string(s.max_objects));
  double work = static_cast<double>(pixels) * o.spp * (o.max_depth + 1);
  if (work > s.max_work)
    return limit_error("max_work", "pixels x spp x (max_depth + 1) is " + format_number(work) +
                                       "; the limit is " + format_number(s.max_work));
  if (scene.lights.size() > static_cast<size_t>(s.max_lights))
    return limit_error("max_lights", "the scene has " + std::to_string(scene.lights.size()) +
                                         " lights; the limit is " + std::to_string(s.max_lights));
  return {};
}

std::shared_ptr<Job> Service::find(const std::string& id) const {
  std::lock_guard lock(mu_);
  auto it = jobs_.find(id);
  return it == jobs_.end() ? nullptr : it->second;
}

std::vector<std::shared_ptr<Job>> Service::jobs_of(const std::string& client, size_t limit) const {
  std::vector<std::shared_ptr<Job>> out;
  {
    std::lock_guard lock(mu_);
    for (auto& [id, j] : jobs_)
      if (j->client == client) out.push_back(j);
  }
  std::sort(out.begin(), out.end(), [](auto& a, auto& b) { return a->sequence > b->sequence; });
  if (out.size() > limit) out.resize(limit);
  return out;
}

ApiError Service::cancel(const std::string& id, const std::string& client) {
  auto job = find(id);
  if (!job) return error(404, "not_found", "no job " + id);
  if (job->client != client)
    return error(403, "forbidden", "only the client that submitted a job can cancel it");
  {
    std::lock_guard jl(job->mu);
    if (is_final(job->state)) {
      if (job->state == JobState::canceled) return {};
      return error(409, "already_finished", "the job has already " +
                                                std::string(job->state == JobState::done
                                                                ? "finished"
                                                                : "failed"));
    }
  }
  scheduler_->cancel(job);
  return {};
}

void Service::persist(const Job& job) {
  try {
    store_.save_record(job);
  } catch (const std::exception&) {
    // The job goes on; after a restart it runs again, which is safe.
  }
}

void Service::on_finished(Job& job, RenderJob* render) {
  RenderStats st = render ? render->stats() : RenderStats{};
  JobState state;
  std::string code, message;
  std::shared_ptr<const std::string> png;
  {
    std::lock_guard jl(job.mu);
    if (!render) {
      state = job.error.empty() ? JobState::canceled : JobState::failed;
      code = job.error_code;
      message = job.error;
    } else if (job.timed_out) {
      state = JobState::failed;
      code = "timeout";
      message = "the job ran longer than the server's limit of " +
                format_number(settings_.job_timeout) + " s (--job-timeout)";
    } else if (!job.error.empty()) {
      state = JobState::failed;
      code = job.error_code;
      message = job.error;
    } else if (st.stop_reason == "canceled") {
      // Stopped by its client, or interrupted by a shutdown (a cancel that came after the
      // last tile does not discard a complete image).
      state = job.cancel_requested ? JobState::canceled : JobState::queued;
    } else {
      state = JobState::done;
    }
  }
  if (state == JobState::queued) {
    // Interrupted by a shutdown: it stays queued on disk and runs again after a restart.
    std::lock_guard jl(job.mu);
    job.state = JobState::queued;
    job.attempts = std::max(0, job.attempts - 1);
    job.stats = st;
  } else {
    if (state == JobState::done) {
      try {
        auto bytes = encode_png(render->image());
        png = std::make_shared<const std::string>(bytes.begin(), bytes.end());
        store_.save_image(job.image_name, *png);
        cache_.put(job.image_name, png);
      } catch (const std::exception& ex) {
        state = JobState::failed;
        code = "storage_error";
        message = std::string("could not store the result: ") + ex.what();
      }
    }
    std::lock_guard jl(job.mu);
    job.state = state;
    job.error_code = code;
    job.error = message;
    job.finished_ms = now_ms();
    job.stats = render ? st : job.stats;
    job.render.reset();
    ++job.version;
  }
  job.changed.notify_all();
  persist(job);
  if (state != JobState::queued)
    metrics_.render_finished(std::string(to_string(state)), st.render_ms / 1000, st.primary_rays,
                             st.shadow_rays, st.reflection_rays);
}

std::shared_ptr<const std::string> Service::result_png(const Job& job) {
  if (auto hit = cache_.get(job.image_name)) return hit;
  if (auto disk = store_.load_image(job.image_name)) {
    auto png = std::make_shared<const std::string>(std::move(*disk));
    cache_.put(job.image_name, png);
    return png;
  }
  return nullptr;
}

std::optional<Image> Service::current_image(const Job& job) {
  std::shared_ptr<RenderJob> render;
  JobState state;
  {
    std::lock_guard jl(job.mu);
    render = job.render;
    state = job.state;
  }
  if (render) return render->image();
  if (state == JobState::done) {
    auto png = result_png(job);
    if (!png) return std::nullopt;
    std::string error;
    return decode_image(*png, &error);
  }
  return Image(job.width, job.height);  // not started: black
}

const Sample* Service::sample(const std::string& name) const {
  for (const Sample& s : samples_)
    if (s.name == name) return &s;
  return nullptr;
}

void Service::load_samples() {
  fs::path dir = settings_.samples_dir;
  std::error_code ec;
  if (dir.empty() || !fs::is_directory(dir, ec)) return;
  for (auto& e : fs::directory_iterator(dir, ec)) {
    auto ext = e.path().extension();
    if (ext != ".txt" && ext != ".json") continue;
    std::string name = e.path().stem().string();
    if (ext == ".json") name += ".json";
    std::string text = read_text(e.path());
    std::string description;
    std::istringstream lines(text);
    std::string line;
    while (std::getline(lines, line)) {
      size_t hash = line.find('#');
      if (hash == std::string::npos) continue;
      description = line.substr(hash + 1);
      while (!description.empty() && description.front() == ' ') description.erase(0, 1);
      break;
    }
    if (!load_scene(text).scene) continue;  // only scenes that render are offered
    samples_.push_back({name, description, e.path()});
  }
  std::sort(samples_.begin(), samples_.end(), [](auto& a, auto& b) { return a.name < b.name; });
}

bool Service::acquire_stream() {
  if (streams_.fetch_add(1) >= settings_.max_event_streams) {
    streams_.fetch_sub(1);
    return false;
  }
  return true;
}
void Service::release_stream() { streams_.fetch_sub(1); }
bool Service::acquire_waiter() {
  if (waiters_.fetch_add(1) >= settings_.max_waiting_requests) {
    waiters_.fetch_sub(1);
    return false;
  }
  return true;
}
void Service::release_waiter() { waiters_.fetch_sub(1); }

nlohmann::json Service::health() const {
  return {{"status", shutting_down_ ? "shutting_down" : "ok"},
          {"queue_depth", scheduler_->waiting()},
          {"running", scheduler_->active()},
          {"queue_capacity", settings_.queue_capacity},
          {"workers", scheduler_->workers()}};
}

std::string Service::metrics_text() const {
  Metrics::Gauges g;
  {
    std::lock_guard lock(mu_);
    for (auto& [id, j] : jobs_) {
      std::lock_guard jl(j->mu);
      ++g.jobs_by_state[std::string(to_string(j->state))];
    }
  }
  g.queue_depth = static_cast<long>(scheduler_->waiting());
  g.running = static_cast<long>(scheduler_->active());
  g.workers = scheduler_->workers();
  g.event_streams = streams_.load();
  g.waiting_requests = waiters_.load();
  g.cache_bytes = static_cast<long>(cache_.bytes());
  return metrics_.render_text(g);
}

void Service::shutdown() {
  if (shutting_down_.exchange(true)) return;
  scheduler_->drain(std::chrono::milliseconds(static_cast<long>(settings_.shutdown_grace * 1000)));
  scheduler_->stop();
  stopped_ = true;
  std::vector<std::shared_ptr<Job>> jobs;
  {
    std::lock_guard lock(mu_);
    for (auto& [id, j] : jobs_) jobs.push_back(j);
  }
  // Waiting requests and event streams wake up and see stopped().
  for (auto& j : jobs) {
    { std::lock_guard jl(j->mu); }
    j->changed.notify_all();
  }
}

void Service::expire() {
  const long long cutoff = now_ms() - static_cast<long long>(settings_.result_ttl * 1000);
  std::vector<std::shared_ptr<Job>> old;
  {
    std::lock_guard lock(mu_);
    for (auto it = jobs_.begin(); it != jobs_.end();) {
      bool expired;
      {
        std::lock_guard jl(it->second->mu);
        expired = is_final(it->second->state) && it->second->finished_ms < cutoff;
      }
      if (expired) {
        old.push_back(it->second);
        it = jobs_.erase(it);
      } else {
        ++it;
      }
    }
  }
  std::set<std::string> referenced;
  {
    std::lock_guard lock(mu_);
    for (auto& [id, j] : jobs_) referenced.insert(j->image_name);
  }
  for (auto& j : old) {
    store_.remove_job(j->id);
    if (!referenced.count(j->image_name)) {
      store_.remove_image(j->image_name);
      cache_.erase(j->image_name);
    }
  }
  // Over the size budget: the oldest images go, and the jobs that pointed at them.
  auto images = store_.images_oldest_first();
  std::uintmax_t total = 0;
  for (auto& [name, size] : images) total += size;
  for (auto& [name, size] : images) {
    if (total <= settings_.results_max_bytes) break;
    store_.remove_image(name);
    cache_.erase(name);
    total -= size;
  }
}

void Service::restore() {
  if (!store_.enabled()) return;
  auto stored = store_.load_jobs();
  std::sort(stored.begin(), stored.end(), [](auto& a, auto& b) {
    return a.record.value("created_ms", 0LL) < b.record.value("created_ms", 0LL);
  });
  constexpr int kMaxAttempts = 3;
  for (auto& s : stored) {
    const nlohmann::json& r = s.record;
    auto job = std::make_shared<Job>();
    job->id = r.value("id", "");
    if (job->id.size() != 32) continue;
    job->client = r.value("client", "");
    job->created_ms = r.value("created_ms", 0LL);
    job->started_ms = r.value("started_ms", 0LL);
    job->finished_ms = r.value("finished_ms", 0LL);
    job->attempts = r.value("attempts", 0);
    job->cache_key = r.value("cache_key", "");
    job->image_name = r.value("image_name", job->id);
    job->error = r.value("error", "");
    job->error_code = r.value("error_code", "");
    job->width = r.value("width", 0);
    job->height = r.value("height", 0);
    job->scene_text = s.scene_text;
    if (r.contains("options") && r["options"].is_object())
      for (auto& [k, v] : r["options"].items())
        if (v.is_string() && !(k == "width" && v == "0") && !(k == "height" && v == "0") &&
            !(k == "camera" && v == ""))
          apply_option(job->options, k, v.get<std::string>());
    if (r.contains("stats") && r["stats"].is_object()) {
      const auto& st = r["stats"];
      job->stats.primary_rays = st.value("primary", 0ULL);
      job->stats.shadow_rays = st.value("shadow", 0ULL);
      job->stats.reflection_rays = st.value("reflection", 0ULL);
      job->stats.render_ms = st.value("render_ms", 0.0);
      job->stats.spp_done = st.value("spp_done", 0);
      job->stats.error_estimate = st.value("error_estimate", -1.0);
      if (st.contains("parts") && st["parts"].is_array())
        for (auto& p : st["parts"])
          if (p.is_string()) job->stats.parts.push_back(p.get<std::string>());
    }
    auto state = job_state_from(r.value("state", "")).value_or(JobState::failed);
    bool rerun = false;
    if (state == JobState::done) {
      if (!store_.has_image(job->image_name)) {  // its image expired
        store_.remove_job(job->id);
        continue;
      }
      job->stats.finished = true;
      job->stats.spp_target = job->stats.spp_done;
    } else if (!is_final(state)) {
      if (job->attempts >= kMaxAttempts) {
        state = JobState::failed;
        job->error_code = "render_crashed";
        job->error = "the renderer stopped during this job " + std::to_string(job->attempts) +
                     " times; it will not be retried";
        job->finished_ms = now_ms();
      } else {
        LoadedScene loaded = load_scene(job->scene_text);
        if (loaded.scene) {
          job->scene = std::make_shared<const Scene>(std::move(*loaded.scene));
          state = JobState::queued;
          rerun = true;
        } else {
          state = JobState::failed;
          job->error_code = "lost";
          job->error = "the job's scene could not be read back after a restart";
        }
      }
    }
    job->state = state;
    {
      std::lock_guard lock(mu_);
      job->sequence = ++sequence_;
      jobs_[job->id] = job;
    }
    if (!rerun && state == JobState::failed) persist(*job);
    if (rerun) scheduler_->submit(job);
  }
}

}  // namespace rayfarm::server
