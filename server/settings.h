// rayfarmd's settings: each a flag and an environment variable (docs/http-api.md#limits).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "rayfarm/options.h"

namespace rayfarm::server {

struct Settings {
  std::string host = "127.0.0.1";
  int port = 8080;
  int workers = 0;  // 0: all cores
  int queue_capacity = 256;
  std::uint64_t max_body_bytes = 16ULL << 20;
  std::int64_t max_pixels = 4096LL * 4096;
  int max_spp = 1024;
  int max_depth = 64;
  int max_objects = 1000000;
  int max_lights = 1000;
  int max_textures = 16;                          // texture files uploaded with one scene
  std::uint64_t max_texture_bytes = 8ULL << 20;  // one texture file's size
  double max_work = 8e9;  // pixels x spp x (max_depth + 1): the most ray paths a job may ask for
  double job_timeout = 600;  // seconds; 0: none
  std::string results_dir;   // empty: keep results in memory only
  std::uint64_t cache_bytes = 256ULL << 20;
  std::vector<std::string> tokens;  // accepted bearer tokens; empty: no authentication
  std::string tokens_file;  // the roster: NAME TOKEN [max_jobs=N] per line (roster.h)
  std::string make_tokens;  // a class list to make a roster for (printed), then exit
  Profile default_profile = Profile::lecture;  // of a request whose query and scene name none

  // For a shared lab: connections, streams, quotas, retention, folders.
  int http_threads = 64;
  int max_event_streams = 16;
  int max_waiting_requests = 32;
  int max_jobs_per_client = 32;  // queued or running at once
  double result_ttl = 24 * 3600;  // seconds a finished job is kept
  // Seconds between expiry sweeps; 0: 10 s, or a quarter of result_ttl when that is shorter
  // (no flag: tests that expire by hand set it long).
  double expiry_every = 0;
  std::uint64_t results_max_bytes = 2ULL << 30;
  std::string samples_dir;
  std::string assignments_dir;  // assignments POST /grade may name
  double shutdown_grace = 10;  // seconds running renders may finish after SIGTERM
  double header_timeout = 10;  // seconds a client has to send a request line and headers
  // The one origin (scheme://host[:port]) whose pages may call the API from a browser (a
  // grader hosted elsewhere); empty: no cross-origin access.
  std::string cors_origin;
  bool access_log = true;

  // The farm (docs/deployment.md#a-farm-of-several-machines): empty `redis` is the single
  // process; otherwise this process is one node of the farm that Redis holds together.
  std::string redis;                // redis://[user@]host:port[/db] or unix:///path
  std::string redis_password_file;  // else RAYFARM_REDIS_PASSWORD; never on the command line
  std::string node_id;              // empty: host:port:pid:start-ms
  std::string redis_prefix = "rf:";
  int heartbeat_ms = 1000;
  int lease_ms = 10000;
  double unit_work = 4e6;        // ray paths (pixels x spp x (max_depth + 1)) a unit should take
  double distribute_work = 2e7;  // a job of at most this many ray paths is one unit
};

// Parses flags (each also read from RAYFARM_<NAME>). Returns nullopt after printing help or
// an error; `exit_code` tells which.
std::optional<Settings> parse_settings(int argc, char** argv, int& exit_code);

}  // namespace rayfarm::server
