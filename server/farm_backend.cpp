// The farm side of Service (farm_backend.h): job records, submissions, cancels and images in
// Redis through the rayfarm1 Functions, and this node's FarmNode rendering units.
#include "farm_backend.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "farm_node.h"
#include "rayfarm/render.h"
#include "rayfarm/sha256.h"

namespace rayfarm::server {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

long long number(const farm::JobFields& f, const char* name) {
  auto it = f.find(name);
  if (it == f.end() || it->second.empty()) return 0;
  char* end = nullptr;
  const long long v = std::strtoll(it->second.c_str(), &end, 10);
  return end && *end == '\0' ? v : 0;
}

std::string text(const farm::JobFields& f, const char* name) {
  auto it = f.find(name);
  return it == f.end() ? std::string() : it->second;
}

// A job's state in the farm (queued, running, assembling, done, failed, canceled) as the
// service's; assembling is the end of running.
std::pair<JobState, int> state_of(const std::string& s) {
  if (s == "running") return {JobState::running, 1};
  if (s == "assembling") return {JobState::running, 2};
  if (s == "done") return {JobState::done, 3};
  if (s == "failed") return {JobState::failed, 4};
  if (s == "canceled") return {JobState::canceled, 5};
  return {JobState::queued, 0};
}

std::string label_value(const std::string& v) {
  std::string out;
  for (char c : v) {
    if (c == '\\' || c == '"') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out;
}

std::string default_node_id(const Settings& s) {
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0) std::snprintf(host, sizeof host, "%s", s.host.c_str());
  const auto start = std::chrono::duration_cast<milliseconds>(
                         std::chrono::system_clock::now().time_since_epoch())
                         .count();
  return std::string(host) + ":" + std::to_string(s.port) + ":" + std::to_string(getpid()) + ":" +
         std::to_string(start);
}

ApiError unavailable(const std::string& why) {
  ApiError e = api_error(503, "redis_unavailable", "the farm's Redis is unavailable: " + why);
  e.retry_after = 2;
  return e;
}

}  // namespace

struct FarmBackend::Impl {
  Settings settings;
  farm::FarmConfig config;
  std::shared_ptr<farm::FarmSetup> setup;
  std::unique_ptr<farm::Pool> pool;
  // Progress of this node's local renders not yet written to the farm (by the heartbeat),
  // per mille; the last value written, so that only changes go. Before the node, whose
  // heartbeat reads them: they outlive it.
  std::mutex progress_mu;
  std::map<std::string, int> progress_new, progress_sent;
  std::set<std::string> progress_live;  // local jobs accepted here and not yet ended
  std::unique_ptr<farm::FarmNode> node;
  std::string url;
  std::atomic<std::uint64_t> calls{0}, micros{0};

  // Runs `f` with a farm client over a pooled connection; throws Unavailable when there is
  // none, or when the result is an error.
  template <class F>
  auto call(F&& f) {
    auto lease = pool->acquire(milliseconds(2000));
    if (!lease) throw Unavailable(lease.error().message);
    farm::Connection& c = **lease;
    // A pooled connection Redis closed while it was idle is opened again now, not found
    // broken by the request (a 503 and a reconnect delay with Redis up all along).
    if (c.connected() && c.closed_by_peer()) {
      c.disconnect();
      if (auto st = c.connect(); !st) throw Unavailable(st.error().message);
    }
    if (!c.connected())
      if (auto st = c.ensure_connected(); !st) throw Unavailable(st.error().message);
    farm::FarmClient fc(c, config);
    const auto t0 = Clock::now();
    auto r = f(fc);
    calls += 1;
    micros += std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - t0).count();
    if (!r) {
      const farm::Error& e = r.error();
      throw Unavailable(e.kind == farm::ErrorKind::Oom ? "Redis is out of memory"
                                                       : std::string(farm::to_string(e.kind)) +
                                                             ": " + e.message);
    }
    return std::move(*r);
  }

  JobRecord record(const std::string& id, const farm::JobFields& f) const {
    JobRecord r;
    r.id = id;
    r.client = text(f, "client");
    auto [state, rank] = state_of(text(f, "state"));
    r.state = state;
    r.created_ms = number(f, "created_ms");
    r.started_ms = number(f, "started_ms");
    r.finished_ms = number(f, "finished_ms");
    r.options.priority = static_cast<Priority>(std::clamp<long long>(number(f, "prio"), 0, 2));
    std::string why;
    if (auto job = farm::FarmJob::from_json(text(f, "opts"), &why)) {
      for (const auto& [name, value] : job->options) (void)apply_option(r.options, name, value);
      r.width = job->width;
      r.height = job->height;
      r.image_name = job->result;
    }
    r.options.priority = static_cast<Priority>(std::clamp<long long>(number(f, "prio"), 0, 2));
    if (!text(f, "result").empty()) r.image_name = text(f, "result");
    r.cache_key = r.image_name == id ? "" : r.image_name;
    r.cache_hit = text(f, "cache") == "hit";
    r.request_digest = text(f, "digest");
    if (const std::string w = text(f, "warnings"); !w.empty())
      r.warnings = warnings_from_json(nlohmann::json::parse(w, nullptr, false));
    r.error = text(f, "error");
    if (!r.error.empty()) r.error_code = text(f, "code").empty() ? "render_failed" : text(f, "code");
    long long units = std::max(1LL, number(f, "units")), done = number(f, "done");
    long long seen = done;  // for the version, which only grows
    if (text(f, "local") == "1") {
      // Rendered by its node alone, which writes how far it has got with its heartbeats.
      if (state == JobState::running) {
        units = 1000;
        done = seen = std::clamp(number(f, "permille"), 0LL, 999LL);
      } else if (is_final(state)) {
        seen = 1000;
      }
    }
    RenderStats& st = r.stats;
    st.spp_target = 1;
    st.tiles_per_pass = static_cast<int>(units);
    st.tiles_done = static_cast<int>(std::min(done, units));
    st.primary_rays = static_cast<std::uint64_t>(number(f, "primary_rays"));
    st.shadow_rays = static_cast<std::uint64_t>(number(f, "shadow_rays"));
    st.reflection_rays = static_cast<std::uint64_t>(number(f, "reflection_rays"));
    if (state == JobState::done) {
      st.finished = true;
      st.spp_target = st.spp_done = r.options.spp;
      st.stop_reason = "spp";
      if (!text(f, "error_estimate").empty()) st.error_estimate = std::atof(text(f, "error_estimate").c_str());
      if (r.finished_ms > r.started_ms && r.started_ms > 0)
        st.render_ms = static_cast<double>(r.finished_ms - r.started_ms);
    }
    // Grows with every unit done and every change of state: what watchers compare.
    r.version = 1 + static_cast<std::uint64_t>(seen) * 8 + static_cast<std::uint64_t>(rank);
    return r;
  }

  std::optional<JobRecord> get(const std::string& id) {
    auto fields = call([&](farm::FarmClient& fc) { return fc.job(id); });
    if (!fields || fields->empty()) return std::nullopt;
    return record(id, *fields);
  }
};

FarmBackend::FarmBackend(const Settings& s, int workers,
                         std::function<void(const std::string&)> on_cancel)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.settings = s;
  auto url = farm::parse_redis_url(s.redis);
  if (!url) throw std::runtime_error("--redis: " + url.error().message);
  std::optional<std::string> file;
  if (!s.redis_password_file.empty()) file = s.redis_password_file;
  auto password = farm::load_redis_password(file, std::getenv("RAYFARM_REDIS_PASSWORD"));
  if (!password) throw std::runtime_error(password.error().message);
  m.url = url->to_string();
  farm::ConnectOptions base;
  base.url = *url;
  base.password = *password;
  base.command_timeout = milliseconds(std::max(2000, 2 * s.lease_ms));
  m.config.prefix = s.redis_prefix;
  m.config.node = s.node_id.empty() ? default_node_id(s) : s.node_id;
  // The render version (the images) and the Function library (the farm's protocol): nodes
  // that differ in either would disagree, so they refuse each other.
  m.config.build = "rayfarmd render " + std::to_string(kRenderVersion) + ", farm library " +
                   sha256_hex(farm::function_library()).substr(0, 12);
  m.config.feed_target = std::max(8, 2 * workers);
  m.config.block = milliseconds(std::clamp(s.heartbeat_ms, 50, 1000));
  m.setup = std::make_shared<farm::FarmSetup>(m.config);
  // The requests' connections wait 2 s at most: a frozen Redis (stopped, swapping) answers
  // a health check or a submission 503 in that time, not in the workers' 20.
  farm::ConnectOptions requests = base;
  requests.command_timeout = milliseconds(2000);
  m.pool = std::make_unique<farm::Pool>(farm::farm_connect_options(requests, m.setup), 16);
  // A password Redis refuses, an ACL user short of rights or a database it lacks are
  // settings to fix, not an outage to wait out: the start stops with Redis's words. Redis
  // down, or a farm of another build (an upgrade under way), is waited out.
  {
    farm::Connection probe(farm::farm_connect_options(requests, m.setup));
    if (auto st = probe.connect(); !st) {
      const farm::Error& e = st.error();
      if (e.kind == farm::ErrorKind::Auth)
        throw std::runtime_error("--redis " + m.url + " refused this node's credentials: " +
                                 e.message +
                                 " (the password comes from --redis-password-file or "
                                 "RAYFARM_REDIS_PASSWORD; none is sent when neither is set)");
      if (e.kind == farm::ErrorKind::NoPerm || e.kind == farm::ErrorKind::Config)
        throw std::runtime_error("--redis " + m.url + ": " + e.message);
    } else if (!s.node_id.empty()) {
      // Two nodes under one name would renew and take each other's leases. (A default name
      // holds the process's number and start: no other node has it.)
      farm::FarmClient fc(probe, m.config);
      const auto running = fc.node_running();
      if (running && *running)
        throw std::runtime_error("--node-id " + s.node_id +
                                 ": a running node of this farm has that name (its record " +
                                 fc.key("node:" + s.node_id) +
                                 " was renewed while this one waited): give each node a name "
                                 "of its own");
      if (!running)
        std::fprintf(stderr,
                     "rayfarmd: warning: whether a running node is named %s was not found out "
                     "(%s); this one starts\n",
                     s.node_id.c_str(), running.error().message.c_str());
    }
  }
  farm::NodeConfig nc;
  nc.connect = base;
  nc.farm = m.config;
  nc.workers = workers;
  nc.heartbeat = milliseconds(s.heartbeat_ms);
  nc.lease = milliseconds(s.lease_ms);
  nc.cancel_poll = milliseconds(s.heartbeat_ms);  // a backstop: cancels come as messages
  nc.result_ttl = milliseconds(static_cast<long long>(s.result_ttl * 1000));
  nc.on_cancel = std::move(on_cancel);
  nc.local_progress = [&m] {
    std::lock_guard lock(m.progress_mu);
    std::vector<std::pair<std::string, int>> changed(m.progress_new.begin(), m.progress_new.end());
    for (const auto& [job, permille] : changed) m.progress_sent[job] = permille;
    m.progress_new.clear();
    return changed;
  };
  m.node = std::make_unique<farm::FarmNode>(nc);
  m.node->start();
}

FarmBackend::~FarmBackend() { stop(); }

void FarmBackend::stop() {
  if (impl_->node) impl_->node->stop();
}

const std::string& FarmBackend::node() const { return impl_->config.node; }

FarmBackend::Outcome FarmBackend::submit(JobRecord job, const std::string& scene_text,
                                         int max_jobs_of_client, bool local) {
  Impl& m = *impl_;
  RenderOptions options = job.options;
  options.width = job.width;
  options.height = job.height;
  const std::string result_key = job.cache_key.empty() ? job.id : job.cache_key;
  const auto ttl = milliseconds(static_cast<long long>(m.settings.result_ttl * 1000));
  try {
    // Rendered already by some node, and still kept: answered from it, recorded as done so
    // that every node can answer for the job. (With an Idempotency-Key the farm's submit
    // decides, so a repeated key gives the first job.)
    if (!job.cache_key.empty() && job.idempotency_key.empty()) {
      const bool kept = m.call([&](farm::FarmClient& fc) -> farm::Result<bool> {
        auto r = fc.connection().command({"EXISTS", fc.key("png:" + result_key)});
        if (!r) return r.error();
        return r->integer() == 1;
      });
      if (kept) {
        farm::FarmJob f;
        f.scene = sha256_hex(scene_text);
        f.options = option_pairs(options);
        f.width = job.width;
        f.height = job.height;
        f.tiles_per_unit = tile_count(job.width, job.height);
        f.units = 1;
        f.result = result_key;
        farm::RecordRequest rr;
        rr.job = job.id;
        rr.client = job.client;
        rr.priority = static_cast<farm::Priority>(static_cast<int>(job.options.priority));
        rr.state = farm::EndState::Done;
        rr.result = result_key;
        rr.ttl = ttl;
        rr.fields = {{"opts", f.to_json()}, {"cache", "hit"}};
        m.call([&](farm::FarmClient& fc) { return fc.record(rr); });
        return {m.get(job.id), {}, false};
      }
    }
    farm::FarmSubmission s;
    s.job = job.id;
    s.client = job.client;
    s.priority = static_cast<farm::Priority>(static_cast<int>(job.options.priority));
    s.scene_text = scene_text;
    s.options = options;
    s.result_key = result_key;
    s.unit_work = m.settings.unit_work;
    s.idempotency_key = job.idempotency_key;
    s.local = local;
    if (local) s.fields.emplace_back("node", m.config.node);
    if (!job.request_digest.empty()) s.fields.emplace_back("digest", job.request_digest);
    if (!job.warnings.empty()) s.fields.emplace_back("warnings", json_text(warnings_json(job.warnings)));
    s.max_active_per_client = max_jobs_of_client;
    s.max_jobs = m.settings.queue_capacity;
    s.ttl = ttl;
    // A local job is timed by its node's scheduler, by its own render time; units spread over
    // the farm by the clock from the job's start, with this node's limit.
    if (!local && m.settings.job_timeout > 0)
      s.timeout = milliseconds(std::max(1LL, std::llround(m.settings.job_timeout * 1000)));
    const farm::SubmitResult r =
        m.call([&](farm::FarmClient& fc) { return farm::submit_job(fc, s); });
    switch (r.status) {
      case farm::SubmitStatus::Accepted: {
        if (local) {
          std::lock_guard lock(m.progress_mu);
          m.progress_live.insert(job.id);
          return {job, {}, false, true};
        }
        auto rec = m.get(job.id);
        if (!rec) return {std::nullopt, unavailable("the job vanished after submission")};
        return {rec, {}, false};
      }
      case farm::SubmitStatus::Exists: {
        auto rec = m.get(r.job.empty() ? job.id : r.job);
        if (!rec) return {std::nullopt, unavailable("the job of this Idempotency-Key expired")};
        if (!job.idempotency_key.empty() && rec->request_digest != job.request_digest)
          return {std::nullopt,
                  api_error(422, "idempotency_key_reused",
                            "this Idempotency-Key was used for another request (job " +
                                rec->id + "): the scene, options or textures differ; use a new "
                                "key for a new request")};
        return {rec, {}, true};
      }
      case farm::SubmitStatus::ClientLimit: {
        ApiError e = api_error(429, "too_many_jobs",
                               "you have " + std::to_string(max_jobs_of_client) +
                                   " jobs queued or running on the farm; wait for some to finish");
        e.retry_after = 2;
        return {std::nullopt, e};
      }
      case farm::SubmitStatus::Full: {
        ApiError e = api_error(429, "queue_full",
                               "the farm's queue is full (" +
                                   std::to_string(m.settings.queue_capacity) +
                                   " jobs); try again later");
        e.retry_after = 2;
        return {std::nullopt, e};
      }
    }
    return {std::nullopt, unavailable("an unknown answer")};
  } catch (const Unavailable& e) {
    return {std::nullopt, unavailable(e.what())};
  }
}

bool FarmBackend::finish_local(const JobRecord& job, JobState state, const std::string& code,
                               const std::string& error, const std::string* png,
                               const RenderStats& st, int attempts) {
  Impl& m = *impl_;
  {
    std::lock_guard lock(m.progress_mu);
    m.progress_new.erase(job.id);
    m.progress_sent.erase(job.id);
    m.progress_live.erase(job.id);
  }
  const auto ttl = milliseconds(static_cast<long long>(m.settings.result_ttl * 1000));
  farm::RecordRequest rr;
  rr.job = job.id;
  rr.client = job.client;
  rr.priority = static_cast<farm::Priority>(static_cast<int>(job.options.priority));
  rr.state = state == JobState::done     ? farm::EndState::Done
             : state == JobState::failed ? farm::EndState::Failed
                                         : farm::EndState::Canceled;
  rr.ttl = ttl;
  if (state == JobState::done) rr.result = job.image_name;
  rr.error = error;
  if (!code.empty()) rr.fields.emplace_back("code", code);
  rr.fields.emplace_back("primary_rays", std::to_string(st.primary_rays));
  rr.fields.emplace_back("shadow_rays", std::to_string(st.shadow_rays));
  rr.fields.emplace_back("reflection_rays", std::to_string(st.reflection_rays));
  rr.fields.emplace_back("error_estimate", format_number(st.error_estimate));
  // A render thread waits out a short outage here; a long one is the job limit's to end.
  for (int attempt = 0; attempt < attempts; ++attempt) {
    if (attempt > 0) std::this_thread::sleep_for(milliseconds(200 << attempt));
    try {
      if (png)
        m.call([&](farm::FarmClient& fc) {
          return fc.connection().command({"SET", fc.key("png:" + job.image_name), *png, "PX",
                                          std::to_string(ttl.count())});
        });
      m.call([&](farm::FarmClient& fc) { return fc.record(rr); });
      return true;
    } catch (const Unavailable& e) {
      std::fprintf(stderr, "rayfarmd: cannot record job %s in the farm yet: %s\n",
                   job.id.c_str(), e.what());
    }
  }
  return false;
}

std::optional<JobRecord> FarmBackend::get(const std::string& id) { return impl_->get(id); }

std::vector<JobRecord> FarmBackend::list(const std::string& client, size_t limit) {
  Impl& m = *impl_;
  std::vector<std::string> ids = m.call([&](farm::FarmClient& fc) -> farm::Result<std::vector<std::string>> {
    auto r = fc.connection().command(
        {"ZREVRANGE", fc.key("cjobs:" + client), "0", std::to_string(std::max<size_t>(limit, 1) - 1)});
    if (!r) return r.error();
    std::vector<std::string> out;
    for (std::size_t i = 0; i < r->size(); ++i)
      if (auto id = (*r)[i].string()) out.emplace_back(*id);
    return out;
  });
  std::vector<JobRecord> jobs;
  std::vector<std::string> gone;
  for (const std::string& id : ids) {
    auto rec = m.get(id);
    if (!rec) gone.push_back(id);  // expired: its ID leaves the client's list
    else if (rec->client == client) jobs.push_back(*rec);
  }
  if (!gone.empty()) {
    try {  // tidying only: the list is answered whether or not it is done
      m.call([&](farm::FarmClient& fc) -> farm::Result<bool> {
        const std::string key = fc.key("cjobs:" + client);
        std::vector<std::string_view> zrem{"ZREM", key};
        zrem.insert(zrem.end(), gone.begin(), gone.end());
        if (auto r = fc.connection().command(zrem); !r) return r.error();
        return true;
      });
    } catch (const Unavailable&) {
    }
  }
  return jobs;
}

ApiError FarmBackend::cancel(const std::string& id, const std::string& client) {
  auto r = impl_->call([&](farm::FarmClient& fc) { return fc.cancel(id, client); });
  switch (r.status) {
    case farm::CancelStatus::Canceled:
      return {};
    case farm::CancelStatus::NotFound:
      return api_error(404, "not_found", "no job " + id);
    case farm::CancelStatus::Forbidden:
      return api_error(403, "forbidden", "only the client that submitted a job can cancel it");
    case farm::CancelStatus::AlreadyEnded:
      if (r.state == "canceled") return {};
      return api_error(409, "already_finished",
                       "the job has already " +
                           std::string(r.state == "done" ? "finished" : "failed"));
  }
  return {};
}

int FarmBackend::queue_position(const std::string& id) {
  return impl_->call([&](farm::FarmClient& fc) -> farm::Result<int> {
    auto r = fc.connection().command({"ZRANK", fc.key("queued"), id});
    if (!r) return r.error();
    return r->is_nil() ? 0 : static_cast<int>(r->integer()) + 1;
  });
}

std::shared_ptr<const std::string> FarmBackend::png(const std::string& key) {
  auto bytes = impl_->call([&](farm::FarmClient& fc) { return farm::job_png(fc, key); });
  if (!bytes) return nullptr;
  return std::make_shared<const std::string>(std::move(*bytes));
}

void FarmBackend::local_progress(const std::string& id, double fraction) {
  Impl& m = *impl_;
  const int permille = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * 1000);
  std::lock_guard lock(m.progress_mu);
  // Not after its end (a tile of another thread can report after it), and never backwards
  // (threads' reports can cross): what the other nodes show only grows, as its version must.
  if (!m.progress_live.count(id)) return;
  if (auto it = m.progress_sent.find(id); it != m.progress_sent.end() && it->second >= permille)
    return;
  if (auto it = m.progress_new.find(id); it != m.progress_new.end() && it->second >= permille)
    return;
  m.progress_new[id] = permille;
}

bool FarmBackend::healthy(nlohmann::json& details) {
  Impl& m = *impl_;
  details = {{"url", m.url}, {"node", m.config.node}, {"units_in_flight", m.node->in_flight()}};
  try {
    // A write, not a PING: a Redis out of memory answers PING and refuses every job.
    m.call([&](farm::FarmClient& fc) {
      const std::string key = fc.key("health:" + m.config.node);
      return fc.connection().command({"SET", key, "1", "PX", "5000"});
    });
    details["status"] = "ok";
  } catch (const Unavailable& e) {
    details["status"] = "unreachable";
    details["error"] = e.what();
    return false;
  }
  try {  // The farm's own figures (its jobs are in no node's queue); left out if unread.
    const farm::FarmCounts n = m.call([&](farm::FarmClient& fc) { return fc.counts(); });
    details["farm"] = {{"queued", n.queued}, {"running", n.running},
                       {"assembling", n.assembling}, {"nodes", n.nodes}};
  } catch (const Unavailable&) {
  }
  return true;
}

std::string FarmBackend::metrics_text() const {
  Impl& m = *impl_;
  const farm::NodeCounters& c = m.node->counters();
  std::string out;
  auto counter = [&](const char* name, const char* help, double v, const char* type = "counter") {
    out += std::string("# HELP ") + name + " " + help + "\n# TYPE " + name + " " + type + "\n" +
           name + " " + (v == std::floor(v) && std::fabs(v) < 1e15 ? std::to_string(std::llround(v))
                                                                    : std::to_string(v)) +
           "\n";
  };
  out += "# HELP rayfarm_node_info This farm node.\n# TYPE rayfarm_node_info gauge\n";
  out += "rayfarm_node_info{node=\"" + label_value(m.config.node) + "\"} 1\n";
  counter("rayfarm_units_rendered_total", "Units of farm jobs this node rendered.",
          static_cast<double>(c.units_rendered));
  counter("rayfarm_units_reclaimed_total", "Units of dead or stalled nodes this node requeued.",
          static_cast<double>(c.units_reclaimed));
  counter("rayfarm_units_stopped_total", "Units this node stopped (canceled or lease lost).",
          static_cast<double>(c.units_stopped));
  counter("rayfarm_units_failed_total", "Units this node could not render.",
          static_cast<double>(c.units_failed));
  counter("rayfarm_jobs_assembled_total", "Farm jobs whose image this node put together.",
          static_cast<double>(c.jobs_assembled));
  counter("rayfarm_units_in_flight", "Units this node renders now.",
          static_cast<double>(m.node->in_flight()), "gauge");
  counter("rayfarm_farm_jobs_timed_out_total",
          "Farm jobs this node's janitor failed for running past their limit.",
          static_cast<double>(c.jobs_timed_out));
  counter("rayfarm_farm_jobs_orphaned_total",
          "Farm jobs this node's janitor failed because their rendering node was gone.",
          static_cast<double>(c.jobs_orphaned));
  counter("rayfarm_farm_jobs_reassembled_total",
          "Farm jobs this node's janitor put together for an assembler that was gone.",
          static_cast<double>(c.jobs_reassembled));
  // Farm-wide, from Redis: the jobs spread over the nodes are in no node's own queue. Left out
  // (and rayfarm_farm_up 0) while Redis cannot be reached.
  std::optional<farm::FarmCounts> n;
  try {
    n = m.call([&](farm::FarmClient& fc) { return fc.counts(); });
  } catch (const Unavailable&) {
  }
  counter("rayfarm_farm_up", "1 when this node reached Redis for these figures.", n ? 1.0 : 0.0,
          "gauge");
  if (n) {
    out += "# HELP rayfarm_farm_jobs Jobs of the whole farm by state.\n"
           "# TYPE rayfarm_farm_jobs gauge\n";
    out += "rayfarm_farm_jobs{state=\"queued\"} " + std::to_string(n->queued) + "\n";
    out += "rayfarm_farm_jobs{state=\"running\"} " + std::to_string(n->running) + "\n";
    out += "rayfarm_farm_jobs{state=\"assembling\"} " + std::to_string(n->assembling) + "\n";
    counter("rayfarm_farm_nodes", "Farm nodes whose heartbeat is current.",
            static_cast<double>(n->nodes), "gauge");
  }
  const double calls = static_cast<double>(c.redis_calls + m.calls);
  const double secs = static_cast<double>(c.redis_micros + m.micros) / 1e6;
  out += "# HELP rayfarm_redis_round_trip_seconds Round trips to Redis (workers and requests).\n"
         "# TYPE rayfarm_redis_round_trip_seconds summary\n";
  out += "rayfarm_redis_round_trip_seconds_sum " + std::to_string(secs) + "\n";
  out += "rayfarm_redis_round_trip_seconds_count " + std::to_string(static_cast<std::uint64_t>(calls)) + "\n";
  return out;
}

}  // namespace rayfarm::server
