#include "farm_fixture.h"

#include <atomic>

namespace rayfarm::farm::test {

RedisServer* FarmTest::server_ = nullptr;

void FarmTest::SetUpTestSuite() {
  if (!RedisServer::binary()) return;
  server_ = new RedisServer();
  server_->start();
}

void FarmTest::TearDownTestSuite() {
  delete server_;
  server_ = nullptr;
}

void FarmTest::SetUp() {
  RAYFARM_REQUIRE_REDIS_SERVER();
  ASSERT_TRUE(server_ && server_->running()) << "redis-server did not start; see its log in "
                                             << (server_ ? server_->dir() : "?");
  static std::atomic<int> counter{0};
  prefix_ = "t" + std::to_string(++counter) + ":";
}

FarmConfig test_config(const std::string& prefix, const std::string& node, int target) {
  FarmConfig c;
  c.prefix = prefix;
  c.node = node;
  c.build = "test-build";
  c.feed_target = target;
  c.max_tries = 3;
  c.block = std::chrono::milliseconds(1000);
  return c;
}

TestNode make_node(const RedisServer& server, const FarmConfig& c) {
  TestNode n;
  n.setup = std::make_shared<FarmSetup>(c);
  n.conn = std::make_unique<Connection>(farm_connect_options(server.options(), n.setup));
  n.farm = std::make_unique<FarmClient>(*n.conn, c);
  return n;
}

FarmConfig FarmTest::config(const std::string& node, int target) const {
  return test_config(prefix_, node, target);
}

TestNode FarmTest::node(const std::string& name, int target) const {
  return node(config(name, target));
}

TestNode FarmTest::node(const FarmConfig& c) const { return make_node(*server_, c); }

Connection& FarmTest::raw() {
  if (!raw_) raw_ = std::make_unique<Connection>(server_->options());
  return *raw_;
}

long long FarmTest::integer(std::initializer_list<std::string_view> argv) {
  auto r = raw().command(argv);
  EXPECT_TRUE(r) << r.error().message;
  return r ? r->integer() : -1;
}

std::string FarmTest::hget(const std::string& key, const std::string& field) {
  auto r = raw().command({"HGET", prefix_ + key, field});
  EXPECT_TRUE(r) << r.error().message;
  return r ? std::string(r->str()) : "";
}

long long FarmTest::stream_length() { return integer({"XLEN", prefix_ + "work"}); }

long long FarmTest::pending() {
  auto r = raw().command({"XPENDING", prefix_ + "work", "render"});
  EXPECT_TRUE(r) << r.error().message;
  return r ? (*r)[0].integer() : -1;
}

SubmitResult FarmTest::submit(TestNode& n, const std::string& job, const std::string& client,
                              int units, Priority p) {
  SubmitRequest q;
  q.job = job;
  q.client = client;
  q.units = units;
  q.priority = p;
  q.opts = "{\"job\":\"" + job + "\"}";
  auto r = n->submit(q);
  EXPECT_TRUE(r) << r.error().message;
  return r ? *r : SubmitResult{SubmitStatus::Full, ""};
}

}  // namespace rayfarm::farm::test
