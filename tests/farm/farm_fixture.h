// A redis-server per test suite and helpers for farm tests: each test works under its own key
// prefix, so tests never see each other's keys.
#pragma once

#include <memory>
#include <string>

#include "farm_client.h"
#include "redis_server.h"

namespace rayfarm::farm::test {

// One node: its connection (with the farm setup hook) and a FarmClient over it.
struct TestNode {
  std::unique_ptr<Connection> conn;
  std::unique_ptr<FarmClient> farm;
  std::shared_ptr<FarmSetup> setup;
  FarmClient* operator->() { return farm.get(); }
};

// A farm config for tests (build "test-build", feed target 1, max tries 3).
FarmConfig test_config(const std::string& prefix, const std::string& node, int target = 1);
// A node connected (lazily) to `server` with the farm setup hook.
TestNode make_node(const RedisServer& server, const FarmConfig& config);

class FarmTest : public testing::Test {
 protected:
  static void SetUpTestSuite();
  static void TearDownTestSuite();
  void SetUp() override;

  FarmConfig config(const std::string& node, int target = 1) const;
  TestNode node(const std::string& name, int target = 1) const;
  TestNode node(const FarmConfig& config) const;
  // A plain connection (no farm hook) to inspect keys.
  Connection& raw();
  long long integer(std::initializer_list<std::string_view> argv);
  // A field of a hash under this test's prefix ("" when missing).
  std::string hget(const std::string& key, const std::string& field);
  // XLEN and the XPENDING count of the work stream.
  long long stream_length();
  long long pending();
  SubmitResult submit(TestNode& n, const std::string& job, const std::string& client, int units,
                      Priority p = Priority::Normal);

  static RedisServer* server_;
  std::string prefix_;
  std::unique_ptr<Connection> raw_;
};

}  // namespace rayfarm::farm::test
