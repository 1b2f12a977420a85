// Settings from flags and environment variables.
#include "settings.h"

#include "rayfarm/render.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <regex>
#include <thread>

namespace rayfarm::server {
namespace {

// The message for a bad value that came from an option's environment variable rather than
// the command line (the user never typed --port); empty for any other error.
std::string from_environment(const CLI::App& app, const CLI::ParseError& e, int argc,
                             char** argv) {
  const std::string what = e.what();
  for (const CLI::Option* o : app.get_options()) {
    const std::string& env = o->get_envname();
    const char* value = env.empty() ? nullptr : std::getenv(env.c_str());
    const std::string flag = o->get_name();
    const bool about_it =
        what.rfind(flag + ":", 0) == 0 || what.find(": " + flag + " = ") != std::string::npos;
    if (!value || !about_it) continue;
    for (int i = 1; i < argc; ++i)
      if (std::string arg = argv[i]; arg == flag || arg.rfind(flag + "=", 0) == 0) return "";
    std::string reason = what.rfind(flag + ": ", 0) == 0 ? what.substr(flag.size() + 2) : what;
    return env + "='" + value + "' (from the environment) is not a valid " + flag + ": " + reason;
  }
  return "";
}

}  // namespace

std::optional<Settings> parse_settings(int argc, char** argv, int& exit_code) {
  Settings s;
  CLI::App app{"rayfarmd: the rayfarm render service"};
  app.set_version_flag("--version", "rayfarmd 0.1.0 (render version " + std::to_string(kRenderVersion) + ")");
  std::string tokens;
  std::string profile(to_string(s.default_profile));
  // Read as the render option is, so the accepted names and the message come from its table.
  auto as_profile = [](const std::string& v) {
    RenderOptions o;
    return apply_option(o, "profile", v).value_or("");
  };
  auto add = [&](const std::string& flag, auto& value, const std::string& help) {
    std::string env = "RAYFARM_";
    for (char c : flag.substr(2)) env += c == '-' ? '_' : static_cast<char>(std::toupper(c));
    return app.add_option(flag, value, help)->envname(env)->capture_default_str();
  };
  add("--host", s.host, "address to listen on");
  add("--port", s.port, "port to listen on (0: any free port)")->check(CLI::Range(0, 65535));
  add("--workers", s.workers, "render threads (0: all cores)")->check(CLI::Range(0, 1024));
  add("--queue-capacity", s.queue_capacity, "jobs queued or running before 429")
      ->check(CLI::Range(1, 1000000));
  add("--max-body-bytes", s.max_body_bytes, "largest request body");
  add("--max-pixels", s.max_pixels, "largest image (width x height)")
      ->check(CLI::Range(1LL, 256LL * 1024 * 1024));
  add("--max-spp", s.max_spp, "largest spp")->check(CLI::Range(1, 1 << 20));
  add("--max-depth", s.max_depth, "largest max_depth")->check(CLI::Range(0, 100000));
  add("--max-objects", s.max_objects, "most objects in a scene (every kind counts)")->check(CLI::Range(0, 100000000));
  add("--max-lights", s.max_lights, "most lights in a scene")->check(CLI::Range(0, 1000000));
  add("--max-textures", s.max_textures, "most texture files uploaded with one scene")
      ->check(CLI::Range(0, 100000));
  add("--max-texture-bytes", s.max_texture_bytes, "largest uploaded texture file");
  add("--max-work", s.max_work, "most pixels x spp x (max_depth + 1) in one job")
      ->check(CLI::Range(1.0, 1e18));
  add("--job-timeout", s.job_timeout, "seconds a job may render (0: no limit)")
      ->check(CLI::Range(0.0, 1e9));
  add("--results-dir", s.results_dir, "directory for results and queued jobs (survive restarts)");
  add("--cache-bytes", s.cache_bytes, "result bytes kept in memory");
  add("--token", tokens, "bearer token(s) required of clients, comma-separated");
  add("--tokens-file", s.tokens_file,
      "the class roster: lines NAME TOKEN [max_jobs=N], # comments; reread on SIGHUP");
  app.add_option("--make-tokens", s.make_tokens,
                 "print a roster for a class list (one name per line) and exit");
  add("--default-profile", profile, "profile of a request whose query and scene name none")
      ->check(as_profile)
      ->type_name(std::string(find_option("profile")->value_help));
  add("--http-threads", s.http_threads, "connection threads")->check(CLI::Range(4, 4096));
  add("--max-event-streams", s.max_event_streams, "open event streams at once")
      ->check(CLI::Range(0, 100000));
  add("--max-waiting-requests", s.max_waiting_requests, "requests blocked in wait=1 at once")
      ->check(CLI::Range(0, 100000));
  add("--max-jobs-per-client", s.max_jobs_per_client, "jobs one client may have queued or running")
      ->check(CLI::Range(1, 1000000));
  add("--result-ttl", s.result_ttl, "seconds a finished job is kept")->check(CLI::Range(1.0, 1e9));
  add("--results-max-bytes", s.results_max_bytes, "bytes of images kept in --results-dir");
  add("--samples-dir", s.samples_dir, "directory of bundled sample scenes");
  add("--assignments-dir", s.assignments_dir,
      "directory of assignments POST /grade may name (NAME.json, scenes beside it)");
  add("--shutdown-grace", s.shutdown_grace, "seconds running renders may finish on SIGTERM")
      ->check(CLI::Range(0.0, 3600.0));
  add("--header-timeout", s.header_timeout, "seconds a client has to send a request's head")
      ->check(CLI::Range(0.1, 3600.0));
  // An exact origin as browsers send it: a path, a trailing slash or a wildcard would never
  // match, so they are refused at start rather than failing silently in the browser.
  add("--cors-origin", s.cors_origin,
      "the origin (scheme://host[:port]) whose web pages may call this API; none by default")
      ->check([](const std::string& v) -> std::string {
        static const std::regex origin(
            R"(https?://([A-Za-z0-9.-]+|\[[0-9A-Fa-f:.]+\])(:[0-9]{1,5})?)");
        if (v.empty() || std::regex_match(v, origin)) return {};
        return "must be an origin such as https://grader.example.edu or http://localhost:3000 "
               "(a scheme and a host, an optional port, no path)";
      });
  add("--redis", s.redis,
      "join the farm at this Redis: redis://[user@]host:port[/db] or unix:///path "
      "(no password in it)");
  // Its own environment variable, RAYFARM_REDIS_PASSWORD, holds the password itself.
  app.add_option("--redis-password-file", s.redis_password_file,
                 "file holding the Redis password (or set RAYFARM_REDIS_PASSWORD)")
      ->envname("RAYFARM_REDIS_PASSWORD_FILE");
  // It is a Redis key's part, a metric label and a message's word: a plain name, not empty.
  add("--node-id", s.node_id, "this node's name in the farm (default host:port:pid:start-ms)")
      ->check([](const std::string& v) -> std::string {
        static const std::regex name(R"([A-Za-z0-9._:@-]{1,128})");
        if (std::regex_match(v, name)) return {};
        return "must be 1 to 128 letters, digits and . _ : @ - (no spaces), got '" +
               v.substr(0, 40) + (v.size() > 40 ? "...'" : "'");
      });
  add("--redis-prefix", s.redis_prefix, "prefix of the farm's Redis keys");
  add("--heartbeat-ms", s.heartbeat_ms, "how often a farm node renews its units' leases")
      ->check(CLI::Range(10, 600000));
  add("--lease-ms", s.lease_ms, "a unit not renewed this long goes to another node")
      ->check(CLI::Range(50, 3600000));
  add("--unit-work", s.unit_work, "ray paths one unit of a farm job should take")
      ->check(CLI::Range(1.0, 1e18));
  add("--distribute-work", s.distribute_work,
      "a farm job of at most this many ray paths is rendered on the node that took it")
      ->check(CLI::Range(0.0, 1e18));
  bool quiet = false;
  app.add_flag("--no-access-log", quiet, "do not log each request")->envname("RAYFARM_NO_ACCESS_LOG");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (std::string env = from_environment(app, e, argc, argv); !env.empty()) {
      std::fprintf(stderr, "rayfarmd: %s\n", env.c_str());
      exit_code = 2;
      return std::nullopt;
    }
    exit_code = app.exit(e);
    if (exit_code != 0) exit_code = 2;
    return std::nullopt;
  }
  s.access_log = !quiet;
  if (!s.redis.empty() && s.lease_ms < 2 * s.heartbeat_ms) {
    std::fprintf(stderr, "rayfarmd: --lease-ms (%d) must be at least twice --heartbeat-ms (%d)\n",
                 s.lease_ms, s.heartbeat_ms);
    exit_code = 2;
    return std::nullopt;
  }
  // Browsers send an origin in lower case.
  for (char& c : s.cors_origin) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  RenderOptions resolved;
  apply_option(resolved, "profile", profile);
  s.default_profile = resolved.profile;
  size_t start = 0;
  while (start < tokens.size()) {
    size_t comma = tokens.find(',', start);
    std::string t = tokens.substr(start, comma == std::string::npos ? comma : comma - start);
    if (!t.empty()) s.tokens.push_back(t);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return s;
}

}  // namespace rayfarm::server
