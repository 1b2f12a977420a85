// How many units per second one Redis sustains: K threads, each with its own connection (as a
// node's fetcher/completer threads would), run take -> complete with zero render work, plus a
// heartbeat every second, against one redis-server this program starts on a unix socket.
// Prints units/s, p50/p99 latency of take and complete, and Redis's CPU use (in all and per
// unit), for K = 1..32.
//   rayfarm_farm_bench [seconds per K = 2] [payload bytes = 4096]
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "farm_client.h"
#include "redis_server.h"

using namespace rayfarm::farm;
using Clock = std::chrono::steady_clock;

namespace {

struct ThreadStats {
  std::vector<double> take_us, complete_us;
  long units = 0;
  long errors = 0;
};

double percentile(std::vector<double>& v, double p) {
  if (v.empty()) return 0;
  auto k = static_cast<std::size_t>(p * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

double us_since(Clock::time_point t) {
  return std::chrono::duration<double, std::micro>(Clock::now() - t).count();
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 2.0;
  const std::size_t payload_bytes = argc > 2 ? std::strtoul(argv[2], nullptr, 10) : 4096;
  rayfarm::farm::test::RedisServer server;
  if (!server.start()) {
    std::fprintf(stderr, "farm_bench: could not start redis-server (is it installed?)\n");
    return 1;
  }
  const std::string payload(payload_bytes, 'p');
  std::printf(
      "one redis-server 7.0 (unix socket, AOF everysec), zero render work, %zu-byte "
      "results, %.1f s per row\n",
      payload_bytes, seconds);
  std::printf("%3s %10s %10s %10s %12s %12s %10s %14s\n", "K", "units/s", "take p50", "take p99",
              "complete p50", "complete p99", "redis CPU", "redis CPU/unit");
  for (int k : {1, 2, 4, 8, 16, 32}) {
    const std::string prefix = "b" + std::to_string(k) + ":";
    FarmConfig base;
    base.prefix = prefix;
    base.build = "bench";
    base.feed_target = k;
    {  // 8 clients x 4 jobs x 2,000 units: more than any row takes
      base.node = "submitter";
      Connection c(farm_connect_options(server.options(), std::make_shared<FarmSetup>(base)));
      FarmClient farm(c, base);
      for (int client = 0; client < 8; ++client)
        for (int job = 0; job < 4; ++job) {
          SubmitRequest q;
          q.client = "c" + std::to_string(client);
          q.job = q.client + "j" + std::to_string(job);
          q.units = 2000;
          q.opts = "{\"scene\":\"0123456789abcdef\"}";
          if (auto r = farm.submit(q); !r) {
            std::fprintf(stderr, "submit: %s\n", r.error().message.c_str());
            return 1;
          }
        }
    }
    std::atomic<bool> stop{false};
    std::atomic<int> ready{0};
    std::vector<ThreadStats> stats(static_cast<std::size_t>(k));
    std::vector<std::thread> threads;
    for (int t = 0; t < k; ++t)
      threads.emplace_back([&, t] {
        FarmConfig cfg = base;
        cfg.node = "node" + std::to_string(t);
        Connection c(farm_connect_options(server.options(), std::make_shared<FarmSetup>(cfg)));
        FarmClient farm(c, cfg);
        ThreadStats& s = stats[static_cast<std::size_t>(t)];
        (void)c.connect();
        ++ready;
        while (ready.load() < k) std::this_thread::yield();
        auto last_beat = Clock::now();
        while (!stop.load(std::memory_order_relaxed)) {
          auto t0 = Clock::now();
          auto u = farm.take();
          s.take_us.push_back(us_since(t0));
          if (!u || !*u) {
            ++s.errors;
            continue;
          }
          t0 = Clock::now();
          auto done = farm.complete(**u, payload);
          s.complete_us.push_back(us_since(t0));
          if (!done)
            ++s.errors;
          else
            ++s.units;
          if (done && *done == CompleteStatus::Assemble) (void)farm.finish((*u)->job, "png");
          if (Clock::now() - last_beat > std::chrono::seconds(1)) {
            (void)farm.heartbeat("{}", std::chrono::milliseconds(3000), {});
            last_beat = Clock::now();
          }
        }
      });
    while (ready.load() < k) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const double cpu0 = server.cpu_seconds();
    const auto t0 = Clock::now();
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
    stop = true;
    for (auto& th : threads) th.join();
    const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
    const double cpu = server.cpu_seconds() - cpu0;
    ThreadStats all;
    for (auto& s : stats) {
      all.units += s.units;
      all.errors += s.errors;
      all.take_us.insert(all.take_us.end(), s.take_us.begin(), s.take_us.end());
      all.complete_us.insert(all.complete_us.end(), s.complete_us.begin(), s.complete_us.end());
    }
    std::printf("%3d %10.0f %8.0f us %8.0f us %10.0f us %10.0f us %9.0f %% %11.0f us%s\n", k,
                static_cast<double>(all.units) / wall, percentile(all.take_us, 0.5),
                percentile(all.take_us, 0.99), percentile(all.complete_us, 0.5),
                percentile(all.complete_us, 0.99), 100.0 * cpu / wall,
                all.units ? 1e6 * cpu / static_cast<double>(all.units) : 0.0,
                all.errors ? " (errors)" : "");
    std::fflush(stdout);
    // Free this row's keys before the next (the stream is shared by nothing else).
    Connection c(server.options());
    (void)c.command({"FLUSHALL"});
  }
  return 0;
}
