#include "farm_node.h"

#include <algorithm>
#include <cmath>
#include <exception>

#include <nlohmann/json.hpp>

#include "rayfarm/image_io.h"
#include "rayfarm/load.h"
#include "rayfarm/render_unit.h"
#include "rayfarm/sha256.h"

namespace rayfarm::farm {
namespace {

using Clock = std::chrono::steady_clock;
constexpr int kFormat = 1;  // of FarmJob's JSON
// Prepared jobs kept (a large scene's structures take tens of megabytes).
constexpr size_t kPreparedKept = 4;

std::string ms_text(std::chrono::milliseconds ms) { return std::to_string(ms.count()); }

}  // namespace

std::string FarmJob::to_json() const {
  nlohmann::json j = {{"v", kFormat},      {"scene", scene},
                      {"width", width},    {"height", height},
                      {"tiles_per_unit", tiles_per_unit},
                      {"units", units},    {"result", result}};
  nlohmann::json opts = nlohmann::json::array();
  for (const auto& [name, value] : options) opts.push_back({name, value});
  j["options"] = std::move(opts);
  return j.dump();
}

std::optional<FarmJob> FarmJob::from_json(std::string_view text, std::string* error) {
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    if (j.at("v").get<int>() != kFormat) {
      if (error) *error = "job description of another format (" + j.at("v").dump() + ")";
      return std::nullopt;
    }
    FarmJob f;
    f.scene = j.at("scene").get<std::string>();
    f.width = j.at("width").get<int>();
    f.height = j.at("height").get<int>();
    f.tiles_per_unit = j.at("tiles_per_unit").get<int>();
    f.units = j.at("units").get<int>();
    f.result = j.at("result").get<std::string>();
    for (const auto& p : j.at("options"))
      f.options.emplace_back(p.at(0).get<std::string>(), p.at(1).get<std::string>());
    const int tiles = tile_count(std::max(f.width, 1), std::max(f.height, 1));
    if (f.width < 1 || f.height < 1 || f.tiles_per_unit < 1 || f.units < 1 ||
        static_cast<long long>(f.units - 1) * f.tiles_per_unit >= tiles ||
        static_cast<long long>(f.units) * f.tiles_per_unit < tiles) {
      if (error) *error = "job description with units that do not cover its image";
      return std::nullopt;
    }
    return f;
  } catch (const std::exception& e) {
    if (error) *error = std::string("bad job description: ") + e.what();
    return std::nullopt;
  }
}

TileRange FarmJob::unit_range(int index) const {
  const int tiles = tile_count(width, height);
  return {index * tiles_per_unit, std::min((index + 1) * tiles_per_unit, tiles)};
}

Result<SubmitResult> submit_job(FarmClient& client, const FarmSubmission& s) {
  FarmJob f;
  f.scene = sha256_hex(s.scene_text);
  f.options = option_pairs(s.options);
  f.width = s.options.width;
  f.height = s.options.height;
  const double pixel_work = std::max(1, s.options.spp) * (s.options.effective_max_depth() + 1.0);
  const std::vector<TileRange> plan = plan_units(f.width, f.height, pixel_work, s.unit_work);
  f.tiles_per_unit = plan.front().count();
  f.units = static_cast<int>(plan.size());
  f.result = s.result_key;
  // The scene first, so no node can take a unit whose scene is not there yet; it lives as long
  // as a job that names it may still be rendered.
  if (!s.local) {
    const std::string key = client.key("scene:" + f.scene);
    const std::string ttl = ms_text(s.ttl + std::chrono::hours(24));
    auto stored = client.connection().command({"SET", key, s.scene_text, "PX", ttl});
    if (!stored) return stored.error();
  }
  SubmitRequest r;
  r.job = s.job;
  r.client = s.client;
  r.priority = s.priority;
  r.units = s.local ? 0 : f.units;
  r.fields = s.fields;
  r.opts = f.to_json();
  r.idempotency_key = s.idempotency_key;
  r.max_active_per_client = s.max_active_per_client;
  r.max_jobs = s.max_jobs;
  r.ttl = s.ttl;
  r.timeout = s.timeout;
  return client.submit(r);
}

Result<std::optional<std::string>> job_png(FarmClient& client, std::string_view result_key) {
  auto r = client.connection().command({"GET", client.key("png:" + std::string(result_key))});
  if (!r) return r.error();
  if (r->is_nil()) return std::optional<std::string>();
  return std::optional<std::string>(std::string(r->str()));
}

FarmNode::FarmNode(NodeConfig config)
    : config_(std::move(config)), setup_(std::make_shared<FarmSetup>(config_.farm)) {}

FarmNode::~FarmNode() { stop(); }

void FarmNode::start() {
  running_ = true;
  for (int i = 0; i < config_.workers; ++i) threads_.emplace_back([this, i] { work(i); });
  threads_.emplace_back([this] { keep_alive(); });
  threads_.emplace_back([this] { listen(); });
}

void FarmNode::stop() {
  running_ = false;
  for (auto& t : threads_)
    if (t.joinable()) t.join();
  threads_.clear();
}

void FarmNode::abandon() {
  abandoned_ = true;
  {
    std::lock_guard lock(mu_);
    for (auto& [entry, held] : held_) held.stop->store(true);
    for (auto& [entry, job] : rendering_) job->cancel();
  }
  stop();
}

void FarmNode::halt(const std::string& entry) {
  std::lock_guard lock(mu_);
  if (auto it = held_.find(entry); it != held_.end()) it->second.stop->store(true);
  if (auto it = rendering_.find(entry); it != rendering_.end()) it->second->cancel();
}

void FarmNode::halt_job(const std::string& job) {
  std::vector<std::string> entries;
  {
    std::lock_guard lock(mu_);
    for (const auto& [entry, held] : held_)
      if (held.job == job) entries.push_back(entry);
  }
  for (const std::string& entry : entries) halt(entry);
}

void FarmNode::listen() {
  Connection connection(farm_connect_options(config_.connect, setup_));
  const std::string channel = config_.farm.prefix + "cancel";
  bool subscribed = false;
  while (running_ && !abandoned_) {
    if (!subscribed) {
      if (!connection.wait_connected(std::chrono::milliseconds(200))) continue;
      subscribed = static_cast<bool>(connection.command({"SUBSCRIBE", channel}));
      if (subscribed) listening_ = true;
      continue;  // (a cancel published meanwhile is the keep-alive poll's)
    }
    auto message = connection.next_message(std::chrono::milliseconds(200));
    if (!message) {
      subscribed = false;  // the connection is gone: reconnect with its backoff
      continue;
    }
    // ["message", channel, job]
    if (*message && (*message)->size() == 3 && (**message)[0].str() == "message") {
      const std::string job((**message)[2].str());
      halt_job(job);
      if (config_.on_cancel) config_.on_cancel(job);
    }
  }
}

size_t FarmNode::in_flight() const {
  std::lock_guard lock(mu_);
  return held_.size();
}

void FarmNode::work(int index) {
  Connection connection(farm_connect_options(config_.connect, setup_));
  FarmConfig fc_config = config_.farm;
  FarmClient fc(connection, fc_config);
  (void)index;
  // No unit before the node hears cancels: one taken earlier could miss its job's.
  while (running_ && !abandoned_ && !listening_)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  while (running_) {
    if (!connection.connected() && !connection.wait_connected(std::chrono::milliseconds(200)))
      continue;
    const auto t0 = Clock::now();
    auto unit = fc.take();
    counters_.redis_calls += 1;
    counters_.redis_micros += std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - t0).count();
    // Then a wait for work, which is no round trip's time (an idle node's mean was 0.9 s).
    if (unit && !*unit) unit = fc.block_for_work();
    if (!unit) {  // Redis refused (full, busy) or the connection broke: do not hammer it
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      continue;
    }
    if (!*unit) continue;
    const Unit u = **unit;
    auto stop = std::make_shared<std::atomic<bool>>(false);
    {
      std::lock_guard lock(mu_);
      held_[u.entry] = {u.job, stop};
    }
    const bool rendered = render_unit(fc, u, *stop);
    {
      std::lock_guard lock(mu_);
      held_.erase(u.entry);
    }
    if (abandoned_) return;
    if (!rendered) {
      counters_.units_stopped += 1;
      // Canceled or lost: acknowledged without a result (a lost entry is gone already). A
      // shutdown hands it back instead, so another node starts it at once.
      (void)fc.release(u);
    }
  }
}

std::shared_ptr<const FarmNode::Prepared> FarmNode::prepare(FarmClient& fc, const Unit& unit,
                                                            std::string* error) {
  {
    std::lock_guard lock(mu_);
    if (auto it = prepared_.find(unit.job); it != prepared_.end()) return it->second;
  }
  auto job = FarmJob::from_json(unit.opts, error);
  if (!job) return nullptr;
  auto text = fc.connection().command({"GET", fc.key("scene:" + job->scene)});
  if (!text) {
    *error = "reading the scene: " + text.error().message;
    return nullptr;
  }
  if (text->is_nil()) {
    *error = "the job's scene is no longer kept";
    return nullptr;
  }
  LoadedScene loaded = load_scene(text->str(), LoadDetail::scene);
  if (!loaded.scene) {
    *error = "the job's scene does not load on this node";
    return nullptr;
  }
  auto p = std::make_shared<Prepared>();
  p->job = *job;
  for (const auto& [name, value] : job->options)
    if (auto bad = apply_option(p->options, name, value)) {
      *error = "option " + name + ": " + *bad;
      return nullptr;
    }
  p->scene = std::make_shared<const Scene>(std::move(*loaded.scene));
  p->render = PreparedRender::create(*p->scene, p->options, error);
  if (!p->render) return nullptr;
  std::lock_guard lock(mu_);
  // Another worker may have prepared the same job meanwhile: keep one.
  if (auto [it, added] = prepared_.emplace(unit.job, p); !added) return it->second;
  prepared_order_.push_back(unit.job);
  if (prepared_order_.size() > kPreparedKept) {
    prepared_.erase(prepared_order_.front());
    prepared_order_.erase(prepared_order_.begin());
  }
  return p;
}

bool FarmNode::render_unit(FarmClient& fc, const Unit& unit, const std::atomic<bool>& stop) {
  std::string error;
  std::shared_ptr<const Prepared> p;
  std::unique_ptr<RenderJob> job;
  try {
    p = prepare(fc, unit, &error);
    if (p && (unit.index < 0 || unit.index >= p->job.units)) error = "unit out of range";
    else if (p) job = p->render->job(p->job.unit_range(unit.index), &error);
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (!job) {
    counters_.units_failed += 1;
    (void)fc.fail(unit, error.empty() ? "the unit could not start" : error);
    return true;  // answered (failed), not to be released
  }
  {
    std::lock_guard lock(mu_);
    rendering_[unit.entry] = job.get();
  }
  // A cancel or a lost lease stops the render mid-tile (halt()); the flag covers a stop that
  // came before the render was registered.
  do {
    if (stop.load(std::memory_order_relaxed)) job->cancel();
  } while (job->run_step() != RenderJob::Step::done);
  {
    std::lock_guard lock(mu_);
    rendering_.erase(unit.entry);
  }
  // (a stop after the last step still drops the result: the lease may be another node's now)
  if (job->canceled() || stop.load()) return false;
  const std::string payload = encode_unit(unit_result(*job));
  auto status = fc.complete(unit, payload);
  counters_.units_rendered += 1;
  if (status && *status == CompleteStatus::Assemble) assemble(fc, p->job, unit.job);
  return true;
}

void FarmNode::assemble(FarmClient& fc, const FarmJob& farm_job, const std::string& job) {
  auto tiles = fc.tiles(job, farm_job.units);
  if (!tiles) return;  // the janitor's sweep hands the job to another node
  UnitAssembler assembler(farm_job.width, farm_job.height);
  for (const auto& bytes : *tiles) {
    std::string error;
    if (!bytes) return;  // canceled meanwhile: the tiles went with it
    auto unit = decode_unit(*bytes, &error);
    if (!unit || !assembler.add(*unit, &error)) return;
  }
  if (!assembler.complete()) return;
  const std::vector<unsigned char> png = encode_png(assembler.image());
  const RenderStats st = assembler.stats();
  auto stored = fc.connection().command(
      {"SET", fc.key("png:" + farm_job.result),
       std::string_view(reinterpret_cast<const char*>(png.data()), png.size()), "PX",
       ms_text(config_.result_ttl)});
  if (!stored) return;
  Fields fields = {{"primary_rays", std::to_string(st.primary_rays)},
                   {"shadow_rays", std::to_string(st.shadow_rays)},
                   {"reflection_rays", std::to_string(st.reflection_rays)},
                   {"spp_done", std::to_string(st.spp_done)},
                   {"error_estimate", format_number(st.error_estimate)}};
  if (fc.finish(job, farm_job.result, fields)) counters_.jobs_assembled += 1;
}

void FarmNode::keep_alive() {
  Connection connection(farm_connect_options(config_.connect, setup_));
  FarmClient fc(connection, config_.farm);
  auto next_beat = Clock::now(), next_poll = Clock::now();
  std::optional<Clock::time_point> joined;  // no reclaim until a lease after (re)connecting
  std::uint64_t connects = 0;
  std::string cursor = "0-0";
  while (running_) {
    std::this_thread::sleep_for(std::min(config_.cancel_poll, config_.heartbeat));
    if (!running_ || abandoned_) break;
    if (!connection.connected() && !connection.ensure_connected()) continue;
    if (connection.connects() != connects) {
      connects = connection.connects();
      joined = Clock::now();
    }
    std::vector<std::pair<std::string, Held>> held;
    {
      std::lock_guard lock(mu_);
      held.assign(held_.begin(), held_.end());
    }
    // Jobs canceled (or ended) elsewhere whose message listen() missed: their units stop.
    if (!held.empty() && Clock::now() >= next_poll) {
      next_poll = Clock::now() + config_.cancel_poll;
      std::vector<std::vector<std::string>> cmds;
      for (const auto& [entry, h] : held) cmds.push_back({"HGET", fc.key("job:" + h.job), "state"});
      if (auto states = connection.pipeline(cmds)) {
        for (size_t i = 0; i < held.size(); ++i) {
          const auto& r = (*states)[i];
          if (r && (r->is_nil() || r->str() != "running")) halt(held[i].first);
        }
      }
    }
    if (Clock::now() < next_beat) continue;
    next_beat = Clock::now() + config_.heartbeat;
    std::vector<std::string> entries;
    for (const auto& [entry, h] : held) entries.push_back(entry);
    const std::string info = nlohmann::json({{"workers", config_.workers}}).dump();
    if (auto lost = fc.heartbeat(info, config_.heartbeat * 3, entries)) {
      for (const std::string& entry : *lost) halt(entry);
    }
    // After the leases: how far this node's own jobs have got, for the other nodes' views.
    if (config_.local_progress)
      for (const auto& [job, permille] : config_.local_progress()) (void)fc.progress(job, permille);
    // The janitor: one node at a time, and only a lease after this node (re)connected, since
    // idle times include an outage of Redis.
    if (joined && Clock::now() - *joined >= config_.lease) {
      if (auto mine = fc.janitor_lock(config_.heartbeat * 3); mine && *mine) {
        for (int round = 0; round < 16; ++round) {
          auto r = fc.reclaim(config_.farm.node, config_.lease, cursor);
          if (!r) break;
          counters_.units_reclaimed += r->requeued + r->failed;
          cursor = r->cursor;
          if (cursor == "0-0") break;
        }
        if (auto swept = fc.sweep(config_.farm.node, config_.lease)) {
          counters_.jobs_timed_out += swept->timed_out;
          counters_.jobs_orphaned += swept->orphaned;
          for (const std::string& job : swept->assemble) {
            auto fields = fc.job(job);
            if (!fields || !*fields) continue;
            std::string why;
            auto it = (*fields)->find("opts");
            if (it == (*fields)->end()) continue;
            if (auto farm_job = FarmJob::from_json(it->second, &why)) {
              counters_.jobs_reassembled += 1;
              assemble(fc, *farm_job, job);
            }
          }
        }
      }
    }
  }
}

}  // namespace rayfarm::farm
