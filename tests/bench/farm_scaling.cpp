// Two one-worker farm nodes against one on a long job: how close to twice as fast, and what
// the farm costs against a local render of the same job. Starts its own redis-server (AOF on,
// unix socket); the nodes run in this process, each with its own connections, as separate
// processes would. Rounds alternate the configurations; medians are printed.
//   rayfarm_farm_scaling SCENE [rounds = 3] [spp = 8] [unit ms = 150]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "farm_node.h"
#include "rayfarm/image_io.h"
#include "rayfarm/load.h"
#include "redis_server.h"

using namespace rayfarm;
using namespace rayfarm::farm;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

namespace {

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s SCENE [rounds] [spp] [unit ms]\n", argv[0]);
    return 2;
  }
  const int rounds = argc > 2 ? std::atoi(argv[2]) : 3;
  const int spp = argc > 3 ? std::atoi(argv[3]) : 8;
  const double unit_ms = argc > 4 ? std::atof(argv[4]) : 150;
  std::ifstream in(argv[1], std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  LoadedScene loaded = load_scene(text.str());
  if (!loaded.scene) {
    std::fprintf(stderr, "%s does not load\n", argv[1]);
    return 1;
  }
  RenderOptions options;
  options.spp = spp;
  const Camera& cam = loaded.scene->cameras.front();
  options.width = cam.width;
  options.height = cam.height;

  // The work a unit gets: calibrated from a one-thread local render, so a unit takes unit_ms.
  const auto c0 = Clock::now();
  const Image reference = render_image(*loaded.scene, options, 1);
  const double one_thread_s = seconds_since(c0);
  const double pixel_work = spp * (options.effective_max_depth() + 1.0);
  const double job_work = static_cast<double>(options.width) * options.height * pixel_work;
  const double unit_work = job_work * unit_ms / 1000 / one_thread_s;
  const auto png = encode_png(reference);
  const std::string expected(png.begin(), png.end());

  test::RedisServer redis;
  if (!redis.start()) {
    std::fprintf(stderr, "redis-server did not start\n");
    return 1;
  }
  std::map<std::string, std::vector<double>> times;
  int job_no = 0;
  int units = 0;
  bool identical = true;
  for (int round = 0; round < rounds; ++round) {
    for (int threads : {1, 2}) {
      const auto t0 = Clock::now();
      render_image(*loaded.scene, options, threads);
      times["local, " + std::to_string(threads) + " thread" + (threads > 1 ? "s" : "")]
          .push_back(seconds_since(t0));
    }
    for (int nodes : {1, 2}) {
      const std::string prefix = "b" + std::to_string(++job_no) + ":";
      std::vector<std::unique_ptr<FarmNode>> farm;
      for (int n = 0; n < nodes; ++n) {
        NodeConfig c;
        c.connect = redis.options();
        c.farm.prefix = prefix;
        c.farm.node = "node" + std::to_string(n);
        c.farm.build = "bench";
        c.farm.feed_target = 2 * nodes;
        farm.push_back(std::make_unique<FarmNode>(c));
        farm.back()->start();
      }
      Connection conn(farm_connect_options(redis.options(), std::make_shared<FarmSetup>(
                                                                 FarmConfig{prefix, "client", "bench"})));
      FarmClient client(conn, FarmConfig{prefix, "client", "bench"});
      FarmSubmission s;
      s.job = "job";
      s.client = "bench";
      s.scene_text = text.str();
      s.options = options;
      s.result_key = "result";
      s.unit_work = unit_work;
      const auto t0 = Clock::now();
      auto r = submit_job(client, s);
      if (!r || r->status != SubmitStatus::Accepted) {
        std::fprintf(stderr, "submit failed\n");
        return 1;
      }
      for (;;) {
        auto job = client.job("job");
        if (job && *job && (**job)["state"] != "queued" && (**job)["state"] != "running" &&
            (**job)["state"] != "assembling") {
          units = std::stoi((**job)["units"]);
          break;
        }
        std::this_thread::sleep_for(2ms);
      }
      times[std::to_string(nodes) + " node" + (nodes > 1 ? "s" : "") + " x 1 worker"].push_back(
          seconds_since(t0));
      auto got = job_png(client, "result");
      identical = identical && got && *got && **got == expected;
      for (auto& node : farm) node->stop();
    }
  }
  std::printf("%s, %dx%d, spp %d, %d units of ~%.0f ms (one thread: %.2f s), %d rounds\n",
              argv[1], options.width, options.height, spp, units, unit_ms, one_thread_s, rounds);
  for (const auto& [name, t] : times) std::printf("  %-22s %7.3f s (median)\n", name.c_str(), median(t));
  const double one = median(times["1 node x 1 worker"]), two = median(times["2 nodes x 1 worker"]);
  std::printf("  two nodes / one node: %.2fx faster; parallel efficiency %.0f%%\n", one / two,
              100 * one / (2 * two));
  std::printf("  farm, 2 nodes x 1 worker / local 2 threads: %.2f\n",
              two / median(times["local, 2 threads"]));
  std::printf("  every farm image byte-identical to the local render: %s\n", identical ? "yes" : "NO");
  return identical ? 0 : 1;
}
