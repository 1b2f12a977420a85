#include "farm_client.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <random>
#include <thread>

namespace rayfarm::farm {
namespace {

Error unexpected(std::string_view function, std::string_view what) {
  return Error{ErrorKind::Unexpected,
               std::string(function) + ": unexpected reply " + std::string(what)};
}

int to_int(std::string_view s) {
  int v = 0;
  std::from_chars(s.data(), s.data() + s.size(), v);
  return v;
}

std::string ms(std::chrono::milliseconds d) { return std::to_string(d.count()); }

// Each Function answers with status words; each call maps them to its enum with one table.
template <class E>
using Words = std::initializer_list<std::pair<std::string_view, E>>;

template <class E>
Result<E> word_of(std::string_view function, std::string_view word, Words<E> table) {
  for (const auto& [w, e] : table)
    if (w == word) return e;
  return unexpected(function, word);
}

// A one-word reply.
template <class E>
Result<E> word_reply(std::string_view function, const Result<Reply>& r, Words<E> table) {
  if (!r) return r.error();
  return word_of(function, r->str(), table);
}

// A {word, text} reply.
template <class E>
Result<std::pair<E, std::string>> pair_reply(std::string_view function, const Result<Reply>& r,
                                             Words<E> table) {
  if (!r) return r.error();
  if (r->size() != 2) return unexpected(function, "shape");
  auto e = word_of(function, (*r)[0].str(), table);
  if (!e) return e.error();
  return std::pair{*e, std::string((*r)[1].str())};
}

}  // namespace

// --- setup ---

Status create_work_group(Connection& c, std::string_view prefix) {
  const std::string stream = std::string(prefix) + "work";
  // From "0": entries added before the group existed (a flushed group) are still delivered.
  auto r = c.command({"XGROUP", "CREATE", stream, "render", "0", "MKSTREAM"});
  if (!r && !r.error().message.starts_with("BUSYGROUP")) return r.error();
  return Ok{};
}

Status FarmSetup::on_connect(Connection& c) {
  std::string fresh;
  {
    std::random_device rd;
    char buf[33];
    for (int i = 0; i < 4; ++i) std::snprintf(buf + 8 * i, 9, "%08x", rd());
    fresh.assign(buf, 32);
  }
  // The build check comes before FUNCTION LOAD REPLACE: a node of another build must not
  // replace the library the farm runs.
  FarmClient client(c, config_);
  auto joined = client.join(fresh);
  if (!joined) return joined.error();
  if (auto r = c.command({"FUNCTION", "LOAD", "REPLACE", function_library()}); !r) return r.error();
  if (auto s = create_work_group(c, config_.prefix); !s) return s;
  std::lock_guard lock(mutex_);
  if (epoch_.empty()) {
    epoch_ = joined->epoch;
  } else if (epoch_ != joined->epoch) {
    // Redis lost the farm's state (restarted empty, FLUSHALL): jobs it held are gone.
    std::fprintf(stderr,
                 "rayfarmd: the farm's Redis lost its state (epoch %s, was %s): jobs it held "
                 "answer 404 and must be submitted again\n",
                 joined->epoch.substr(0, 8).c_str(), epoch_.substr(0, 8).c_str());
    epoch_ = joined->epoch;
    ++epoch_changes_;
  }
  return Ok{};
}

std::string FarmSetup::epoch() const {
  std::lock_guard lock(mutex_);
  return epoch_;
}

ConnectOptions farm_connect_options(ConnectOptions base, std::shared_ptr<FarmSetup> setup) {
  base.on_connect = [setup](Connection& c) { return setup->on_connect(c); };
  return base;
}

// --- calls ---

Result<Reply> FarmClient::fcall(std::string_view function, std::vector<std::string_view> args) {
  std::vector<std::string_view> argv{"FCALL", function, "0", config_.prefix};
  argv.insert(argv.end(), args.begin(), args.end());
  Result<Reply> r = c_.command(std::span<const std::string_view>(argv));
  if (!r && r.error().kind == ErrorKind::NoGroup) {
    // Redis lost the stream (FLUSHALL, or restarted empty): recreate the group, try once more.
    if (auto s = create_work_group(c_, config_.prefix); !s) return s.error();
    r = c_.command(std::span<const std::string_view>(argv));
  }
  return r;
}

Result<JoinResult> FarmClient::join(std::string_view fresh_epoch) {
  // SET NX GET (7.0): sets the key if absent and answers the value it had, in one command.
  const std::string build_key = key("meta:build"), epoch_key = key("meta:epoch");
  auto build = c_.command({"SET", build_key, config_.build, "NX", "GET"});
  if (!build) return build.error();
  if (auto have = build->string(); have && *have != config_.build) {
    // An upgrade: once no node of the old build is alive, the farm takes the new one.
    auto nodes = c_.command({"ZRANGE", key("nodes"), "0", "-1"});
    if (!nodes) return nodes.error();
    for (std::size_t i = 0; i < nodes->size(); ++i) {
      auto alive = c_.command({"EXISTS", key("node:" + std::string((*nodes)[i].str()))});
      if (!alive) return alive.error();
      if (alive->integer() == 1)
        return Error{ErrorKind::Build,
                     "this farm runs build " + std::string(*have) + ", this node is " +
                         config_.build +
                         ": the nodes would render different images or disagree on the farm's "
                         "functions; the farm takes this build once no node of the other is "
                         "alive"};
    }
    auto set = c_.command({"SET", build_key, config_.build});
    if (!set) return set.error();
  }
  auto epoch = c_.command({"SET", epoch_key, fresh_epoch, "NX", "GET"});
  if (!epoch) return epoch.error();
  if (auto have = epoch->string()) return JoinResult{std::string(*have), false};
  return JoinResult{std::string(fresh_epoch), true};
}

Result<SubmitResult> FarmClient::submit(const SubmitRequest& q) {
  const std::string prio = std::to_string(static_cast<int>(q.priority));
  const std::string units = std::to_string(q.units);
  const std::string max_active = std::to_string(q.max_active_per_client);
  const std::string max_jobs = std::to_string(q.max_jobs);
  const std::string target = std::to_string(config_.feed_target);
  const std::string ttl = ms(q.ttl), idem_ttl = ms(q.idempotency_ttl), timeout = ms(q.timeout);
  std::vector<std::string_view> args{q.job,  q.client, prio,   units,    max_active,
                                     max_jobs, target, ttl,    q.idempotency_key,
                                     idem_ttl, q.opts, timeout};
  for (const auto& [k, v] : q.fields) {
    args.push_back(k);
    args.push_back(v);
  }
  auto r = fcall("rf1_submit", std::move(args));
  auto p = pair_reply<SubmitStatus>("rf1_submit", r,
                                    {{"accepted", SubmitStatus::Accepted},
                                     {"exists", SubmitStatus::Exists},
                                     {"limit", SubmitStatus::ClientLimit},
                                     {"full", SubmitStatus::Full}});
  if (!p) return p.error();
  return SubmitResult{p->first, p->second};
}

Result<std::optional<Unit>> FarmClient::unit_reply(Result<Reply> r) {
  if (!r) return r.error();
  if (r->is_nil()) return std::optional<Unit>();
  if (r->size() != 5) return unexpected("rf1_take", "shape");
  Unit u;
  u.entry = std::string((*r)[0].str());
  u.job = std::string((*r)[1].str());
  u.index = to_int((*r)[2].str());
  u.tries = to_int((*r)[3].str());
  u.opts = std::string((*r)[4].str());
  return std::optional<Unit>(std::move(u));
}

Result<std::optional<Unit>> FarmClient::take() {
  const std::string target = std::to_string(config_.feed_target);
  return unit_reply(fcall("rf1_take", {config_.node, target}));
}

Result<std::optional<Unit>> FarmClient::block_for_work() {
  const std::string stream = key("work"), block = ms(config_.block);
  const std::string_view argv[] = {"XREADGROUP", "GROUP", "render",  config_.node, "COUNT", "1",
                                   "BLOCK",      block,   "STREAMS", stream,       ">"};
  // The socket timeout must outlast the block, or every idle wait would drop the connection.
  auto r = c_.command(argv, config_.block + c_.options().command_timeout);
  if (!r && r.error().kind == ErrorKind::NoGroup) {
    if (auto s = create_work_group(c_, config_.prefix); !s) return s.error();
    return std::optional<Unit>();
  }
  if (!r) return r.error();
  if (r->is_nil()) return std::optional<Unit>();
  // [[stream, [[id, [fields...]]]]]
  std::string_view id = (*r)[0][1][0][0].str();
  if (id.empty()) return unexpected("XREADGROUP", "shape");
  const std::string target = std::to_string(config_.feed_target);
  return unit_reply(fcall("rf1_adopt", {config_.node, target, id}));
}

Result<std::vector<std::string>> FarmClient::heartbeat(std::string_view node_info,
                                                       std::chrono::milliseconds ttl,
                                                       const std::vector<std::string>& entries) {
  const std::string t = ms(ttl);
  std::vector<std::string_view> args{config_.node, t, node_info};
  args.insert(args.end(), entries.begin(), entries.end());
  auto r = fcall("rf1_heartbeat", std::move(args));
  if (!r) return r.error();
  std::vector<std::string> lost;
  for (std::size_t i = 0; i < r->size(); ++i) lost.emplace_back((*r)[i].str());
  return lost;
}

Result<CompleteStatus> FarmClient::complete(const Unit& u, std::string_view payload) {
  const std::string index = std::to_string(u.index);
  return word_reply<CompleteStatus>(
      "rf1_complete", fcall("rf1_complete", {config_.node, u.entry, u.job, index, payload}),
      {{"ok", CompleteStatus::Stored},
       {"duplicate", CompleteStatus::Duplicate},
       {"drop", CompleteStatus::Dropped},
       {"assemble", CompleteStatus::Assemble}});
}

Result<FailStatus> FarmClient::fail(const Unit& u, std::string_view error) {
  const std::string tries = std::to_string(config_.max_tries);
  return word_reply<FailStatus>("rf1_fail",
                                fcall("rf1_fail", {config_.node, u.entry, tries, error}),
                                {{"requeued", FailStatus::Requeued},
                                 {"failed", FailStatus::JobFailed},
                                 {"drop", FailStatus::Dropped},
                                 {"gone", FailStatus::Gone}});
}

Result<ReleaseStatus> FarmClient::release(const Unit& u) {
  return word_reply<ReleaseStatus>("rf1_release", fcall("rf1_release", {config_.node, u.entry}),
                                   {{"requeued", ReleaseStatus::Requeued},
                                    {"drop", ReleaseStatus::Dropped},
                                    {"gone", ReleaseStatus::Gone}});
}

Result<std::vector<std::string>> FarmClient::held_entries(int count) {
  const std::string stream = key("work"), n = std::to_string(count);
  auto r = c_.command({"XPENDING", stream, "render", "-", "+", n, config_.node});
  if (!r) return r.error();
  std::vector<std::string> out;
  for (std::size_t i = 0; i < r->size(); ++i) out.emplace_back((*r)[i][0].str());
  return out;
}

Result<ReclaimResult> FarmClient::reclaim(std::string_view janitor, std::chrono::milliseconds lease,
                                          std::string_view cursor, int count) {
  const std::string l = ms(lease), tries = std::to_string(config_.max_tries);
  const std::string n = std::to_string(count);
  auto r = fcall("rf1_reclaim", {janitor, l, tries, cursor, n});
  if (!r) return r.error();
  if (r->size() != 3) return unexpected("rf1_reclaim", "shape");
  return ReclaimResult{std::string((*r)[0].str()), static_cast<int>((*r)[1].integer()),
                       static_cast<int>((*r)[2].integer())};
}

Result<SweepResult> FarmClient::sweep(std::string_view janitor, std::chrono::milliseconds lease,
                                      int count) {
  const std::string l = ms(lease), n = std::to_string(count);
  auto r = fcall("rf1_sweep", {janitor, l, n});
  if (!r) return r.error();
  if (r->size() < 2) return unexpected("rf1_sweep", "shape");
  SweepResult out{static_cast<int>((*r)[0].integer()), static_cast<int>((*r)[1].integer()), {}};
  for (std::size_t i = 2; i < r->size(); ++i) out.assemble.emplace_back((*r)[i].str());
  return out;
}

Result<FarmCounts> FarmClient::counts() {
  auto r = fcall("rf1_counts", {});
  if (!r) return r.error();
  if (r->size() != 4) return unexpected("rf1_counts", "shape");
  return FarmCounts{(*r)[0].integer(), (*r)[1].integer(), (*r)[2].integer(), (*r)[3].integer()};
}

Result<CancelResult> FarmClient::cancel(std::string_view job, std::string_view client) {
  auto p = pair_reply<CancelStatus>("rf1_cancel", fcall("rf1_cancel", {job, client}),
                                    {{"canceled", CancelStatus::Canceled},
                                     {"not_found", CancelStatus::NotFound},
                                     {"forbidden", CancelStatus::Forbidden},
                                     {"already", CancelStatus::AlreadyEnded}});
  if (!p) return p.error();
  return CancelResult{p->first, p->second};
}

Result<FinishResult> FarmClient::finish(std::string_view job, std::string_view result_key,
                                        const Fields& fields) {
  std::vector<std::string_view> args{config_.node, job, result_key};
  for (const auto& [k, v] : fields) {
    args.push_back(k);
    args.push_back(v);
  }
  auto p = pair_reply<FinishStatus>("rf1_finish", fcall("rf1_finish", std::move(args)),
                                    {{"done", FinishStatus::Done},
                                     {"already_done", FinishStatus::AlreadyDone},
                                     {"not_assembling", FinishStatus::NotAssembling}});
  if (!p) return p.error();
  return FinishResult{p->first, p->second};
}

Result<RecordStatus> FarmClient::record(const RecordRequest& q) {
  const std::string prio = std::to_string(static_cast<int>(q.priority)), ttl = ms(q.ttl);
  const char* state = q.state == EndState::Done     ? "done"
                      : q.state == EndState::Failed ? "failed"
                                                    : "canceled";
  std::vector<std::string_view> args{config_.node, q.job, q.client, prio,
                                     state,        ttl,   q.result, q.error};
  for (const auto& [k, v] : q.fields) {
    args.push_back(k);
    args.push_back(v);
  }
  auto p = pair_reply<RecordStatus>("rf1_record", fcall("rf1_record", std::move(args)),
                                    {{"recorded", RecordStatus::Recorded},
                                     {"exists", RecordStatus::Exists},
                                     {"forbidden", RecordStatus::Forbidden}});
  if (!p) return p.error();
  return p->first;
}

Result<bool> FarmClient::janitor_lock(std::chrono::milliseconds hold) {
  const std::string h = ms(hold);
  auto r = fcall("rf1_lock", {config_.node, h});
  if (!r) return r.error();
  return r->integer() == 1;
}

Result<bool> FarmClient::node_running() {
  const std::string record = key("node:" + config_.node);
  auto expiry = [&]() -> Result<long long> {
    auto r = c_.command({"PEXPIRETIME", record});
    if (!r) return r.error();
    return r->integer();
  };
  auto first = expiry();
  if (!first) return first.error();
  if (*first < 0) return false;  // none (-2), or one that cannot run out (-1)
  auto left = c_.command({"PTTL", record});
  if (!left) return left.error();
  // Until the record runs out (a heartbeat renews it well before: it lives three), asked a
  // few times a heartbeat: a renewal moves its expiry, which Redis's clock alone sets.
  const long long life = std::max(0LL, left->integer());
  const auto step = std::chrono::milliseconds(std::clamp(life / 12, 10LL, 250LL));
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(life + 100);
  while (std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(step);
    auto now = expiry();
    if (!now) return now.error();
    if (*now < 0) return false;  // ran out: nothing renewed it
    if (*now != *first) return true;
  }
  return false;
}

Result<bool> FarmClient::progress(std::string_view job, int permille) {
  const std::string p = std::to_string(std::clamp(permille, 0, 1000));
  auto r = fcall("rf1_progress", {config_.node, job, p});
  if (!r) return r.error();
  return r->integer() == 1;
}

Result<std::optional<JobFields>> FarmClient::job(std::string_view id) {
  const std::string k = key("job:") + std::string(id);
  auto r = c_.command({"HGETALL", k});
  if (!r) return r.error();
  if (r->size() == 0) return std::optional<JobFields>();
  JobFields out;
  for (std::size_t i = 0; i + 1 < r->size(); i += 2)
    out.emplace(std::string((*r)[i].str()), std::string((*r)[i + 1].str()));
  return std::optional<JobFields>(std::move(out));
}

Result<std::vector<std::optional<std::string>>> FarmClient::tiles(std::string_view job, int units,
                                                                  int chunk) {
  const std::string k = key("tiles:") + std::string(job);
  std::vector<std::optional<std::string>> out;
  out.reserve(static_cast<std::size_t>(std::max(units, 0)));
  for (int first = 0; first < units; first += chunk) {
    std::vector<std::string> argv{"HMGET", k};
    for (int i = first; i < std::min(units, first + chunk); ++i) argv.push_back(std::to_string(i));
    auto r = c_.command(argv);
    if (!r) return r.error();
    for (std::size_t i = 0; i < r->size(); ++i) {
      auto s = (*r)[i].string();
      out.push_back(s ? std::optional<std::string>(std::string(*s)) : std::nullopt);
    }
  }
  return out;
}

}  // namespace rayfarm::farm
