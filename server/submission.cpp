// Accepting a job: the per-client and queue limits, the scene and its options checked, the
// render limits, the content-addressed cache, and the job on disk before it is queued.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include "rayfarm/content_key.h"
#include "rayfarm/lint.h"
#include "rayfarm/load.h"
#include "rayfarm/sha256.h"
#include "rayfarm/writers.h"
#include "service.h"

namespace rayfarm::server {
namespace {

// 31948800000 as "31,948,800,000".
std::string grouped(double v) {
  std::string digits = std::to_string(static_cast<long long>(std::llround(v)));
  std::string out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

}  // namespace

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

// What identifies a request for its Idempotency-Key: the scene, the options as given and the
// textures' bytes (not how the answer is awaited).
std::string request_digest(const std::string& scene_text, const Params& params,
                           const TextureFiles& textures) {
  std::string all = sha256_hex(scene_text);
  Params sorted = params;
  std::sort(sorted.begin(), sorted.end());
  for (const auto& [k, v] : sorted) all += "\n" + sha256_hex(k) + "=" + sha256_hex(v);
  for (const auto& [path, bytes] : textures) all += "\n" + sha256_hex(path) + ":" + sha256_hex(bytes);
  return sha256_hex(all);
}

}  // namespace

Submitted Service::submit(const std::string& scene_text, const Params& params,
                          const std::string& client, const TextureFiles& textures,
                          const SubmitHow& how) {
  if (shutting_down_) {
    ApiError e = api_error(503, "shutting_down", "the server is shutting down; try again shortly");
    e.retry_after = 5;
    return {std::nullopt, e};
  }
  if (how.idempotency_key.empty()) return submit_new(scene_text, params, client, textures, how, "");
  // The farm's submit keeps the keys farm-wide, with the digest in the job's record.
  if (farm_)
    return submit_new(scene_text, params, client, textures, how,
                      request_digest(scene_text, params, textures));
  // draft-ietf-httpapi-idempotency-key-header: the same key and request give the first
  // answer's job; the key with another request is 422; a retry while the first is still
  // being accepted is 409.
  const std::string digest = request_digest(scene_text, params, textures);
  const auto key = std::make_pair(client, how.idempotency_key);
  {
    std::lock_guard lock(mu_);
    if (!keys_in_flight_.insert(key).second) {
      ApiError e = api_error(409, "idempotency_key_in_use",
                             "a request with this Idempotency-Key is still being accepted; "
                             "retry in a moment");
      e.retry_after = 1;
      return {std::nullopt, e};
    }
  }
  struct Done {
    Service& s;
    const std::pair<std::string, std::string>& key;
    ~Done() {
      std::lock_guard lock(s.mu_);
      s.keys_in_flight_.erase(key);
    }
  } done{*this, key};
  if (auto earlier = jobs_->find_by_key(client, how.idempotency_key)) {
    if (earlier->request_digest != digest)
      return {std::nullopt,
              api_error(422, "idempotency_key_reused",
                        "this Idempotency-Key was used for another request (job " + earlier->id +
                            "): the scene, options or textures differ; use a new key for a new "
                            "request")};
    return {earlier, {}, true};
  }
  return submit_new(scene_text, params, client, textures, how, digest);
}

Submitted Service::submit_new(const std::string& scene_text, const Params& params,
                              const std::string& client, const TextureFiles& textures,
                              const SubmitHow& how, const std::string& digest) {
  // A farm counts both limits farm-wide, in its submit.
  // Jobs waiting for another's render count as the queued jobs they are to their clients.
  if (!farm_ && queue_->depth() + queue_->active() + followers_of(nullptr) >=
      static_cast<size_t>(settings_.queue_capacity)) {
    metrics_.rejected("queue_full");
    ApiError e = api_error(429, "queue_full",
                           "the render queue is full (" + std::to_string(settings_.queue_capacity) +
                               " jobs); try again later");
    e.retry_after = 2;
    return {std::nullopt, e};
  }
  if (!farm_) {
    // The pool holds exactly the unfinished jobs: counting there costs the client's own
    // jobs, not every job kept for reading back (thousands on a busy day).
    const auto mine = static_cast<long long>(queue_->jobs_of(client) + followers_of(&client));
    const int named_limit = roster_.max_jobs_of(client);  // a grader may have a larger quota
    if (mine >= (named_limit > 0 ? named_limit : settings_.max_jobs_per_client)) {
      metrics_.rejected("client_limit");
      ApiError e = api_error(
          429, "too_many_jobs",
          "you have " + std::to_string(mine) + " jobs queued or running; wait for some to finish");
      e.retry_after = 2;
      return {std::nullopt, e};
    }
  }

  if (ApiError e = check_uploads(textures)) {
    metrics_.rejected(e.limit);
    return {std::nullopt, e};
  }
  // Textures decode to far more than they upload (a 200 KB PNG to 48 MB at the pixel limit,
  // 16 of them to a request): a scene with any is read in turn, as a large text is.
  const LoadGate::Pass pass =
      enter_load(scene_text.size() + (textures.empty() ? 0 : LoadGate::kSmall + 1));
  LoadedScene loaded = load_scene(scene_text);
  if (!loaded.scene) return {std::nullopt, scene_error(loaded.diags)};
  if (ApiError e = resolve_uploads(*loaded.scene, textures)) {
    if (!e.limit.empty()) metrics_.rejected(e.limit);
    return {std::nullopt, e};
  }
  auto scene = std::make_shared<const Scene>(std::move(*loaded.scene));

  // Precedence: the query, the scene's render block, the server's default profile.
  RenderOptions options;
  options.profile = settings_.default_profile;
  Diagnostics diags;
  apply_options(options, scene->render, diags);
  OptionSet query;
  for (auto& [k, v] : params) query.push_back({k, v, {0, 0, k}});
  const auto names_priority = [](const OptionSet& set) {
    return std::any_of(set.begin(), set.end(), [](auto& o) { return o.name == "priority"; });
  };
  if (!names_priority(query) && !names_priority(scene->render))
    options.priority = how.default_priority;
  apply_options(options, query, diags);
  if (!diags.has_errors()) {
    std::string option;
    if (std::string conflict = profile_conflict(options, &option); !conflict.empty()) {
      // Placed where the option the profile refuses was given: the query's parameter, else
      // the scene's render block, else (the server's default profile) its name.
      Where at{0, 0, option};
      const auto given = [&option, &at](const OptionSet& set) {
        for (const auto& o : set)
          if (const OptionSpec* spec = find_option(o.name); spec && spec->name == option) {
            at = o.where;
            return true;
          }
        return false;
      };
      if (!given(query)) given(scene->render);
      diags.error("bad-option", conflict, at);
    }
  }
  if (diags.has_errors()) {
    const Diagnostic* d = diags.first_error();
    ApiError e = api_error(400, "invalid_option", d->message);
    e.line = d->where.line;
    e.column = d->where.column;
    e.path = d->where.path;
    return {std::nullopt, e};
  }
  auto camera = scene->find_camera(options.camera);
  if (!camera) {
    const std::string names = scene->camera_names();
    ApiError e = api_error(400, "invalid_option",
                           "no camera named '" + options.camera.substr(0, 64) + "'; the scene's cameras: " + names);
    e.path = "camera";
    return {std::nullopt, e};
  }
  const Camera& cam = scene->cameras[*camera];
  int width = options.width > 0 ? options.width : cam.width;
  int height = options.height > 0 ? options.height : cam.height;
  if (ApiError e = check_limits(*scene, options, width, height)) {
    metrics_.rejected(e.limit);
    return {std::nullopt, e};
  }

  JobRecord job;
  job.id = random_id();
  job.client = client;
  job.created_ms = now_ms();
  job.options = options;
  job.idempotency_key = how.idempotency_key;
  job.request_digest = digest;
  {
    Diagnostics lints;
    lint_scene(*scene, options, lints, /*every_camera=*/false);
    for (const Diagnostic& d : loaded.diags.items())
      if (d.severity == Severity::warning) job.warnings.push_back(d);
    for (const Diagnostic& d : lints.items()) job.warnings.push_back(d);
  }
  job.width = width;
  job.height = height;
  // A time limit makes the result depend on the machine's speed: never shared.
  const std::vector<std::string> hashes = texture_hashes(*scene, textures);
  if (options.time_limit == 0) job.cache_key = content_key(loaded.desc, options, hashes);
  job.image_name = job.cache_key.empty() ? job.id : job.cache_key;
  if (farm_) {
    // A small job is rendered here (spreading it costs more round trips than it saves), and so
    // is one with texture files: only this node has them. The farm still counts and lists it.
    const double work = static_cast<double>(width) * height * std::max(1, options.spp) *
                        (options.effective_max_depth() + 1.0);
    const bool local = !hashes.empty() || work <= settings_.distribute_work;
    const int named_limit = roster_.max_jobs_of(client);
    auto out = farm_->submit(job, scene_text,
                             named_limit > 0 ? named_limit : settings_.max_jobs_per_client, local);
    if (out.error.status == 429)
      metrics_.rejected(out.error.code == "queue_full" ? "queue_full" : "client_limit");
    if (out.job && out.job->cache_hit) metrics_.cache(true);
    if (!out.local) return {out.job, out.error, out.replayed};
    if (!job.cache_key.empty()) metrics_.cache(false);
  }

  bool hit;
  {
    // The image's reference is taken with the check, so expiry cannot delete an image this
    // job is about to be answered from. (A farm looked for the image in Redis already.)
    std::lock_guard lock(mu_);
    hit = !farm_ && !job.cache_key.empty() &&
          (cache_.get(job.cache_key) || blobs_.has(BlobKind::image, job.cache_key));
    ++image_refs_[job.image_name];
  }
  if (hit) {
    job.state = JobState::done;
    job.cache_hit = true;
    job.started_ms = job.finished_ms = job.created_ms;
    job.stats.finished = true;
    job.stats.spp_target = job.stats.spp_done = options.spp;
  } else {
    job.textures = hashes;  // the text and textures are kept for re-runs
  }
  if (hit && !farm_) metrics_.cache(true);
  try {
    if (!hit) keep_textures(job.textures, *scene, textures);
    job = jobs_->create(std::move(job), scene_text);
  } catch (const std::exception& ex) {
    if (!hit) release_textures(job.textures);
    release_image(job.image_name);
    ApiError e = api_error(503, "storage_error", std::string("cannot store the job: ") + ex.what());
    e.retry_after = 10;
    return {std::nullopt, e};
  }
  if (!hit) {
    auto run = std::make_shared<Job>();
    run->id = job.id;
    run->client = job.client;
    run->priority = job.options.priority;
    run->scene = scene;
    run->options = options;
    const Scheduled scheduled = schedule(std::move(run), job.cache_key);
    if (scheduled == Scheduled::waits)
      metrics_.merged();
    else if (!job.cache_key.empty() && !farm_)
      metrics_.cache(scheduled == Scheduled::answered);
  }
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
  const int depth = o.effective_max_depth();
  if (depth > s.max_depth)
    return limit_error("max_depth", "max_depth " + std::to_string(depth) +
                                        " is over the limit of " + std::to_string(s.max_depth));
  size_t objects = scene.objects.size();
  if (objects > static_cast<size_t>(s.max_objects))
    return limit_error("max_objects", "the scene has " + std::to_string(objects) +
                                          " objects; the limit is " + std::to_string(s.max_objects));
  double work = static_cast<double>(pixels) * o.spp * (depth + 1);
  if (work > s.max_work) {
    // What would fit: the most spp at this size and depth.
    const double fits = std::floor(s.max_work / (static_cast<double>(pixels) * (depth + 1)));
    return limit_error(
        "max_work", "the job asks for " + grouped(work) + " ray paths (" + std::to_string(pixels) +
                        " pixels x spp " + std::to_string(o.spp) + " x (max_depth " +
                        std::to_string(depth) + " + 1)); the limit is " + grouped(s.max_work) +
                        (fits >= 1 ? ": lower spp to " + grouped(fits) + " or less, or the size"
                                   : ": lower the size or max_depth"));
  }
  if (scene.lights.size() > static_cast<size_t>(s.max_lights))
    return limit_error("max_lights", "the scene has " + std::to_string(scene.lights.size()) +
                                         " lights; the limit is " + std::to_string(s.max_lights));
  return {};
}

}  // namespace rayfarm::server
