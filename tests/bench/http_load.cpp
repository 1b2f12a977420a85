// Tiny renders per second through rayfarmd's HTTP API: C connections, each sending
// POST /render?wait=1 for a small scene, one request after another, for S seconds. Every
// request differs (its seed), so none is a cache hit. Prints requests/s, the p50/p99 latency
// and the failures (any answer but 200).
//   rayfarm_http_load HOST PORT SCENE [connections = 32] [seconds = 10] [query = width=32&height=24&spp=2]
#include <httplib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

using Clock = std::chrono::steady_clock;

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s HOST PORT SCENE [connections] [seconds] [query]\n", argv[0]);
    return 2;
  }
  const std::string host = argv[1];
  const int port = std::atoi(argv[2]);
  std::ifstream in(argv[3], std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  const std::string scene = text.str();
  const int connections = argc > 4 ? std::atoi(argv[4]) : 32;
  const double seconds = argc > 5 ? std::atof(argv[5]) : 10;
  const std::string query = argc > 6 ? argv[6] : "width=32&height=24&spp=2";
  std::atomic<long> next_seed{1}, failures{0};
  std::vector<std::vector<double>> latencies(connections);
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  std::vector<std::thread> threads;
  for (int c = 0; c < connections; ++c)
    threads.emplace_back([&, c] {
      httplib::Client client(host, port);
      client.set_keep_alive(true);
      client.set_read_timeout(120, 0);
      while (Clock::now() < end) {
        const std::string path = "/render?wait=1&" + query + "&seed=" + std::to_string(next_seed++);
        const auto t0 = Clock::now();
        auto res = client.Post(path, scene, "text/plain");
        const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        if (!res || res->status != 200) {
          ++failures;
          if (!res) std::this_thread::sleep_for(std::chrono::milliseconds(10));
          continue;
        }
        latencies[c].push_back(ms);
      }
    });
  for (auto& t : threads) t.join();
  std::vector<double> all;
  for (auto& v : latencies) all.insert(all.end(), v.begin(), v.end());
  std::sort(all.begin(), all.end());
  auto pct = [&](double p) { return all.empty() ? 0 : all[static_cast<size_t>(p * (all.size() - 1))]; };
  std::printf("%d connections, %.0f s: %zu renders, %.1f renders/s, p50 %.1f ms, p99 %.1f ms, "
              "%ld failed\n",
              connections, seconds, all.size(), static_cast<double>(all.size()) / seconds,
              pct(0.5), pct(0.99), failures.load());
  return failures.load() == 0 ? 0 : 1;
}
