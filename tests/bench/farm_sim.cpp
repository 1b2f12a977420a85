// A farm of N simulated nodes on one Redis: each node does everything a node does (take,
// heartbeat with its held units, complete with a result payload, the janitor's reclaim and
// sweep when it holds the lock) except render, which is a sleep of the unit's time. Every
// `period` seconds 10% of the nodes are killed (they stop without releasing or acknowledging
// anything, as kill -9) and as many new ones join. Prints units/s done, Redis's CPU, and the
// reclaim time of the killed nodes' units (kill to completed by another node: lease, janitor
// round, requeue, take, render).
//   rayfarm_farm_sim [nodes = 120] [seconds = 30] [unit ms = 200] [lease ms = 2000]
//                    [heartbeat ms = 500] [period s = 5]
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "farm_client.h"
#include "redis_server.h"

using namespace rayfarm::farm;
using rayfarm::farm::test::RedisServer;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

namespace {

struct Shared {
  std::mutex mu;
  std::map<std::string, Clock::time_point> abandoned;  // "job/unit" -> when its node was killed
  std::vector<double> reclaim_ms;
  std::atomic<long> units{0}, errors{0}, reclaimed{0};
  std::atomic<bool> ending{false};  // the run's own end: not a kill
};

struct SimNode {
  std::atomic<bool> killed{false};
  std::thread thread;
};

void run_node(const RedisServer& server, FarmConfig cfg, milliseconds unit, milliseconds lease,
              milliseconds beat, Shared& shared, SimNode& self, const std::string& payload) {
  Connection c(farm_connect_options(server.options(), std::make_shared<FarmSetup>(cfg)));
  FarmClient farm(c, cfg);
  auto next_beat = Clock::now();
  const auto joined = Clock::now();
  std::string cursor = "0-0";
  auto keep_alive = [&](const std::vector<std::string>& held) {
    if (Clock::now() < next_beat) return;
    next_beat = Clock::now() + beat;
    (void)farm.heartbeat("{}", beat * 3, held);
    if (Clock::now() - joined < lease) return;
    if (auto mine = farm.janitor_lock(beat * 3); mine && *mine) {
      for (int round = 0; round < 16; ++round) {
        auto r = farm.reclaim(cfg.node, lease, cursor);
        if (!r) break;
        shared.reclaimed += r->requeued;
        cursor = r->cursor;
        if (cursor == "0-0") break;
      }
      (void)farm.sweep(cfg.node, lease);
    }
  };
  while (!self.killed) {
    keep_alive({});
    auto u = farm.take();
    if (!u) {
      ++shared.errors;
      std::this_thread::sleep_for(milliseconds(100));
      continue;
    }
    if (!*u) {
      std::this_thread::sleep_for(milliseconds(20));
      continue;
    }
    const std::string key = (*u)->job + "/" + std::to_string((*u)->index);
    // "Rendering": the unit's time, in slices, heartbeating with the unit held.
    const auto done_at = Clock::now() + unit;
    while (Clock::now() < done_at && !self.killed) {
      keep_alive({(*u)->entry});
      std::this_thread::sleep_for(std::min<Clock::duration>(milliseconds(20), done_at - Clock::now()));
    }
    if (self.killed) {
      std::lock_guard lock(shared.mu);
      if (!shared.ending) shared.abandoned.emplace(key, Clock::now());
      return;  // as kill -9: nothing released, acknowledged or renewed
    }
    auto r = farm.complete(**u, payload);
    if (!r) {
      ++shared.errors;
      continue;
    }
    if (*r == CompleteStatus::Stored || *r == CompleteStatus::Assemble) {
      ++shared.units;
      std::lock_guard lock(shared.mu);
      if (auto it = shared.abandoned.find(key); it != shared.abandoned.end()) {
        shared.reclaim_ms.push_back(
            std::chrono::duration<double, std::milli>(Clock::now() - it->second).count());
        shared.abandoned.erase(it);
      }
    }
    if (*r == CompleteStatus::Assemble) (void)farm.finish((*u)->job, "png:" + (*u)->job);
  }
}

double pct(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1))];
}

}  // namespace

int main(int argc, char** argv) {
  const int nodes = argc > 1 ? std::atoi(argv[1]) : 120;
  const double seconds = argc > 2 ? std::atof(argv[2]) : 30;
  const milliseconds unit(argc > 3 ? std::atoi(argv[3]) : 200);
  const milliseconds lease(argc > 4 ? std::atoi(argv[4]) : 2000);
  const milliseconds beat(argc > 5 ? std::atoi(argv[5]) : 500);
  const double period = argc > 6 ? std::atof(argv[6]) : 5;
  RedisServer server;
  if (!server.start()) {
    std::fprintf(stderr, "farm_sim: could not start redis-server (is it installed?)\n");
    return 1;
  }
  FarmConfig base;
  base.prefix = "sim:";
  base.build = "sim";
  base.feed_target = nodes;
  {
    base.node = "submitter";
    Connection c(farm_connect_options(server.options(), std::make_shared<FarmSetup>(base)));
    FarmClient farm(c, base);
    // 20 clients x 5 jobs, more units than the run can take.
    const long per_job = static_cast<long>(seconds * 1000 / unit.count() * nodes / 100 * 2 + 10);
    for (int client = 0; client < 20; ++client)
      for (int job = 0; job < 5; ++job) {
        SubmitRequest q;
        q.client = "c" + std::to_string(client);
        q.job = q.client + "j" + std::to_string(job);
        q.units = static_cast<int>(per_job);
        q.max_active_per_client = 100;
        q.opts = "{}";
        if (auto r = farm.submit(q); !r) {
          std::fprintf(stderr, "submit: %s\n", r.error().message.c_str());
          return 1;
        }
      }
  }
  const std::string payload(16384, 'p');
  Shared shared;
  std::vector<std::unique_ptr<SimNode>> all;
  int serial = 0;
  auto spawn = [&] {
    auto n = std::make_unique<SimNode>();
    FarmConfig cfg = base;
    cfg.node = "node" + std::to_string(serial++);
    SimNode* raw = n.get();
    n->thread = std::thread([&, cfg, raw] {
      run_node(server, cfg, unit, lease, beat, shared, *raw, payload);
    });
    all.push_back(std::move(n));
  };
  for (int i = 0; i < nodes; ++i) spawn();
  std::vector<SimNode*> live;
  for (auto& n : all) live.push_back(n.get());
  std::mt19937 rng(12345);
  const double cpu0 = server.cpu_seconds();
  const long units0 = shared.units.load();
  const auto t0 = Clock::now();
  int killed = 0;
  auto next_kill = t0 + std::chrono::duration<double>(period);
  while (Clock::now() - t0 < std::chrono::duration<double>(seconds)) {
    std::this_thread::sleep_for(milliseconds(50));
    if (Clock::now() < next_kill) continue;
    next_kill += std::chrono::duration<double>(period);
    std::shuffle(live.begin(), live.end(), rng);
    const int k = std::max(1, nodes / 10);
    for (int i = 0; i < k; ++i) live[static_cast<std::size_t>(i)]->killed = true;
    live.erase(live.begin(), live.begin() + k);
    killed += k;
    for (int i = 0; i < k; ++i) {
      spawn();
      live.push_back(all.back().get());
    }
  }
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  const double cpu = server.cpu_seconds() - cpu0;
  const long done = shared.units.load() - units0;
  shared.ending = true;
  for (auto& n : all) n->killed = true;
  for (auto& n : all) n->thread.join();
  std::lock_guard lock(shared.mu);
  std::printf("%d nodes, units of %lld ms, lease %lld ms, heartbeat %lld ms, %d killed (10%% every "
              "%.0f s), %.0f s\n",
              nodes, static_cast<long long>(unit.count()), static_cast<long long>(lease.count()),
              static_cast<long long>(beat.count()), killed, period, wall);
  std::printf("  units done: %.0f/s (ideal %.0f/s); redis CPU %.0f%% (%.0f us per unit); "
              "errors %ld\n",
              static_cast<double>(done) / wall, nodes * 1000.0 / static_cast<double>(unit.count()),
              100 * cpu / wall, done ? 1e6 * cpu / static_cast<double>(done) : 0.0,
              shared.errors.load());
  std::printf("  units of killed nodes done elsewhere: %zu (%zu not yet at the end); "
              "kill to done: p50 %.0f ms, p99 %.0f ms, max %.0f ms\n",
              shared.reclaim_ms.size(), shared.abandoned.size(), pct(shared.reclaim_ms, 0.5),
              pct(shared.reclaim_ms, 0.99), pct(shared.reclaim_ms, 1.0));
  return 0;
}
