// Connection, Reply and Pool against real redis-servers: binary safety, pipelining, error kinds
// (auth, ACL, OOM), backoff, and reconnecting after Redis is killed and restarted.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "farm_fixture.h"

namespace rayfarm::farm::test {
namespace {

using namespace std::chrono_literals;

class RedisConnection : public testing::Test {
 protected:
  void SetUp() override { RAYFARM_REQUIRE_REDIS_SERVER(); }
};

TEST_F(RedisConnection, PayloadsWithNulBytesRoundTrip) {
  RedisServer server;
  ASSERT_TRUE(server.start());
  Connection c(server.options());
  std::string payload("a\0b\r\n\0\xff", 7);
  for (int i = 0; i < 256; ++i) payload.push_back(static_cast<char>(i));
  ASSERT_TRUE(c.command({"SET", "k\0ey", payload}));
  auto r = c.command({"GET", "k\0ey"});
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_TRUE(r->string());
  EXPECT_EQ(*r->string(), payload);
  auto missing = c.command({"GET", "missing"});
  ASSERT_TRUE(missing);
  EXPECT_TRUE(missing->is_nil());
  EXPECT_FALSE(missing->string());
}

TEST_F(RedisConnection, UnitResultsWithNulBytesRoundTripThroughTheFunctions) {
  RedisServer server;
  ASSERT_TRUE(server.start());
  TestNode n = make_node(server, test_config("b:", "n1"));
  FarmClient& farm = *n.farm;
  SubmitRequest q;
  q.job = "j";
  q.client = "A";
  q.opts = std::string("o\0pts", 5);
  auto submitted = farm.submit(q);
  ASSERT_TRUE(submitted) << to_string(submitted.error().kind) << ": " << submitted.error().message;
  auto u = farm.take();
  ASSERT_TRUE(u && *u) << (u ? "none" : u.error().message);
  EXPECT_EQ((*u)->opts, q.opts);
  const std::string payload("RFU1\0\0\x01\x02", 8);
  EXPECT_EQ(*farm.complete(**u, payload), CompleteStatus::Assemble);
  EXPECT_EQ((*farm.tiles("j", 1))[0], payload);
}

TEST_F(RedisConnection, PipelinesManyCommandsAndKeepsPerCommandErrors) {
  RedisServer server;
  ASSERT_TRUE(server.start());
  Connection c(server.options());
  std::vector<std::vector<std::string>> cmds;
  for (int i = 0; i < 100; ++i) cmds.push_back({"INCR", "counter"});
  cmds.push_back({"LPUSH", "counter", "x"});  // WRONGTYPE, and the batch goes on
  cmds.push_back({"GET", "counter"});
  auto r = c.pipeline(cmds);
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_EQ(r->size(), 102u);
  EXPECT_EQ((*r)[99]->integer(), 100);
  EXPECT_FALSE((*r)[100]);
  EXPECT_EQ((*r)[100].error().kind, ErrorKind::Reply);
  EXPECT_EQ((*r)[101]->str(), "100");
}

TEST_F(RedisConnection, ATimeoutLeavesTheOutcomeUnknownAndTheNextCommandReconnects) {
  RedisServer server;
  ASSERT_TRUE(server.start());
  ConnectOptions o = server.options();
  o.command_timeout = 100ms;
  o.backoff_initial = 1ms;
  Connection c(o);
  auto r = c.command({"BLPOP", "nothing", "2"});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().kind, ErrorKind::Timeout) << r.error().message;
  EXPECT_TRUE(r.error().outcome_unknown());
  EXPECT_FALSE(c.connected());
  std::this_thread::sleep_for(5ms);
  EXPECT_TRUE(c.command({"PING"}));
  // A longer timeout for one blocking command, then the usual one again.
  const std::string_view blpop[] = {"BLPOP", "nothing", "0.3"};
  auto waited = c.command(blpop, 1000ms);
  ASSERT_TRUE(waited) << waited.error().message;
  EXPECT_TRUE(waited->is_nil());
  EXPECT_EQ(c.connects(), 2u);
}

// Redis's idle `timeout` (or a proxy dropping quiet connections) closes a pooled connection:
// that is seen before the next command is sent, so the caller can connect again at once.
TEST_F(RedisConnection, AnIdleConnectionRedisClosedIsSeenBeforeUse) {
  RedisServer server;
  ASSERT_TRUE(server.start());
  Connection admin(server.options());
  Connection c(server.options());
  ASSERT_TRUE(c.command({"PING"}));
  EXPECT_FALSE(c.closed_by_peer());
  ASSERT_TRUE(admin.command({"CLIENT", "KILL", "TYPE", "normal", "SKIPME", "yes"}));
  bool seen = false;
  for (int i = 0; i < 200 && !seen; ++i) {
    seen = c.closed_by_peer();
    if (!seen) std::this_thread::sleep_for(5ms);
  }
  EXPECT_TRUE(seen);
  c.disconnect();
  ASSERT_TRUE(c.connect());
  EXPECT_FALSE(c.closed_by_peer());
  EXPECT_TRUE(c.command({"PING"}));
}

TEST_F(RedisConnection, ANewConnectionWaitsForItsBackoffAndReportsUnavailable) {
  ConnectOptions o;
  o.url.transport = RedisUrl::Transport::Unix;
  o.url.path = "/tmp/rayfarm-no-such-redis.sock";
  o.backoff_initial = 10s;
  Connection c(o);
  auto first = c.command({"PING"});
  ASSERT_FALSE(first);
  EXPECT_EQ(first.error().kind, ErrorKind::Unavailable);
  auto second = c.command({"PING"});
  ASSERT_FALSE(second);
  EXPECT_NE(second.error().message.find("next attempt in"), std::string::npos);
}

TEST_F(RedisConnection, ReconnectsAfterRedisIsKilledAndRestartedAndLosesNoAcceptedJob) {
  RedisServer server;
  ASSERT_TRUE(server.start());
  TestNode n = make_node(server, test_config("r:", "n1"));
  FarmClient& farm = *n.farm;
  for (int i = 0; i < 50; ++i) {
    SubmitRequest q;
    q.job = "j" + std::to_string(i);
    q.client = "C" + std::to_string(i);
    q.units = 3;
    ASSERT_EQ(farm.submit(q)->status, SubmitStatus::Accepted);
  }
  const std::string epoch = n.setup->epoch();
  server.kill9();
  auto down = farm.job("j0");
  ASSERT_FALSE(down);
  EXPECT_TRUE(down.error().transient()) << down.error().message;
  ASSERT_TRUE(server.start());

  // The library survived in the AOF: a plain connection (no FUNCTION LOAD) can call it.
  Connection plain(server.options());
  auto lock = plain.command({"FCALL", "rf1_lock", "0", "r:", "x", "1000"});
  ASSERT_TRUE(lock) << lock.error().message;
  EXPECT_EQ(lock->integer(), 1);

  ASSERT_TRUE(n.conn->wait_connected(5s));
  EXPECT_EQ(n.conn->connects(), 2u);
  EXPECT_EQ(n.setup->epoch(), epoch);
  EXPECT_EQ(n.setup->epoch_changes(), 0);
  for (int i = 0; i < 50; ++i) {
    auto job = farm.job("j" + std::to_string(i));
    ASSERT_TRUE(job) << job.error().message;
    ASSERT_TRUE(*job) << "job " << i << " was lost";
  }
  auto u = farm.take();
  ASSERT_TRUE(u && *u);
}

TEST_F(RedisConnection, ApplesAuthAndSelectOnEveryConnect) {
  RedisServer server({"--requirepass", "s3cret"});
  ASSERT_TRUE(server.start());
  ConnectOptions none = server.options();
  Connection anonymous(none);
  auto r = anonymous.command({"PING"});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().kind, ErrorKind::Auth);

  ConnectOptions wrong = server.options();
  wrong.password = "nope";
  Status s = Connection(wrong).connect();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().kind, ErrorKind::Auth);

  ConnectOptions good = server.options();
  good.password = "s3cret";
  good.url.db = 3;
  Connection c(good);
  ASSERT_TRUE(c.command({"SET", "k", "v"}));
  c.disconnect();  // the next command reconnects: AUTH and SELECT again
  auto where = c.command({"CLIENT", "INFO"});
  ASSERT_TRUE(where) << where.error().message;
  EXPECT_NE(where->str().find(" db=3 "), std::string::npos);
  EXPECT_EQ(c.command({"GET", "k"})->str(), "v");
}

// Settings Redis refuses at connect are told as settings (the node stops at start on them),
// whatever words Redis chose: a password it has no use for, a database it does not have.
TEST_F(RedisConnection, RefusalsAtConnectAreSettingErrors) {
  RedisServer server;
  ASSERT_TRUE(server.start());
  ConnectOptions needless = server.options();
  needless.password = "x";  // this Redis has no password: "ERR AUTH <password> called without"
  Status s = Connection(needless).connect();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().kind, ErrorKind::Auth) << s.error().message;
  ConnectOptions far = server.options();
  far.url.db = 99;  // Redis has 16
  s = Connection(far).connect();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().kind, ErrorKind::Config) << s.error().message;
  EXPECT_NE(s.error().message.find("database 99"), std::string::npos) << s.error().message;
  // Said again until the next attempt, without Redis's full stop before it.
  RedisServer locked({"--requirepass", "s3cret"});
  ASSERT_TRUE(locked.start());
  ConnectOptions wrong = locked.options();
  wrong.password = "nope";
  Connection c(wrong);
  ASSERT_FALSE(c.connect());
  Status again = c.ensure_connected();
  ASSERT_FALSE(again);
  EXPECT_NE(again.error().message.find("refused this node: WRONGPASS"), std::string::npos)
      << again.error().message;
  EXPECT_NE(again.error().message.find("disabled; next attempt in"), std::string::npos)
      << again.error().message;
  // A Redis at its maxclients answers the first command, AUTH too, with an error: an outage
  // to wait out, not the credentials' fault.
  RedisServer full({"--maxclients", "1"});
  ASSERT_TRUE(full.start());
  Connection first(full.options());
  // Redis frees the start's own client a moment after it hangs up.
  bool in = false;
  for (int i = 0; i < 100 && !in; ++i) {
    in = static_cast<bool>(first.command({"PING"}));
    if (!in) {
      first.disconnect();
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  ASSERT_TRUE(in);
  ConnectOptions second = full.options();
  second.password = "x";
  Status busy = Connection(second).connect();
  ASSERT_FALSE(busy);
  EXPECT_EQ(busy.error().kind, ErrorKind::Unavailable) << busy.error().message;
}

TEST_F(RedisConnection, TellsNoPermFromOtherErrors) {
  RedisServer server({"--requirepass", "admin"});
  ASSERT_TRUE(server.start());
  ConnectOptions admin = server.options();
  admin.password = "admin";
  Connection a(admin);
  ASSERT_TRUE(a.command({"ACL", "SETUSER", "reader", "on", ">pw", "~*", "+get", "+ping"}));
  ConnectOptions reader = server.options();
  reader.url.user = "reader";
  reader.password = "pw";
  Connection c(reader);
  ASSERT_TRUE(c.command({"GET", "x"}));
  auto r = c.command({"SET", "x", "1"});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().kind, ErrorKind::NoPerm);
}

TEST_F(RedisConnection, AFullRedisGivesOomAndKeepsLeasesAndCancelsWorking) {
  RedisServer server({"--maxmemory", "4mb", "--maxmemory-policy", "noeviction"});
  ASSERT_TRUE(server.start());
  TestNode n = make_node(server, test_config("o:", "n1"));
  FarmClient& farm = *n.farm;
  SubmitRequest q;
  q.client = "A";
  q.max_active_per_client = 1000;
  q.opts = std::string(256 * 1024, 'x');
  std::optional<Error> oom;
  int accepted = 0;
  for (int i = 0; i < 200 && !oom; ++i) {
    q.job = "j" + std::to_string(i);
    auto r = farm.submit(q);
    if (r)
      ++accepted;
    else
      oom = r.error();
  }
  ASSERT_TRUE(oom) << "maxmemory was never reached";
  EXPECT_EQ(oom->kind, ErrorKind::Oom) << oom->message;
  EXPECT_FALSE(oom->outcome_unknown());
  EXPECT_GT(accepted, 0);
  EXPECT_TRUE(farm.heartbeat("{}", 3000ms, {}));  // allow-oom
  auto canceled = farm.cancel("j0", "A");
  ASSERT_TRUE(canceled) << canceled.error().message;
  EXPECT_EQ(canceled->status, CancelStatus::Canceled);
  EXPECT_TRUE(n.conn->command({"PING"}));
}

TEST_F(RedisConnection, TellsBusyAndNoGroupFromOtherErrors) {
  RedisServer server({"--busy-reply-threshold", "50"});
  ASSERT_TRUE(server.start());
  Connection c(server.options());
  auto nogroup = c.command({"XREADGROUP", "GROUP", "g", "c", "STREAMS", "nostream", ">"});
  ASSERT_FALSE(nogroup);
  EXPECT_EQ(nogroup.error().kind, ErrorKind::NoGroup);
  std::thread busy([&] {
    Connection s(server.options());
    // A script that runs for 400 ms of server time.
    (void)s.command({"EVAL",
                     "local t0 = redis.call('TIME') repeat local t = redis.call('TIME') until "
                     "(t[1] - t0[1]) * 1000000 + t[2] - t0[2] > 400000 return 1",
                     "0"});
  });
  std::this_thread::sleep_for(200ms);
  auto r = c.command({"PING"});
  busy.join();
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().kind, ErrorKind::Busy) << r.error().message;
  EXPECT_TRUE(c.command({"PING"}));
}

TEST_F(RedisConnection, APoolLendsEachConnectionToOneThreadAtATime) {
  RedisServer server;
  ASSERT_TRUE(server.start());
  Pool pool(server.options(), 2);
  auto a = pool.acquire(100ms);
  auto b = pool.acquire(100ms);
  ASSERT_TRUE(a && b);
  auto c = pool.acquire(50ms);
  ASSERT_FALSE(c);
  EXPECT_EQ(c.error().kind, ErrorKind::Unavailable);
  Connection* first = &**a;
  { auto moved = std::move(*a); }  // returned here
  auto d = pool.acquire(50ms);
  ASSERT_TRUE(d);
  EXPECT_EQ(&**d, first);
  std::vector<std::thread> threads;
  std::atomic<int> ok{0};
  auto e = std::move(*d);
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&] {
      for (int i = 0; i < 50; ++i) {
        auto lease = pool.acquire(5s);
        if (lease && (*lease)->command({"INCR", "n"})) ++ok;
      }
    });
  { auto release = std::move(e); }
  for (auto& t : threads) t.join();
  EXPECT_EQ(ok.load(), 200);
}

}  // namespace
}  // namespace rayfarm::farm::test
