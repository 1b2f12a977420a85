// RedisUrl parsing and where the password may come from.
#include "redis_url.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

namespace rayfarm::farm {
namespace {

TEST(RedisUrl, ParsesHostPortUserAndDatabase) {
  auto u = parse_redis_url("redis://rayfarm@10.0.0.5:6380/2");
  ASSERT_TRUE(u) << u.error().message;
  EXPECT_EQ(u->transport, RedisUrl::Transport::Tcp);
  EXPECT_EQ(u->host, "10.0.0.5");
  EXPECT_EQ(u->port, 6380);
  EXPECT_EQ(u->user, "rayfarm");
  EXPECT_EQ(u->db, 2);
  EXPECT_EQ(u->to_string(), "redis://rayfarm@10.0.0.5:6380/2");
}

TEST(RedisUrl, DefaultsToPort6379AndDatabase0) {
  auto u = parse_redis_url("redis://redis.lab");
  ASSERT_TRUE(u);
  EXPECT_EQ(u->host, "redis.lab");
  EXPECT_EQ(u->port, 6379);
  EXPECT_EQ(u->db, 0);
  EXPECT_TRUE(u->user.empty());
}

TEST(RedisUrl, ParsesBracketedIpv6) {
  auto u = parse_redis_url("redis://[::1]:7000");
  ASSERT_TRUE(u);
  EXPECT_EQ(u->host, "::1");
  EXPECT_EQ(u->port, 7000);
  EXPECT_EQ(u->to_string(), "redis://[::1]:7000");
}

TEST(RedisUrl, ParsesUnixSocket) {
  auto u = parse_redis_url("unix:///run/redis/redis.sock");
  ASSERT_TRUE(u);
  EXPECT_EQ(u->transport, RedisUrl::Transport::Unix);
  EXPECT_EQ(u->path, "/run/redis/redis.sock");
}

TEST(RedisUrl, RefusesAPasswordInTheUrlWithoutEchoingIt) {
  auto u = parse_redis_url("redis://rayfarm:s3cret@host:6379");
  ASSERT_FALSE(u);
  EXPECT_EQ(u.error().kind, ErrorKind::Config);
  EXPECT_NE(u.error().message.find("password in the URL is refused"), std::string::npos);
  EXPECT_NE(u.error().message.find("--redis-password-file"), std::string::npos);
  EXPECT_EQ(u.error().message.find("s3cret"), std::string::npos);
  EXPECT_FALSE(parse_redis_url("redis://:s3cret@host"));
}

TEST(RedisUrl, RefusesBadForms) {
  for (const char* bad : {"http://host", "redis://", "redis://host:0", "redis://host:99999",
                          "redis://host:abc", "redis://host/x", "unix://relative.sock",
                          "rediss://host", "redis://[::1", "redis://@host"}) {
    auto u = parse_redis_url(bad);
    EXPECT_FALSE(u) << bad;
    if (!u) {
      EXPECT_EQ(u.error().kind, ErrorKind::Config) << bad;
    }
  }
}

TEST(RedisPassword, ComesFromTheFileWithoutItsNewline) {
  const std::string path = testing::TempDir() + "/rf_redis_password";
  std::ofstream(path) << "s3cret\n";
  auto p = load_redis_password(path, nullptr);
  ASSERT_TRUE(p) << p.error().message;
  EXPECT_EQ(*p, "s3cret");
  std::remove(path.c_str());
}

TEST(RedisPassword, ComesFromTheEnvironmentOrIsEmpty) {
  auto p = load_redis_password(std::nullopt, "fromenv");
  ASSERT_TRUE(p);
  EXPECT_EQ(*p, "fromenv");
  auto none = load_redis_password(std::nullopt, nullptr);
  ASSERT_TRUE(none);
  EXPECT_EQ(*none, "");
}

TEST(RedisPassword, RefusesBothSourcesAMissingFileAndAnEmptyOne) {
  EXPECT_FALSE(load_redis_password(std::string("/nonexistent/pw"), "x"));
  EXPECT_FALSE(load_redis_password(std::string("/nonexistent/pw"), nullptr));
  const std::string path = testing::TempDir() + "/rf_redis_password_empty";
  std::ofstream(path) << "\n";
  auto p = load_redis_password(path, nullptr);
  ASSERT_FALSE(p);
  EXPECT_NE(p.error().message.find("is empty"), std::string::npos);
  std::ofstream(path) << "a\nb\n";
  EXPECT_FALSE(load_redis_password(path, nullptr));
  std::remove(path.c_str());
  // A folder is said to be one (the library's words were "basic_filebuf::underflow error").
  auto folder = load_redis_password(testing::TempDir(), nullptr);
  ASSERT_FALSE(folder);
  EXPECT_NE(folder.error().message.find("is a folder, not a file"), std::string::npos)
      << folder.error().message;
}

}  // namespace
}  // namespace rayfarm::farm
