// Farm nodes rendering one job together: the image byte-identical to a local render, also when
// a node dies holding units, and a cancel sent through any connection stopping every node.
#include <chrono>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>
#include <vector>

#include "farm_fixture.h"
#include "farm_node.h"
#include "rayfarm/image_io.h"
#include "rayfarm/load.h"
#include "rayfarm/render_unit.h"
#include "rayfarm/sha256.h"

namespace rayfarm::farm::test {
namespace {

using namespace std::chrono_literals;

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class FarmNodes : public FarmTest {
 protected:
  std::unique_ptr<FarmNode> start_node(const std::string& name, int workers = 1,
                                       std::chrono::milliseconds cancel_poll = 50ms,
                                       std::chrono::milliseconds heartbeat = 100ms) {
    NodeConfig c;
    c.connect = server_->options();
    c.farm = config(name, 2);
    c.workers = workers;
    c.heartbeat = heartbeat;
    c.lease = 5 * heartbeat;
    c.cancel_poll = cancel_poll;
    auto n = std::make_unique<FarmNode>(c);
    n->start();
    return n;
  }

  FarmSubmission submission(const std::string& job, const std::string& file, int w, int h,
                            int spp, double unit_work) {
    FarmSubmission s;
    s.job = job;
    s.client = "alice";
    s.scene_text = read_text(std::string(RAYFARM_SOURCE_DIR) + "/" + file);
    s.options.width = w;
    s.options.height = h;
    s.options.spp = spp;
    s.result_key = "png-" + job;
    s.unit_work = unit_work;
    return s;
  }

  std::string local_png(const FarmSubmission& s) {
    LoadedScene loaded = load_scene(s.scene_text);
    EXPECT_TRUE(loaded.scene);
    if (!loaded.scene) return {};
    const Image image = render_image(*loaded.scene, s.options, 2);
    const auto png = encode_png(image);
    return std::string(png.begin(), png.end());
  }

  // Waits for the job to end; returns its final state.
  std::string wait_final(const std::string& job, std::chrono::milliseconds limit = 60s) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < end) {
      const std::string state = hget("job:" + job, "state");
      if (state == "done" || state == "failed" || state == "canceled") return state;
      std::this_thread::sleep_for(20ms);
    }
    return "timeout";
  }
};

TEST_F(FarmNodes, TwoNodesRenderAJobByteIdenticalToALocalRender) {
  auto client = node("client");
  const FarmSubmission s = submission("j1", "scenes/lab.txt", 200, 150, 2, 5e4);
  auto r = submit_job(*client.farm, s);
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_EQ(r->status, SubmitStatus::Accepted);
  EXPECT_GT(std::stoi(hget("job:j1", "units")), 4);
  auto a = start_node("a"), b = start_node("b");
  ASSERT_EQ(wait_final("j1"), "done") << hget("job:j1", "error");
  auto png = job_png(*client.farm, s.result_key);
  ASSERT_TRUE(png && *png);
  EXPECT_EQ(**png, local_png(s)) << "the farm's PNG is not the local render's";
  EXPECT_GT(a->counters().units_rendered.load(), 0u);
  EXPECT_GT(b->counters().units_rendered.load(), 0u);
  EXPECT_EQ(a->counters().jobs_assembled + b->counters().jobs_assembled, 1u);
  EXPECT_EQ(stream_length(), 0);
  EXPECT_EQ(pending(), 0);
  EXPECT_EQ(integer({"EXISTS", prefix_ + "tiles:j1"}), 0) << "tiles are dropped once assembled";
}

TEST_F(FarmNodes, ANodeThatDiesHoldingAUnitLosesNothing) {
  auto client = node("client");
  // A tile a unit (spp 8, 9 bounces): 48 units, each long enough to be caught holding one.
  const FarmSubmission s = submission("j2", "scenes/lab.txt", 256, 192, 8, 1024 * 8 * 9.0);
  ASSERT_TRUE(submit_job(*client.farm, s));
  // A victim caught holding a unit it has not acknowledged. On a loaded machine this thread
  // can sleep past the end of the unit it saw held: then another victim is tried.
  std::vector<std::unique_ptr<FarmNode>> victims;
  for (int i = 0; i < 5 && pending() == 0; ++i) {
    victims.push_back(start_node("victim" + std::to_string(i)));
    const auto end = std::chrono::steady_clock::now() + 20s;
    while (victims.back()->in_flight() == 0 && std::chrono::steady_clock::now() < end)
      std::this_thread::sleep_for(1ms);
    ASSERT_GT(victims.back()->in_flight(), 0u);
    victims.back()->abandon();  // as kill -9: no release, no ack, no more heartbeats
  }
  ASSERT_GT(pending(), 0) << "no victim was caught holding a unit";
  auto a = start_node("a"), b = start_node("b");
  ASSERT_EQ(wait_final("j2"), "done") << hget("job:j2", "error");
  EXPECT_GE(a->counters().units_reclaimed + b->counters().units_reclaimed, 1u);
  auto png = job_png(*client.farm, s.result_key);
  ASSERT_TRUE(png && *png);
  EXPECT_EQ(**png, local_png(s));
  EXPECT_EQ(pending(), 0);
}

TEST_F(FarmNodes, ACancelFromAnyConnectionStopsEveryNodeAtOnce) {
  auto client = node("client");
  // Units of seconds each, so that only a stop mid-unit ends them this soon.
  const FarmSubmission s = submission("j3", "scenes/lab.txt", 800, 600, 64, 1024 * 64 * 9.0 * 128);
  ASSERT_TRUE(submit_job(*client.farm, s));
  // No polling of job states and a slow heartbeat: only the cancel channel can stop the
  // units this soon.
  auto a = start_node("a", 1, 1h, 3s), b = start_node("b", 1, 1h, 3s);
  const auto end = std::chrono::steady_clock::now() + 20s;
  while ((a->in_flight() == 0 || b->in_flight() == 0) && std::chrono::steady_clock::now() < end)
    std::this_thread::sleep_for(1ms);
  ASSERT_GT(a->in_flight() + b->in_flight(), 1u);
  auto other = node("other");
  auto c = other->cancel("j3", "alice");
  ASSERT_TRUE(c);
  EXPECT_EQ(c->status, CancelStatus::Canceled);
  const auto t0 = std::chrono::steady_clock::now();
  while (a->in_flight() + b->in_flight() > 0 && std::chrono::steady_clock::now() - t0 < 5s)
    std::this_thread::sleep_for(1ms);
  const auto stopped_after = std::chrono::steady_clock::now() - t0;
  EXPECT_EQ(a->in_flight() + b->in_flight(), 0u);
#ifdef RAYFARM_SANITIZED
  // Renders are 5-15x slower there, and their mid-tile checks as far apart; still far below
  // the 3 s heartbeat, the only other way these units would stop this soon.
  constexpr auto kBound = 1500ms;
#else
  constexpr auto kBound = 500ms;
#endif
  EXPECT_LT(stopped_after, kBound) << "running units stop within a fraction of a second";
  EXPECT_EQ(hget("job:j3", "state"), "canceled");
  EXPECT_EQ(integer({"EXISTS", prefix_ + "tiles:j3"}), 0);
}

// A job's limit is the one its accepting node was given, whichever nodes render it and
// whatever limit the janitor's own node has: a job of the short limit fails with `timeout`
// (and its units stop on the cancel channel); one submitted without a limit goes on.
TEST_F(FarmNodes, AJobPastItsOwnLimitFailsWhileOneWithoutALimitGoesOn) {
  auto client = node("client");
  FarmSubmission s = submission("j6", "scenes/lab.txt", 800, 600, 64, 1024 * 64 * 9.0 * 128);
  s.timeout = 400ms;
  ASSERT_TRUE(submit_job(*client.farm, s));
  FarmSubmission slow = submission("j7", "scenes/lab.txt", 400, 300, 64, 1024 * 64 * 9.0 * 64);
  slow.client = "bob";
  ASSERT_TRUE(submit_job(*client.farm, slow));
  auto a = start_node("a", 2), b = start_node("b", 2);
  ASSERT_EQ(wait_final("j6", 30s), "failed");
  EXPECT_EQ(hget("job:j6", "code"), "timeout");
  EXPECT_NE(hget("job:j6", "error").find("limit of 0.4 s"), std::string::npos)
      << hget("job:j6", "error");
  // The janitor counts it once its sweep call returns, a moment after Redis says failed.
  auto timed_out = [&] { return a->counters().jobs_timed_out + b->counters().jobs_timed_out; };
  for (auto end = std::chrono::steady_clock::now() + 10s;
       timed_out() == 0 && std::chrono::steady_clock::now() < end;)
    std::this_thread::sleep_for(5ms);
  EXPECT_EQ(timed_out(), 1u);
  EXPECT_EQ(integer({"EXISTS", prefix_ + "tiles:j6"}), 0);
  // Bob's job, submitted without a limit, has no deadline and is not timed out (it may have
  // finished meanwhile; it is canceled if not, to end the test).
  EXPECT_EQ(hget("job:j7", "timeout_ms"), "0");
  EXPECT_EQ(integer({"ZCARD", prefix_ + "deadlines"}), 0);  // j6 left it; j7 was never in
  EXPECT_NE(hget("job:j7", "state"), "failed") << hget("job:j7", "error");
  (void)client->cancel("j7", "bob");
}

TEST_F(FarmNodes, ACancelWhoseMessageWasMissedIsFoundByThePoll) {
  auto client = node("client");
  const FarmSubmission s = submission("j5", "scenes/lab.txt", 400, 300, 64, 1024 * 64 * 9.0 * 32);
  ASSERT_TRUE(submit_job(*client.farm, s));
  auto a = start_node("a", 1, 100ms, 3s);
  const auto end = std::chrono::steady_clock::now() + 20s;
  while (a->in_flight() == 0 && std::chrono::steady_clock::now() < end)
    std::this_thread::sleep_for(1ms);
  ASSERT_EQ(a->in_flight(), 1u);
  // Ended behind the Functions' back: no message is published.
  ASSERT_EQ(integer({"HSET", prefix_ + "job:j5", "state", "canceled"}), 0);
  const auto t0 = std::chrono::steady_clock::now();
  while (a->in_flight() > 0 && std::chrono::steady_clock::now() - t0 < 5s)
    std::this_thread::sleep_for(1ms);
  EXPECT_EQ(a->in_flight(), 0u);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 1s);
}

TEST_F(FarmNodes, AJobWhoseAssemblerDiedIsAssembledByTheJanitor) {
  auto ghost = node("ghost");
  const FarmSubmission s = submission("j6", "scenes/cho.txt", 96, 64, 2, 2e4);
  ASSERT_TRUE(submit_job(*ghost.farm, s));
  // The ghost renders every unit as a node would, is told to assemble, and dies.
  LoadedScene loaded = load_scene(s.scene_text);
  ASSERT_TRUE(loaded.scene);
  std::string error;
  auto prepared = PreparedRender::create(*loaded.scene, s.options, &error);
  ASSERT_TRUE(prepared) << error;
  bool told = false;
  for (int i = 0; i < 100 && !told; ++i) {
    auto u = ghost->take();
    ASSERT_TRUE(u && *u);
    auto job = FarmJob::from_json((*u)->opts, &error);
    ASSERT_TRUE(job) << error;
    auto render = prepared->job(job->unit_range((*u)->index), &error);
    ASSERT_TRUE(render) << error;
    while (render->run_step() != RenderJob::Step::done) {
    }
    told = *ghost->complete(**u, encode_unit(unit_result(*render))) == CompleteStatus::Assemble;
  }
  ASSERT_TRUE(told);
  ASSERT_EQ(hget("job:j6", "state"), "assembling");
  auto a = start_node("a");
  ASSERT_EQ(wait_final("j6", 10s), "done") << hget("job:j6", "error");
  EXPECT_EQ(a->counters().jobs_reassembled.load(), 1u);
  auto png = job_png(*ghost.farm, s.result_key);
  ASSERT_TRUE(png && *png);
  EXPECT_EQ(**png, local_png(s));
}

TEST_F(FarmNodes, AJobWhoseSceneIsGoneFailsAfterThreeTriesWithTheReason) {
  auto client = node("client");
  FarmSubmission s = submission("j4", "scenes/cho.txt", 64, 48, 1, 1e9);
  ASSERT_TRUE(submit_job(*client.farm, s));
  ASSERT_EQ(integer({"DEL", prefix_ + "scene:" + sha256_hex(s.scene_text)}), 1);
  auto a = start_node("a");
  ASSERT_EQ(wait_final("j4"), "failed");
  EXPECT_NE(hget("job:j4", "error").find("no longer kept"), std::string::npos)
      << hget("job:j4", "error");
  EXPECT_EQ(a->counters().units_failed.load(), 3u);
}

// A name is in use while a node of that name runs (its record is renewed), and free again once
// it stops, its record left to run out (a node restarted under its name starts once it has; a
// second node under a running one's name does not: rayfarmd refuses it at start).
TEST_F(FarmNodes, ANameIsInUseOnlyWhileItsNodeRuns) {
  TestNode probe = node("twin");
  auto running = probe->node_running();
  ASSERT_TRUE(running) << running.error().message;
  EXPECT_FALSE(*running);  // no record
  const std::string record = prefix_ + "node:twin";
  auto twin = start_node("twin", 1, 50ms, 250ms);
  for (int i = 0; i < 500 && integer({"EXISTS", record}) == 0; ++i) std::this_thread::sleep_for(10ms);
  ASSERT_EQ(integer({"EXISTS", record}), 1);
  for (int round = 0; round < 3; ++round) {
    running = probe->node_running();
    ASSERT_TRUE(running) << running.error().message;
    EXPECT_TRUE(*running) << "round " << round;
  }
  twin->stop();  // (its record left behind runs out, or has)
  running = probe->node_running();
  ASSERT_TRUE(running) << running.error().message;
  EXPECT_FALSE(*running);
  // A record a killed node left: not renewed before it runs out, so not running.
  ASSERT_TRUE(raw().command({"SET", prefix_ + "node:ghost", "{}", "PX", "1500"}));
  const auto t0 = std::chrono::steady_clock::now();
  running = node("ghost")->node_running();
  ASSERT_TRUE(running) << running.error().message;
  EXPECT_FALSE(*running);
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 1s);  // it waited for the record to run out
}

}  // namespace
}  // namespace rayfarm::farm::test
