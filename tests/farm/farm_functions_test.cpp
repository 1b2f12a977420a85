// The rayfarm1 Function library through FarmClient, against a real redis-server: fair feeding,
// limits, idempotence, leases, reclaim and the poison cap, cancel, finish and record.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "farm_fixture.h"

namespace rayfarm::farm::test {
namespace {

using namespace std::chrono_literals;
using FarmFunctions = FarmTest;

std::string label(const Unit& u) { return u.job + ":" + std::to_string(u.index); }

// Takes units one at a time (completing each) and lists them as "job:unit".
std::string drain(TestNode& n, int max = 100) {
  std::string order;
  for (int i = 0; i < max; ++i) {
    auto u = n->take();
    EXPECT_TRUE(u) << u.error().message;
    if (!u || !*u) break;
    order += (order.empty() ? "" : " ") + label(**u);
    EXPECT_TRUE(n->complete(**u, "px"));
  }
  return order;
}

TEST_F(FarmFunctions, FeedsClientsRoundRobinThenTheirJobs) {
  TestNode n = node("n1");
  submit(n, "a1", "A", 4);
  submit(n, "a2", "A", 2);
  submit(n, "b1", "B", 2);
  // A's jobs start in the order A sent them (a2 after a1's next turn), then take turns.
  EXPECT_EQ(drain(n), "a1:0 b1:0 a1:1 b1:1 a2:0 a1:2 a2:1 a1:3");
}

TEST_F(FarmFunctions, PriorityBeatsArrivalOnceFed) {
  TestNode n = node("n1");
  submit(n, "b", "C", 3, Priority::Batch);  // b:0 is fed at once (target 1)
  submit(n, "n", "A", 2, Priority::Normal);
  submit(n, "i", "B", 2, Priority::Interactive);
  EXPECT_EQ(drain(n), "b:0 i:0 i:1 n:0 n:1 b:1 b:2");
}

TEST_F(FarmFunctions, LimitsActiveJobsPerClientAndJobsFarmWide) {
  TestNode n = node("n1");
  SubmitRequest q;
  q.client = "A";
  q.max_active_per_client = 2;
  for (const char* job : {"j1", "j2"}) {
    q.job = job;
    EXPECT_EQ(n->submit(q)->status, SubmitStatus::Accepted);
  }
  q.job = "j3";
  EXPECT_EQ(n->submit(q)->status, SubmitStatus::ClientLimit);
  EXPECT_EQ(n->cancel("j1", "A")->status, CancelStatus::Canceled);
  EXPECT_EQ(n->submit(q)->status, SubmitStatus::Accepted);
  q.client = "B";
  q.job = "k1";
  q.max_jobs = 2;
  EXPECT_EQ(n->submit(q)->status, SubmitStatus::Full);
}

TEST_F(FarmFunctions, SubmitIsIdempotentByJobIdAndByIdempotencyKey) {
  TestNode n = node("n1");
  SubmitRequest q;
  q.job = "j1";
  q.client = "A";
  q.units = 2;
  q.idempotency_key = "key-1";
  EXPECT_EQ(n->submit(q)->status, SubmitStatus::Accepted);
  EXPECT_EQ(n->submit(q)->status, SubmitStatus::Exists);  // a retry after a timeout
  q.job = "j2";  // a retried POST gets a new job id from its node; the key maps it back
  auto again = n->submit(q);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, SubmitStatus::Exists);
  EXPECT_EQ(again->job, "j1");
  EXPECT_FALSE(*n->job("j2"));
  EXPECT_EQ(hget("client:A", "active"), "1");
  EXPECT_EQ((*n->job("j1"))->at("units"), "2");
  EXPECT_EQ(drain(n), "j1:0 j1:1");
}

// Keys of different clients never meet, whatever ':' their names hold; and a key whose job
// has expired is free again (a replay then submits anew, not a 503 until the key expires).
TEST_F(FarmFunctions, IdempotencyKeysOfClientsNeverMeetAndOutliveNoJob) {
  TestNode n = node("n1");
  SubmitRequest q;
  q.job = "bobs";
  q.client = "name:bob";
  q.idempotency_key = "x:K";
  EXPECT_EQ(n->submit(q)->status, SubmitStatus::Accepted);
  q.job = "other";
  q.client = "name:bob:x";
  q.idempotency_key = "K";
  auto other = n->submit(q);
  ASSERT_TRUE(other);
  EXPECT_EQ(other->status, SubmitStatus::Accepted);
  EXPECT_TRUE(*n->job("other"));

  // The first job expires (its record is gone): its key gives a new job, not the old one.
  EXPECT_EQ(integer({"DEL", prefix_ + "job:bobs"}), 1);
  q.job = "bobs2";
  q.client = "name:bob";
  q.idempotency_key = "x:K";
  auto replay = n->submit(q);
  ASSERT_TRUE(replay);
  EXPECT_EQ(replay->status, SubmitStatus::Accepted);
  EXPECT_TRUE(*n->job("bobs2"));
  q.job = "bobs3";
  EXPECT_EQ(n->submit(q)->job, "bobs2");  // and the key now maps to it
}

// A client's list of jobs keeps its newest 1,000: the jobs expire, their IDs there would
// not, and a term of submissions must not grow Redis without end.
TEST_F(FarmFunctions, AClientsJobListKeepsItsNewestThousand) {
  TestNode n = node("n1");
  // 1,005 older jobs, a millisecond apart, then one more recorded now.
  for (int i = 0; i < 1005; ++i)
    EXPECT_EQ(integer({"ZADD", prefix_ + "cjobs:A", std::to_string(1000 + i),
                       "j" + std::to_string(i)}),
              1);
  RecordRequest r;
  r.job = "now";
  r.client = "A";
  r.state = EndState::Done;
  r.result = "img";
  ASSERT_TRUE(n->record(r));
  EXPECT_EQ(integer({"ZCARD", prefix_ + "cjobs:A"}), 1000);
  auto rank = [&](const std::string& job) {
    auto z = raw().command({"ZRANK", prefix_ + "cjobs:A", job});
    EXPECT_TRUE(z);
    return z && !z->is_nil() ? z->integer() : -1;
  };
  EXPECT_EQ(rank("now"), 999);
  EXPECT_EQ(rank("j1004"), 998);
  EXPECT_EQ(rank("j6"), 0);
  EXPECT_EQ(rank("j5"), -1);  // the six oldest went
  EXPECT_EQ(rank("j0"), -1);
}

TEST_F(FarmFunctions, FirstResultWinsAndALateCopyIsADuplicate) {
  TestNode n = node("n1");
  submit(n, "j", "A", 2);
  auto u = n->take();
  ASSERT_TRUE(u && *u);
  EXPECT_EQ(*n->complete(**u, "first"), CompleteStatus::Stored);
  EXPECT_EQ(*n->complete(**u, "second"), CompleteStatus::Duplicate);
  auto tiles = n->tiles("j", 2);
  ASSERT_TRUE(tiles);
  EXPECT_EQ((*tiles)[0], "first");
  EXPECT_FALSE((*tiles)[1]);
}

TEST_F(FarmFunctions, TheAssemblerIsToldAgainOnARepeatAndOthersAreDropped) {
  TestNode n1 = node("n1"), n2 = node("n2");
  submit(n1, "j", "A", 1);
  auto u = n1->take();
  ASSERT_TRUE(u && *u);
  EXPECT_EQ(*n1->complete(**u, "px"), CompleteStatus::Assemble);
  EXPECT_EQ(*n1->complete(**u, "px"), CompleteStatus::Assemble);
  EXPECT_EQ(*n2->complete(**u, "px"), CompleteStatus::Dropped);
}

TEST_F(FarmFunctions, ACompletionAfterCancelIsDroppedAndNothingStays) {
  TestNode n = node("n1", 3);
  submit(n, "j", "A", 5);
  auto u = n->take();
  ASSERT_TRUE(u && *u);
  auto c = n->cancel("j", "A");
  ASSERT_TRUE(c);
  EXPECT_EQ(c->status, CancelStatus::Canceled);
  EXPECT_EQ(*n->complete(**u, "px"), CompleteStatus::Dropped);
  EXPECT_EQ(integer({"EXISTS", prefix_ + "tiles:j"}), 0);
  auto next = n->take();  // the canceled job's fed units are skipped (acked and deleted)
  ASSERT_TRUE(next);
  EXPECT_FALSE(*next);
  EXPECT_EQ(stream_length(), 0);
  EXPECT_EQ(pending(), 0);
  EXPECT_EQ((*n->job("j"))->at("state"), "canceled");
}

TEST_F(FarmFunctions, CancelChecksTheOwnerAndIsIdempotent) {
  TestNode n = node("n1");
  submit(n, "j", "A", 2);
  EXPECT_EQ(n->cancel("j", "B")->status, CancelStatus::Forbidden);
  EXPECT_EQ(n->cancel("nope", "A")->status, CancelStatus::NotFound);
  EXPECT_EQ(n->cancel("j", "A")->status, CancelStatus::Canceled);
  auto again = n->cancel("j", "A");
  EXPECT_EQ(again->status, CancelStatus::AlreadyEnded);
  EXPECT_EQ(again->state, "canceled");
  EXPECT_EQ(hget("client:A", "active"), "0");
}

TEST_F(FarmFunctions, CancelIsPublishedOnTheCancelChannel) {
  TestNode n = node("n1");
  submit(n, "j", "A", 2);
  Connection sub(server_->options());
  ASSERT_TRUE(sub.command({"SUBSCRIBE", prefix_ + "cancel"}));
  ASSERT_TRUE(n->cancel("j", "A"));
  auto msg = sub.command({"PING"});  // in subscribed mode the reply queue holds the message first
  ASSERT_TRUE(msg) << msg.error().message;
  ASSERT_EQ(msg->size(), 3u);
  EXPECT_EQ((*msg)[0].str(), "message");
  EXPECT_EQ((*msg)[2].str(), "j");
}

long long idle_ms(Connection& c, const std::string& stream, const std::string& id,
                  long long* deliveries) {
  auto r = c.command({"XPENDING", stream, "render", "IDLE", "0", id, id, "1"});
  if (!r || r->size() != 1) return -1;
  *deliveries = (*r)[0][3].integer();
  return (*r)[0][2].integer();
}

TEST_F(FarmFunctions, HeartbeatRenewsTheLeaseAndReportsItsLoss) {
  TestNode n = node("n1");
  submit(n, "j", "A", 2);
  auto u = n->take();
  ASSERT_TRUE(u && *u);
  std::this_thread::sleep_for(120ms);
  long long deliveries = 0;
  EXPECT_GE(idle_ms(raw(), prefix_ + "work", (*u)->entry, &deliveries), 100);
  auto lost = n->heartbeat("{}", 3000ms, {(*u)->entry});
  ASSERT_TRUE(lost) << lost.error().message;
  EXPECT_TRUE(lost->empty());
  EXPECT_LT(idle_ms(raw(), prefix_ + "work", (*u)->entry, &deliveries), 100);
  EXPECT_EQ(deliveries, 1);  // JUSTID: a renewal is not a delivery
  EXPECT_EQ(integer({"EXISTS", prefix_ + "node:n1"}), 1);

  // A janitor of a shorter lease waits for a live node's renewal (its heartbeat's 3 s): nodes
  // started with other --heartbeat-ms lose no unit while they live.
  std::this_thread::sleep_for(60ms);
  auto kept = n->reclaim("janitor", 50ms);
  ASSERT_TRUE(kept) << kept.error().message;
  EXPECT_EQ(kept->requeued, 0);
  // Once the node is gone, its unit goes back after the janitor's own lease.
  ASSERT_TRUE(raw().command({"DEL", prefix_ + "node:n1"}));
  auto r = n->reclaim("janitor", 50ms);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->requeued, 1);
  lost = n->heartbeat("{}", 3000ms, {(*u)->entry});
  ASSERT_TRUE(lost);
  EXPECT_EQ(*lost, std::vector<std::string>{(*u)->entry});
}

TEST_F(FarmFunctions, AUnitAbandonedThreeTimesFailsItsJobNamingTheUnit) {
  TestNode n = node("n1");
  submit(n, "j", "A", 1);
  for (int expected_try = 0; expected_try < 3; ++expected_try) {
    auto u = n->take();
    ASSERT_TRUE(u && *u);
    EXPECT_EQ((*u)->tries, expected_try);
    std::this_thread::sleep_for(30ms);
    auto r = n->reclaim("janitor", 20ms);
    ASSERT_TRUE(r) << r.error().message;
    EXPECT_EQ(r->requeued, expected_try < 2 ? 1 : 0);
    EXPECT_EQ(r->failed, expected_try < 2 ? 0 : 1);
  }
  auto job = *n->job("j");
  EXPECT_EQ(job->at("state"), "failed");
  EXPECT_EQ(job->at("error"),
            "unit 0 was abandoned 3 times: a node died or stalled on it each time");
  EXPECT_EQ(stream_length(), 0);
  EXPECT_EQ(pending(), 0);
  EXPECT_EQ(hget("client:A", "active"), "0");
}

TEST_F(FarmFunctions, ARenderFailureCountsATryAndTheThirdFailsTheJob) {
  TestNode n = node("n1");
  submit(n, "j", "A", 2);
  for (int i = 0; i < 3; ++i) {
    auto u = n->take();
    ASSERT_TRUE(u && *u);
    if ((*u)->index == 1) {  // finish unit 1 normally, then go on with unit 0
      EXPECT_TRUE(n->complete(**u, "px"));
      u = n->take();
      ASSERT_TRUE(u && *u);
    }
    EXPECT_EQ((*u)->index, 0);
    EXPECT_EQ((*u)->tries, i);
    auto f = n->fail(**u, "out of memory");
    ASSERT_TRUE(f) << f.error().message;
    EXPECT_EQ(*f, i < 2 ? FailStatus::Requeued : FailStatus::JobFailed);
    EXPECT_EQ(*n->fail(**u, "out of memory"), FailStatus::Gone);  // a repeat is harmless
  }
  auto job = *n->job("j");
  EXPECT_EQ(job->at("state"), "failed");
  EXPECT_EQ(job->at("error"), "unit 0 failed 3 times; the last time on n1: out of memory");
  EXPECT_EQ(stream_length(), 0);
  EXPECT_EQ(pending(), 0);
}

TEST_F(FarmFunctions, ReleaseRequeuesAtOnceWithTheSameTry) {
  TestNode n1 = node("n1"), n2 = node("n2");
  submit(n1, "j", "A", 1);
  auto u = n1->take();
  ASSERT_TRUE(u && *u);
  EXPECT_EQ(*n1->release(**u), ReleaseStatus::Requeued);
  EXPECT_EQ(*n1->release(**u), ReleaseStatus::Gone);
  auto again = n2->take();
  ASSERT_TRUE(again && *again);
  EXPECT_EQ((*again)->index, 0);
  EXPECT_EQ((*again)->tries, 0);
  EXPECT_NE((*again)->entry, (*u)->entry);
}

TEST_F(FarmFunctions, AnEntryWhoseTakeReplyWasLostCanBeFoundAndReleased) {
  TestNode n = node("n1");
  submit(n, "j", "A", 1);
  auto lost = n->take();  // as if the reply never arrived
  ASSERT_TRUE(lost && *lost);
  auto held = n->held_entries();
  ASSERT_TRUE(held) << held.error().message;
  ASSERT_EQ(*held, std::vector<std::string>{(*lost)->entry});
  Unit u;
  u.entry = held->front();
  EXPECT_EQ(*n->release(u), ReleaseStatus::Requeued);
  auto again = n->take();
  ASSERT_TRUE(again && *again);
  EXPECT_EQ((*again)->tries, 0);
  EXPECT_EQ(n->held_entries()->size(), 1u);
}

TEST_F(FarmFunctions, FeedingNeverExceedsTheTarget) {
  TestNode n = node("n1", 3);
  submit(n, "a", "A", 10);
  submit(n, "b", "B", 10);
  EXPECT_EQ(stream_length() - pending(), 3);
  std::vector<Unit> held;
  for (int i = 0; i < 12; ++i) {
    auto u = n->take();
    ASSERT_TRUE(u && *u);
    held.push_back(**u);
    EXPECT_LE(stream_length() - pending(), 3);
  }
  for (const Unit& u : held) ASSERT_TRUE(n->complete(u, "px"));
  EXPECT_LE(stream_length(), 3);
}

TEST_F(FarmFunctions, AFinishedJobLeavesNothingInTheStream) {
  TestNode n = node("n1", 4);
  submit(n, "j", "A", 3);
  std::vector<Unit> held;
  for (int i = 0; i < 3; ++i) held.push_back(**n->take());
  EXPECT_EQ(*n->complete(held[0], "u0"), CompleteStatus::Stored);
  EXPECT_EQ(*n->complete(held[2], "u2"), CompleteStatus::Stored);
  EXPECT_EQ(*n->complete(held[1], "u1"), CompleteStatus::Assemble);
  EXPECT_EQ(stream_length(), 0);
  EXPECT_EQ(pending(), 0);
  auto tiles = n->tiles("j", 3, 2);
  ASSERT_TRUE(tiles);
  EXPECT_EQ(*tiles, (std::vector<std::optional<std::string>>{"u0", "u1", "u2"}));
  auto f = n->finish("j", "png:abc", {{"stats", "{}"}});
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_EQ(f->status, FinishStatus::Done);
  auto job = *n->job("j");
  EXPECT_EQ(job->at("state"), "done");
  EXPECT_EQ(job->at("result"), "png:abc");
  EXPECT_EQ(job->at("stats"), "{}");
  EXPECT_EQ(integer({"EXISTS", prefix_ + "tiles:j"}), 0);
  EXPECT_EQ(hget("client:A", "active"), "0");
  EXPECT_GT(integer({"PTTL", prefix_ + "job:j"}), 0);
}

TEST_F(FarmFunctions, FinishOnlyFromAssembling) {
  TestNode n = node("n1");
  submit(n, "j", "A", 1);
  auto f = n->finish("j", "png:x");
  EXPECT_EQ(f->status, FinishStatus::NotAssembling);
  EXPECT_EQ(f->state, "running");                              // its unit was fed at submission
  EXPECT_FALSE(n->finish("j", "png:x", {{"state", "done"}}));  // the farm's own fields
  auto u = n->take();
  EXPECT_EQ(*n->complete(**u, "px"), CompleteStatus::Assemble);
  EXPECT_EQ(n->finish("j", "png:x")->status, FinishStatus::Done);
  EXPECT_EQ(n->finish("j", "png:x")->status, FinishStatus::AlreadyDone);
  submit(n, "k", "A", 1);
  ASSERT_TRUE(n->cancel("k", "A"));
  f = n->finish("k", "png:y");
  EXPECT_EQ(f->status, FinishStatus::NotAssembling);
  EXPECT_EQ(f->state, "canceled");
}

TEST_F(FarmFunctions, ALocalJobCountsAgainstTheLimitUntilRecorded) {
  TestNode n = node("n1");
  SubmitRequest q;
  q.job = "small";
  q.client = "A";
  q.units = 0;
  q.max_active_per_client = 1;
  EXPECT_EQ(n->submit(q)->status, SubmitStatus::Accepted);
  EXPECT_EQ((*n->job("small"))->at("state"), "running");
  EXPECT_FALSE(*n->take());  // never fed
  q.job = "other";
  EXPECT_EQ(n->submit(q)->status, SubmitStatus::ClientLimit);
  RecordRequest r;
  r.job = "small";
  r.client = "A";
  r.result = "png:s";
  r.fields = {{"stats", "{\"rays\":1}"}};
  EXPECT_EQ(*n->record(r), RecordStatus::Recorded);
  EXPECT_EQ(*n->record(r), RecordStatus::Exists);
  auto job = *n->job("small");
  EXPECT_EQ(job->at("state"), "done");
  EXPECT_EQ(job->at("result"), "png:s");
  EXPECT_EQ(n->submit(q)->status, SubmitStatus::Accepted);
  r.job = "never-submitted";
  EXPECT_EQ(*n->record(r), RecordStatus::Recorded);
  EXPECT_EQ((*n->job("never-submitted"))->at("state"), "done");
  r.client = "B";
  EXPECT_EQ(*n->record(r), RecordStatus::Forbidden);
}

// Client A's job rendered by `node` alone (units 0), as a farm node submits one.
SubmitRequest local_job(const std::string& job, const std::string& node) {
  SubmitRequest q;
  q.client = "A";
  q.units = 0;
  q.job = job;
  q.fields = {{"node", node}};
  return q;
}

// Only the node rendering a local job writes its progress, and only while it runs.
TEST_F(FarmFunctions, ALocalJobsProgressIsItsNodesWhileItRuns) {
  TestNode n = node("n1"), other = node("n2");
  SubmitRequest q = local_job("mine", "n1");
  ASSERT_EQ(n->submit(q)->status, SubmitStatus::Accepted);
  EXPECT_EQ(*n->progress("mine", 420), true);
  EXPECT_EQ(hget("job:mine", "permille"), "420");
  EXPECT_EQ(*other->progress("mine", 10), false);  // not n2's job
  EXPECT_EQ(*n->progress("nobody", 10), false);    // no such job: no record made
  EXPECT_EQ(hget("job:nobody", "state"), "");
  q.job = "spread";
  q.units = 4;
  ASSERT_EQ(n->submit(q)->status, SubmitStatus::Accepted);
  EXPECT_EQ(*n->progress("spread", 10), false);  // the farm's own units count for it
  RecordRequest r;
  r.job = "mine";
  r.client = "A";
  r.result = "png:m";
  ASSERT_EQ(*n->record(r), RecordStatus::Recorded);
  EXPECT_EQ(*n->progress("mine", 999), false);  // ended: a late heartbeat changes nothing
  EXPECT_EQ(hget("job:mine", "permille"), "420");
}

TEST_F(FarmFunctions, TheSweepFailsALocalJobWhoseNodeIsGone) {
  TestNode n = node("n1");
  SubmitRequest q = local_job("mine", "n1");
  ASSERT_EQ(n->submit(q)->status, SubmitStatus::Accepted);
  q.job = "lost";
  q.fields = {{"node", "ghost"}};
  ASSERT_EQ(n->submit(q)->status, SubmitStatus::Accepted);
  ASSERT_TRUE(n->heartbeat("{}", 10s, {}));  // n1 is alive; ghost never was
  // Not before a lease has passed since the job started.
  auto early = n->sweep("n1", 10s);
  ASSERT_TRUE(early) << early.error().message;
  EXPECT_EQ(early->orphaned, 0);
  std::this_thread::sleep_for(60ms);
  auto r = n->sweep("n1", 50ms);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->orphaned, 1);
  EXPECT_EQ(hget("job:lost", "state"), "failed");
  EXPECT_EQ(hget("job:lost", "code"), "node_lost");
  EXPECT_NE(hget("job:lost", "error").find("ghost"), std::string::npos);
  EXPECT_EQ(hget("job:mine", "state"), "running");
  EXPECT_EQ(hget("client:A", "active"), "1");
}

// Each job carries the limit of the node that accepted it; the janitor ends it by that
// limit, whatever its own, counted from when the job started running (not its wait in the
// queue).
TEST_F(FarmFunctions, TheSweepFailsAJobPastItsOwnLimitAndStopsItsUnits) {
  TestNode n = node("n1", 8);  // all three jobs fed, so all running
  auto submit_with = [&](const std::string& job, std::chrono::milliseconds limit) {
    SubmitRequest q;
    q.job = job;
    q.client = job;
    q.units = 3;
    q.timeout = limit;
    ASSERT_EQ(n->submit(q)->status, SubmitStatus::Accepted);
  };
  submit_with("short", 1s);
  submit_with("long", 10s);
  submit_with("none", 0ms);
  EXPECT_EQ(hget("job:short", "timeout_ms"), "1000");
  auto u = n->take();  // the jobs run from their first fed unit on
  ASSERT_TRUE(u && *u);
  ASSERT_EQ((*u)->job, "short");  // the first client's first unit
  Connection sub(server_->options());
  ASSERT_TRUE(sub.command({"SUBSCRIBE", prefix_ + "cancel"}));
  auto none = n->sweep("n1", 10s);
  ASSERT_TRUE(none);
  EXPECT_EQ(none->timed_out, 0);
  std::this_thread::sleep_for(1100ms);
  auto r = n->sweep("n1", 10s);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->timed_out, 1);
  EXPECT_EQ(hget("job:short", "state"), "failed");
  EXPECT_EQ(hget("job:short", "code"), "timeout");
  EXPECT_NE(hget("job:short", "error").find("limit of 1 s"), std::string::npos)
      << hget("job:short", "error");
  EXPECT_EQ(hget("job:long", "state"), "running");
  EXPECT_EQ(hget("job:none", "state"), "running");
  auto msg = sub.next_message(1s);
  ASSERT_TRUE(msg && *msg);
  ASSERT_EQ((*msg)->size(), 3u);
  EXPECT_EQ((**msg)[2].str(), "short");
  EXPECT_EQ(*n->complete(**u, "px"), CompleteStatus::Dropped);
}

TEST_F(FarmFunctions, AJobsLimitCountsFromItsStartNotItsWaitInTheQueue) {
  TestNode n = node("n1");  // feeds one unit ahead
  submit(n, "first", "A", 1);
  SubmitRequest q;
  q.job = "waiting";
  q.client = "B";
  q.units = 1;
  q.timeout = 1s;
  ASSERT_EQ(n->submit(q)->status, SubmitStatus::Accepted);
  std::this_thread::sleep_for(1100ms);
  ASSERT_EQ(n->sweep("n1", 10s)->timed_out, 0);
  EXPECT_EQ(hget("job:waiting", "state"), "queued");
  auto u = n->take();  // first's unit; "waiting" is fed behind it and starts now
  ASSERT_TRUE(u && *u);
  EXPECT_EQ((*u)->job, "first");
  EXPECT_EQ(hget("job:waiting", "state"), "running");
  ASSERT_EQ(n->sweep("n1", 10s)->timed_out, 0);
  std::this_thread::sleep_for(1100ms);
  ASSERT_EQ(n->sweep("n1", 10s)->timed_out, 1);
  EXPECT_EQ(hget("job:waiting", "code"), "timeout");
  EXPECT_EQ(hget("job:first", "state"), "running");
}

// The figures /metrics and /healthz show for the whole farm: jobs by state and the nodes
// whose heartbeat is current (a node whose key expired is not counted).
TEST_F(FarmFunctions, CountsTheFarmsJobsByStateAndItsLiveNodes) {
  TestNode n = node("n1");  // feeds one unit ahead
  auto zero = n->counts();
  ASSERT_TRUE(zero) << zero.error().message;
  EXPECT_EQ(zero->queued + zero->running + zero->assembling + zero->nodes, 0);
  submit(n, "a", "A", 1);
  submit(n, "b", "B", 1);
  ASSERT_TRUE(n->heartbeat("{}", 10s, {}));
  TestNode gone = node("gone");
  ASSERT_TRUE(gone->heartbeat("{}", 50ms, {}));
  auto u = n->take();
  ASSERT_TRUE(u && *u);
  ASSERT_EQ(*n->complete(**u, "px"), CompleteStatus::Assemble);  // a: its only unit
  std::this_thread::sleep_for(100ms);  // gone's heartbeat key expires
  auto c = n->counts();
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->queued, 0);      // b was fed behind a
  EXPECT_EQ(c->running, 1);     // b
  EXPECT_EQ(c->assembling, 1);  // a
  EXPECT_EQ(c->nodes, 1);
}

TEST_F(FarmFunctions, TheSweepHandsAJobWhoseAssemblerIsGoneToTheJanitor) {
  TestNode n1 = node("n1"), n2 = node("n2");
  submit(n1, "j", "A", 1);
  auto u = n1->take();
  ASSERT_TRUE(u && *u);
  ASSERT_EQ(*n1->complete(**u, "px"), CompleteStatus::Assemble);  // n1 then dies
  ASSERT_TRUE(n2->heartbeat("{}", 10s, {}));
  std::this_thread::sleep_for(60ms);
  auto r = n2->sweep("n2", 50ms);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->assemble, std::vector<std::string>{"j"});
  EXPECT_EQ(hget("job:j", "assembler"), "n2");
  EXPECT_EQ(n2->sweep("n2", 50ms)->assemble.size(), 0u);  // a lease for n2 to do it
  ASSERT_TRUE(n2->finish("j", "png:j"));
  EXPECT_EQ(hget("job:j", "state"), "done");
  // A living assembler keeps the job for four leases.
  submit(n1, "k", "A", 1);
  auto v = n1->take();
  ASSERT_TRUE(v && *v);
  ASSERT_EQ(*n1->complete(**v, "px"), CompleteStatus::Assemble);
  ASSERT_TRUE(n1->heartbeat("{}", 10s, {}));
  std::this_thread::sleep_for(150ms);
  EXPECT_EQ(n2->sweep("n2", 100ms)->assemble.size(), 0u);
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(n2->sweep("n2", 100ms)->assemble, std::vector<std::string>{"k"});
}

TEST_F(FarmFunctions, BlockForWorkWakesOnASubmission) {
  TestNode n1 = node("n1"), n2 = node("n2");
  std::optional<Unit> got;
  std::thread waiter([&] {
    auto u = n2->block_for_work();
    if (u && *u) got = **u;
  });
  std::this_thread::sleep_for(100ms);
  submit(n1, "j", "A", 1);
  waiter.join();
  ASSERT_TRUE(got);
  EXPECT_EQ(label(*got), "j:0");
  EXPECT_EQ(got->opts, "{\"job\":\"j\"}");
}

TEST_F(FarmFunctions, AdoptSkipsAnEntryWhoseJobWasCanceled) {
  TestNode n = node("n1");
  submit(n, "gone", "A", 1);  // fed at once
  ASSERT_TRUE(n->cancel("gone", "A"));
  auto u = n->block_for_work();  // reads the stale entry, adopt acks and deletes it
  ASSERT_TRUE(u) << u.error().message;
  EXPECT_FALSE(*u);
  EXPECT_EQ(stream_length(), 0);
  EXPECT_EQ(pending(), 0);
}

TEST_F(FarmFunctions, ANodeOfAnotherBuildIsRefusedWhileANodeOfTheFarmsLives) {
  TestNode n = node("n1");
  Status joined = n.conn->connect();
  ASSERT_TRUE(joined) << joined.error().message;
  ASSERT_TRUE(n->heartbeat("{}", 1500ms, {}));  // alive for 1.5 s
  FarmConfig other = config("n2");
  other.build = "other-build";
  TestNode stranger = node(other);
  Status s = stranger.conn->connect();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().kind, ErrorKind::Build);
  EXPECT_NE(s.error().message.find("this farm runs build test-build"), std::string::npos);
  EXPECT_FALSE(stranger.conn->wait_connected(200ms));  // a setup error: no retry loop
  // While it waits for its next attempt, it says why it was refused, not "unavailable".
  Status again = stranger.conn->ensure_connected();
  ASSERT_FALSE(again);
  EXPECT_NE(again.error().message.find("refused this node: this farm runs build test-build"),
            std::string::npos)
      << again.error().message;
  // An upgrade: once no node of the farm's build is alive, the farm takes the new build, and
  // an old node coming back is the one refused.
  std::this_thread::sleep_for(1600ms);
  TestNode upgraded = node(other);
  Status now = upgraded.conn->connect();
  ASSERT_TRUE(now) << now.error().message;
  auto build = raw().command({"GET", prefix_ + "meta:build"});
  ASSERT_TRUE(build);
  EXPECT_EQ(std::string(build->str()), "other-build");
  ASSERT_TRUE(upgraded->heartbeat("{}", 10s, {}));
  n.conn->disconnect();
  Status old_node = n.conn->connect();
  ASSERT_FALSE(old_node);
  EXPECT_EQ(old_node.error().kind, ErrorKind::Build);
}

TEST_F(FarmFunctions, AReconnectNoticesALostEpoch) {
  TestNode n = node("n1");
  ASSERT_TRUE(n.conn->connect());
  const std::string epoch = n.setup->epoch();
  EXPECT_EQ(epoch.size(), 32u);
  n.conn->disconnect();
  ASSERT_TRUE(n.conn->connect());
  EXPECT_EQ(n.setup->epoch_changes(), 0);
  integer({"DEL", prefix_ + "meta:epoch"});  // as if Redis came back empty
  n.conn->disconnect();
  ASSERT_TRUE(n.conn->connect());
  EXPECT_EQ(n.setup->epoch_changes(), 1);
  EXPECT_NE(n.setup->epoch(), epoch);
}

TEST_F(FarmFunctions, OneNodeHoldsTheJanitorLock) {
  TestNode n1 = node("n1"), n2 = node("n2");
  EXPECT_TRUE(*n1->janitor_lock(2000ms));
  EXPECT_FALSE(*n2->janitor_lock(2000ms));
  EXPECT_TRUE(*n1->janitor_lock(2000ms));
}

TEST_F(FarmFunctions, ALostGroupIsRecreated) {
  TestNode n = node("n1");
  submit(n, "j", "A", 2);
  integer({"DEL", prefix_ + "work"});  // the stream and its group are gone
  auto u = n->take();
  ASSERT_TRUE(u) << u.error().message;
  ASSERT_TRUE(*u);
  EXPECT_EQ(label(**u), "j:1");  // unit 0's entry was lost with the stream: reclaim cannot see it
}

}  // namespace
}  // namespace rayfarm::farm::test
