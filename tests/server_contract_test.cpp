// The contract every backend of the service keeps (job store, work queue, blob store), run
// against each backend in backends_under_test(): today the local one, in memory and on a
// results directory. A backend added to that list must pass these tests unchanged; they use
// nothing but the interfaces.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <random>
#include <thread>

#include "blob_store.h"
#include "job_store.h"
#include "service.h"
#include "work_queue.h"

namespace rayfarm::server {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

struct BackendUnderTest {
  std::string name;
  bool durable;  // keeps records and blobs for a second instance over the same place
  // Backends over `place` (a fresh, empty folder per test).
  std::function<Backends(const fs::path& place)> make;
};

void PrintTo(const BackendUnderTest& b, std::ostream* os) { *os << b.name; }

std::vector<BackendUnderTest> backends_under_test() {
  return {
      {"Local", true, [](const fs::path& place) { return make_local_backends(place); }},
      {"LocalMemory", false, [](const fs::path&) { return make_local_backends({}); }},
  };
}

class ServerContract : public ::testing::TestWithParam<BackendUnderTest> {
 protected:
  void SetUp() override {
    place_ = fs::temp_directory_path() /
             ("rayfarm-contract-" + std::to_string(std::random_device{}()));
    fs::create_directories(place_);
    b_ = GetParam().make(place_);
  }
  void TearDown() override {
    b_ = {};
    std::error_code ec;
    fs::remove_all(place_, ec);
  }

  JobStore& jobs() { return *b_.jobs; }
  WorkQueue& queue() { return *b_.queue; }
  BlobStore& blobs() { return *b_.blobs; }

  static JobRecord record(const std::string& client, int n = 0) {
    static std::atomic<int> next{0};
    JobRecord r;
    char id[33];
    std::snprintf(id, sizeof id, "%08x%08x%016x", n, static_cast<unsigned>(next++), 0xabcu);
    r.id = id;
    r.client = client;
    r.created_ms = 1000 + n;
    r.width = 4;
    r.height = 3;
    r.image_name = r.id;
    return r;
  }
  static QueueItem item(const std::string& id, const std::string& client,
                        Priority p = Priority::normal) {
    return {id, client, p};
  }
  std::vector<std::string> claim_all(int limit = 100) {
    std::vector<std::string> order;
    while (auto c = queue().claim("node", limit)) order.push_back(c->id);
    return order;
  }

  fs::path place_;
  Backends b_;
};

// --- JobStore ---

TEST_P(ServerContract, CreatedJobsAreFoundWithAVersionAndTheirFields) {
  JobRecord r = record("addr:a");
  r.options.priority = Priority::batch;
  r.warnings.push_back({Severity::warning, "eye-inside", "the eye is inside 'ball'", {3, 4, "x"}});
  JobRecord made = jobs().create(r, "scene text");
  EXPECT_GE(made.version, 1u);
  auto got = jobs().get(r.id);
  ASSERT_TRUE(got);
  EXPECT_EQ(got->client, "addr:a");
  EXPECT_EQ(got->options.priority, Priority::batch);
  EXPECT_EQ(got->state, JobState::queued);
  EXPECT_EQ(got->version, made.version);
  ASSERT_EQ(got->warnings.size(), 1u);
  EXPECT_EQ(got->warnings[0].where.line, 3);
  EXPECT_FALSE(jobs().get("0123456789abcdef0123456789abcdef"));
}

TEST_P(ServerContract, ATransitionIsACompareAndSet) {
  JobRecord r = jobs().create(record("addr:a"), "s");
  auto running = jobs().transition(r.id, {JobState::queued}, [](JobRecord& x) {
    x.state = JobState::running;
    x.attempts = 1;
  });
  ASSERT_TRUE(running);
  EXPECT_EQ(running->state, JobState::running);
  EXPECT_GT(running->version, r.version);
  // A second transition from the state it left fails and changes nothing.
  auto again = jobs().transition(r.id, {JobState::queued},
                                 [](JobRecord& x) { x.state = JobState::canceled; });
  EXPECT_FALSE(again);
  auto now = jobs().get(r.id);
  ASSERT_TRUE(now);
  EXPECT_EQ(now->state, JobState::running);
  EXPECT_EQ(now->version, running->version);
  EXPECT_FALSE(jobs().transition("0123456789abcdef0123456789abcdef", {JobState::queued},
                                 [](JobRecord& x) { x.state = JobState::running; }));
}

TEST_P(ServerContract, OfRacingTransitionsFromOneStateExactlyOneWins) {
  JobRecord r = jobs().create(record("addr:a"), "s");
  std::atomic<int> wins{0};
  std::vector<std::thread> threads;
  for (int i = 0; i < 8; ++i)
    threads.emplace_back([&, i] {
      if (jobs().transition(r.id, {JobState::queued}, [i](JobRecord& x) {
            x.state = JobState::running;
            x.attempts = i;
          }))
        ++wins;
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(wins.load(), 1);
}

TEST_P(ServerContract, ATransitionCannotChangeWhoseJobItIs) {
  JobRecord r = jobs().create(record("addr:a"), "s");
  auto t = jobs().transition(r.id, {JobState::queued}, [](JobRecord& x) {
    x.client = "addr:mallory";
    x.state = JobState::running;
  });
  ASSERT_TRUE(t);
  EXPECT_EQ(jobs().get(r.id)->client, "addr:a");
}

TEST_P(ServerContract, ListByClientIsNewestFirstOnlyTheirsAndLimited) {
  std::vector<std::string> mine;
  for (int i = 0; i < 5; ++i) {
    mine.push_back(jobs().create(record("addr:a", i), "s").id);
    jobs().create(record("addr:b", i), "s");
  }
  auto three = jobs().list_by_client("addr:a", 3);
  ASSERT_EQ(three.size(), 3u);
  EXPECT_EQ(three[0].id, mine[4]);
  EXPECT_EQ(three[1].id, mine[3]);
  EXPECT_EQ(three[2].id, mine[2]);
  EXPECT_EQ(jobs().list_by_client("addr:a", 100).size(), 5u);
  EXPECT_TRUE(jobs().list_by_client("addr:nobody", 100).empty());
}

TEST_P(ServerContract, WatchReturnsAsSoonAsTheJobChanges) {
  JobRecord r = jobs().create(record("addr:a"), "s");
  std::thread changer([&] {
    std::this_thread::sleep_for(50ms);
    RenderStats st;
    st.spp_done = 3;
    jobs().update_progress(r.id, st);
  });
  auto start = Clock::now();
  auto seen = jobs().watch(r.id, r.version, Clock::now() + 10s);
  changer.join();
  ASSERT_TRUE(seen);
  EXPECT_GT(seen->version, r.version);
  EXPECT_EQ(seen->stats.spp_done, 3);
  EXPECT_LT(Clock::now() - start, 5s);
  // A version already passed: at once.
  start = Clock::now();
  EXPECT_TRUE(jobs().watch(r.id, 0, Clock::now() + 10s));
  EXPECT_LT(Clock::now() - start, 1s);
}

TEST_P(ServerContract, WatchReturnsTheUnchangedRecordAtTheDeadline) {
  JobRecord r = jobs().create(record("addr:a"), "s");
  auto start = Clock::now();
  auto seen = jobs().watch(r.id, r.version, Clock::now() + 100ms);
  EXPECT_GE(Clock::now() - start, 100ms);
  ASSERT_TRUE(seen);
  EXPECT_EQ(seen->version, r.version);
  EXPECT_FALSE(jobs().watch("0123456789abcdef0123456789abcdef", 0, Clock::now() + 10ms));
}

TEST_P(ServerContract, UpdateProgressStopsAtAFinalState) {
  JobRecord r = jobs().create(record("addr:a"), "s");
  EXPECT_TRUE(jobs().update_progress(r.id, RenderStats{}));
  ASSERT_TRUE(jobs().transition(r.id, {JobState::queued},
                                [](JobRecord& x) { x.state = JobState::done; }));
  const auto before = jobs().get(r.id)->version;
  EXPECT_FALSE(jobs().update_progress(r.id, RenderStats{}));
  EXPECT_EQ(jobs().get(r.id)->version, before);
}

TEST_P(ServerContract, RequestCancelMarksAnUnfinishedJobAndLeavesAFinalOneAlone) {
  JobRecord a = jobs().create(record("addr:a"), "s");
  auto marked = jobs().request_cancel(a.id);
  ASSERT_TRUE(marked);
  EXPECT_TRUE(marked->cancel_requested);
  EXPECT_GT(marked->version, a.version);
  EXPECT_EQ(marked->state, JobState::queued);  // stopping it is the renderer's move

  JobRecord b = jobs().create(record("addr:a"), "s");
  ASSERT_TRUE(jobs().transition(b.id, {JobState::queued},
                                [](JobRecord& x) { x.state = JobState::done; }));
  auto done = jobs().request_cancel(b.id);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->state, JobState::done);
  EXPECT_FALSE(done->cancel_requested);
  EXPECT_FALSE(jobs().request_cancel("0123456789abcdef0123456789abcdef"));
}

TEST_P(ServerContract, ExpireRemovesOnlyFinalJobsFinishedBeforeTheCutoff) {
  auto finish = [&](const std::string& id, long long at) {
    ASSERT_TRUE(jobs().transition(id, {JobState::queued}, [at](JobRecord& x) {
      x.state = JobState::done;
      x.finished_ms = at;
    }));
  };
  JobRecord old_done = jobs().create(record("addr:a", 1), "s");
  JobRecord new_done = jobs().create(record("addr:a", 2), "s");
  JobRecord queued = jobs().create(record("addr:a", 3), "s");
  finish(old_done.id, 5'000);
  finish(new_done.id, 20'000);
  // The clock is the argument: no sleeping.
  auto gone = jobs().expire(10'000);
  ASSERT_EQ(gone.size(), 1u);
  EXPECT_EQ(gone[0].id, old_done.id);
  EXPECT_FALSE(jobs().get(old_done.id));
  EXPECT_TRUE(jobs().get(new_done.id));
  EXPECT_TRUE(jobs().get(queued.id));
  EXPECT_FALSE(blobs().has(BlobKind::scene, old_done.id));
  EXPECT_TRUE(jobs().expire(10'000).empty());
}

TEST_P(ServerContract, IdempotencyKeysArePerClient) {
  JobRecord r = record("addr:a");
  r.idempotency_key = "k1";
  r.request_digest = "d";
  jobs().create(r, "s");
  auto found = jobs().find_by_key("addr:a", "k1");
  ASSERT_TRUE(found);
  EXPECT_EQ(found->id, r.id);
  EXPECT_FALSE(jobs().find_by_key("addr:b", "k1"));
  EXPECT_FALSE(jobs().find_by_key("addr:a", "k2"));
  EXPECT_FALSE(jobs().find_by_key("addr:a", ""));
}

TEST_P(ServerContract, RecordsAndScenesOutliveTheInstance) {
  if (!GetParam().durable) GTEST_SKIP() << "keeps nothing past its instance";
  JobRecord r = record("addr:a");
  r.idempotency_key = "key";
  r.request_digest = "digest";
  r.options.spp = 7;
  r.textures = {"aa", "bb"};
  JobRecord made = jobs().create(r, "the scene");
  ASSERT_TRUE(jobs().transition(r.id, {JobState::queued}, [](JobRecord& x) {
    x.state = JobState::running;
    x.attempts = 2;
  }));
  b_ = {};
  b_ = GetParam().make(place_);
  auto back = jobs().get(r.id);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->state, JobState::running);
  EXPECT_EQ(back->attempts, 2);
  EXPECT_EQ(back->options.spp, 7);
  EXPECT_EQ(back->textures, r.textures);
  EXPECT_EQ(back->idempotency_key, "key");
  EXPECT_EQ(back->request_digest, "digest");
  EXPECT_EQ(blobs().get(BlobKind::scene, r.id).value_or(""), "the scene");
}

// --- WorkQueue ---

TEST_P(ServerContract, ClientsTakeTurnsAndAClientsJobsKeepTheirOrder) {
  queue().enqueue(item("a1", "A"));
  queue().enqueue(item("a2", "A"));
  queue().enqueue(item("a3", "A"));
  queue().enqueue(item("b1", "B"));
  queue().enqueue(item("c1", "C"));
  queue().enqueue(item("b2", "B"));
  EXPECT_EQ(claim_all(), (std::vector<std::string>{"a1", "b1", "c1", "a2", "b2", "a3"}));
}

TEST_P(ServerContract, AHigherPriorityBeatsArrivalStrictly) {
  queue().enqueue(item("n1", "A", Priority::normal));
  queue().enqueue(item("b1", "B", Priority::batch));
  queue().enqueue(item("n2", "B", Priority::normal));
  queue().enqueue(item("i1", "C", Priority::interactive));
  queue().enqueue(item("i2", "A", Priority::interactive));
  EXPECT_EQ(claim_all(), (std::vector<std::string>{"i1", "i2", "n1", "n2", "b1"}));
}

TEST_P(ServerContract, PositionDepthActiveAndJobsOfFollowTheClaims) {
  queue().enqueue(item("a1", "A"));
  queue().enqueue(item("a2", "A"));
  queue().enqueue(item("b1", "B"));
  queue().enqueue(item("x1", "X", Priority::interactive));
  EXPECT_EQ(queue().position("x1"), 1);
  EXPECT_EQ(queue().position("a1"), 2);
  EXPECT_EQ(queue().position("b1"), 3);
  EXPECT_EQ(queue().position("a2"), 4);
  EXPECT_EQ(queue().position("nope"), 0);
  EXPECT_EQ(queue().depth(), 4u);
  EXPECT_EQ(queue().active(), 0u);
  EXPECT_EQ(queue().jobs_of("A"), 2u);

  ASSERT_EQ(queue().claim("node", 4)->id, "x1");
  ASSERT_EQ(queue().claim("node", 4)->id, "a1");
  EXPECT_EQ(queue().position("a1"), 0);  // started
  EXPECT_EQ(queue().position("b1"), 1);
  EXPECT_EQ(queue().depth(), 2u);
  EXPECT_EQ(queue().active(), 2u);
  EXPECT_EQ(queue().jobs_of("A"), 2u);  // one running, one queued
  queue().complete("a1");
  EXPECT_EQ(queue().active(), 1u);
  EXPECT_EQ(queue().jobs_of("A"), 1u);
  EXPECT_EQ(queue().jobs_of("nobody"), 0u);
}

TEST_P(ServerContract, AClientAtItsActiveLimitWaitsWhileOthersStart) {
  queue().enqueue(item("a1", "A"));
  queue().enqueue(item("a2", "A"));
  queue().enqueue(item("b1", "B"));
  ASSERT_EQ(queue().claim("node", 1)->id, "a1");
  ASSERT_EQ(queue().claim("node", 1)->id, "b1");
  EXPECT_FALSE(queue().claim("node", 1));  // a2 waits for a1
  queue().complete("a1");
  ASSERT_EQ(queue().claim("node", 1)->id, "a2");
}

TEST_P(ServerContract, RemoveTakesOutOnlyQueuedJobsAndReleaseRequeuesFirst) {
  queue().enqueue(item("a1", "A"));
  queue().enqueue(item("a2", "A"));
  queue().enqueue(item("a3", "A"));
  EXPECT_TRUE(queue().remove("a2"));
  EXPECT_FALSE(queue().remove("a2"));
  ASSERT_EQ(queue().claim("node", 4)->id, "a1");
  EXPECT_FALSE(queue().remove("a1"));  // active: the renderer stops it
  queue().release("a1");
  EXPECT_EQ(queue().active(), 0u);
  EXPECT_EQ(claim_all(), (std::vector<std::string>{"a1", "a3"}));
}

// --- BlobStore ---

TEST_P(ServerContract, BlobsArePutGotAndRemovedByKindAndName) {
  if (!blobs().durable()) GTEST_SKIP() << "memory mode keeps no blobs";
  blobs().put(BlobKind::image, "abc", "png bytes");
  blobs().put(BlobKind::texture, "abc", "texture bytes");
  EXPECT_EQ(blobs().get(BlobKind::image, "abc").value_or(""), "png bytes");
  EXPECT_EQ(blobs().get(BlobKind::texture, "abc").value_or(""), "texture bytes");
  EXPECT_FALSE(blobs().has(BlobKind::scene, "abc"));
  EXPECT_EQ(blobs().names(BlobKind::texture), (std::vector<std::string>{"abc"}));
  blobs().remove(BlobKind::image, "abc");
  EXPECT_FALSE(blobs().get(BlobKind::image, "abc"));
  EXPECT_TRUE(blobs().has(BlobKind::texture, "abc"));
  // Names that could leave the store are neither stored nor found.
  blobs().put(BlobKind::image, "../evil", "x");
  EXPECT_FALSE(blobs().has(BlobKind::image, "../evil"));
  EXPECT_TRUE(blobs().names(BlobKind::image).empty());
}

TEST_P(ServerContract, OldestFirstListsImagesInWritingOrderWithTheirSizes) {
  if (!blobs().durable()) GTEST_SKIP() << "memory mode keeps no blobs";
  blobs().put(BlobKind::image, "second", "22");
  std::this_thread::sleep_for(30ms);  // file times have a resolution
  blobs().put(BlobKind::image, "first", "1");
  std::this_thread::sleep_for(30ms);
  blobs().put(BlobKind::image, "third", "333");
  auto items = blobs().oldest_first(BlobKind::image);
  ASSERT_EQ(items.size(), 3u);
  EXPECT_EQ(items[0], (std::pair<std::string, std::uintmax_t>{"second", 2}));
  EXPECT_EQ(items[1], (std::pair<std::string, std::uintmax_t>{"first", 1}));
  EXPECT_EQ(items[2], (std::pair<std::string, std::uintmax_t>{"third", 3}));
}

INSTANTIATE_TEST_SUITE_P(ServerBackends, ServerContract, ::testing::ValuesIn(backends_under_test()),
                         [](const auto& test) { return test.param.name; });

}  // namespace
}  // namespace rayfarm::server
