// The command line as rayfarmd's client: `render --server`, `status`, `cancel`, `wait`.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <thread>

#include "cli_common.h"
#include "commands.h"
#include "remote.h"

namespace rayfarm::cli {
namespace {

std::atomic<bool> interrupted{false};
void on_sigint(int) { interrupted = true; }

std::string url_encode(const std::string& s) {
  static const char* kHex = "0123456789ABCDEF";
  std::string out;
  for (unsigned char c : s) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') out += static_cast<char>(c);
    else out += {'%', kHex[c >> 4], kHex[c & 15]};
  }
  return out;
}

bool valid_id(const std::string& id) {
  return id.size() == 32 && id.find_first_not_of("0123456789abcdef") == std::string::npos;
}

void draw_bar(double fraction, const nlohmann::json& status, bool terminal) {
  int spp_done = status.value("spp_done", 0);
  std::string state = status.value("state", "?");
  if (terminal) {
    constexpr int kWidth = 30;
    int filled = static_cast<int>(fraction * kWidth + 0.5);
    std::string bar(filled, '#');
    bar.resize(kWidth, '.');
    std::fprintf(stderr, "\r[%s] %5.1f%%  %-8s spp %d", bar.c_str(), fraction * 100,
                 state.c_str(), spp_done);
    if (status.contains("queue_position") && status["queue_position"].get<int>() > 0)
      std::fprintf(stderr, "  queue %d", status["queue_position"].get<int>());
    if (status["error_estimate"].is_number())
      std::fprintf(stderr, "  error %.2f", status["error_estimate"].get<double>());
    std::fprintf(stderr, "   ");
  } else {
    std::fprintf(stderr, "%s %.1f%% spp %d\n", state.c_str(), fraction * 100, spp_done);
  }
  std::fflush(stderr);
}

// Follows a job until it ends. Returns its final status, or nullopt with `exit_code` set.
std::optional<nlohmann::json> follow(const Remote& remote, const std::string& id, bool quiet,
                                     int& exit_code, bool cancel_on_interrupt) {
  auto client = remote.client();
  const bool terminal = isatty(STDERR_FILENO);
  auto last_line = std::chrono::steady_clock::now();
  bool drawn = false;
  for (;;) {
    if (interrupted && cancel_on_interrupt) {
      if (drawn && terminal) std::fprintf(stderr, "\n");
      auto res = client->Delete("/jobs/" + id, remote.headers());
      std::cerr << "rayfarm: interrupted; "
                << (res && res->status == 200 ? "canceled job " : "could not cancel job ") << id
                << "\n";
      exit_code = 130;
      return std::nullopt;
    }
    auto res = client->Get("/jobs/" + id, remote.headers());
    if (!res || res->status != 200) {
      if (drawn && terminal) std::fprintf(stderr, "\n");
      exit_code = report_http_error(res, "job " + id);
      return std::nullopt;
    }
    auto status = nlohmann::json::parse(res->body, nullptr, false);
    if (status.is_discarded()) {
      std::cerr << "rayfarm: the server sent a status that is not JSON\n";
      exit_code = kServerError;
      return std::nullopt;
    }
    std::string state = status.value("state", "");
    double progress = status.value("progress", 0.0);
    bool final_state = state == "done" || state == "failed" || state == "canceled";
    auto now = std::chrono::steady_clock::now();
    if (!quiet && (terminal || now - last_line > std::chrono::seconds(2) || final_state)) {
      if (terminal || !final_state || drawn) {
        draw_bar(progress, status, terminal);
        drawn = true;
      }
      last_line = now;
    }
    if (final_state) {
      if (drawn && terminal) std::fprintf(stderr, "\n");
      return status;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
}

int finish(const Remote& remote, const nlohmann::json& status, const std::string& out,
           const std::string& format, bool quiet) {
  std::string id = status.value("id", "");
  std::string state = status.value("state", "");
  if (state != "done") {
    std::string message = status["error"].is_object()
                              ? status["error"].value("message", "")
                              : std::string(state == "canceled" ? "the job was canceled" : "");
    std::cerr << "rayfarm: job " << id << " " << state << (message.empty() ? "" : ": " + message)
              << "\n";
    return kInputError;
  }
  if (out.empty()) return kOk;
  auto res = remote.client()->Get("/jobs/" + id + "/image?format=" + format, remote.headers());
  if (!res || res->status != 200) return report_http_error(res, "fetching the image");
  if (!write_output(out, res->body.data(), res->body.size())) return kInputError;
  if (!quiet) {
    const auto& st = status["stats"];
    const auto& opts = status["options"];
    std::fprintf(stderr, "%s: %dx%d, spp %d, %.1f ms on %s, %.2f Mrays/s, cache %s (job %s)\n",
                 out == "-" ? "<stdout>" : out.c_str(), opts.value("width", 0),
                 opts.value("height", 0), status.value("spp_done", 0),
                 st.value("render_ms", 0.0), remote.url.c_str(),
                 st.value("rays_per_second", 0.0) / 1e6, st.value("cache", "miss").c_str(),
                 id.c_str());
  }
  return kOk;
}

struct IdArgs {
  std::string id;
  std::string server;
  std::string token;
  std::string out;
  bool quiet = false;
};

std::shared_ptr<IdArgs> add_id_args(CLI::App& app) {
  auto args = std::make_shared<IdArgs>();
  app.add_option("id", args->id, "job id")->required();
  app.add_option("--server", args->server, "rayfarmd URL (default: $RAYFARM_SERVER)");
  app.add_option("--token", args->token, "bearer token (default: $RAYFARM_TOKEN)");
  return args;
}

std::optional<Remote> remote_for(const IdArgs& args) {
  Remote r{server_url(args.server), server_token(args.token)};
  if (r.url.empty()) {
    std::cerr << "rayfarm: no server: give --server URL or set RAYFARM_SERVER\n";
    return std::nullopt;
  }
  if (std::string bad = check_server_url(r.url); !bad.empty()) {
    std::cerr << "rayfarm: " << bad << "\n";
    return std::nullopt;
  }
  if (!valid_id(args.id)) {
    std::cerr << "rayfarm: '" << args.id << "' is not a job id (32 hex digits)\n";
    return std::nullopt;
  }
  return r;
}

}  // namespace

int remote_render(const std::string& scene_path, const std::string& text,
                  const std::map<std::string, std::string>& textures, const std::string& out,
                  const OptionSet& options, const std::string& format, const Remote& remote,
                  bool quiet) {
  std::string query;
  for (const OptionValue& v : options) {
    if (v.name == "format") continue;
    query += (query.empty() ? "?" : "&") + v.name + "=" + url_encode(v.value);
  }
  auto client = remote.client();
  auto post = [&] {
    if (textures.empty())
      return client->Post("/render" + query, remote.headers(), text, "text/plain");
    // Part names are the paths exactly as the scene writes them (SPEC §5).
    httplib::MultipartFormDataItems parts = {{"scene", text, "scene", "text/plain"}};
    for (const auto& [path, bytes] : textures)
      parts.push_back({path, bytes, std::filesystem::path(path).filename().string(),
                       "application/octet-stream"});
    return client->Post("/render" + query, remote.headers(), parts);
  };
  auto res = post();
  if (!res || res->status != 202)
    return report_http_error(res, "submitting to " + remote.url, display_name(scene_path), &text);
  auto body = nlohmann::json::parse(res->body, nullptr, false);
  std::string id = body.is_discarded() ? "" : body.value("id", "");
  if (!valid_id(id)) {
    std::cerr << "rayfarm: the server's answer has no job id\n";
    return kServerError;
  }
  std::signal(SIGINT, on_sigint);
  int code = kOk;
  auto status = follow(remote, id, quiet, code, true);
  if (!status) return code;
  return finish(remote, *status, out, format, quiet);
}

Runner add_status(CLI::App& app) {
  auto args = add_id_args(app);
  return [args]() -> int {
    auto remote = remote_for(*args);
    if (!remote) return kUsage;
    auto res = remote->client()->Get("/jobs/" + args->id, remote->headers());
    if (!res || res->status != 200) return report_http_error(res, "job " + args->id);
    auto status = nlohmann::json::parse(res->body, nullptr, false);
    std::cout << (status.is_discarded() ? res->body : status.dump(2)) << "\n";
    return kOk;
  };
}

Runner add_cancel(CLI::App& app) {
  auto args = add_id_args(app);
  return [args]() -> int {
    auto remote = remote_for(*args);
    if (!remote) return kUsage;
    auto res = remote->client()->Delete("/jobs/" + args->id, remote->headers());
    if (!res || res->status != 200) return report_http_error(res, "canceling " + args->id);
    std::cout << "canceled " << args->id << "\n";
    return kOk;
  };
}

Runner add_wait(CLI::App& app) {
  auto args = add_id_args(app);
  app.add_option("-o,--output", args->out, "save the image here when done (- for stdout; default ID.png)");
  app.add_flag("-q,--quiet", args->quiet, "no progress");
  return [args]() -> int {
    auto remote = remote_for(*args);
    if (!remote) return kUsage;
    if (args->out.empty()) args->out = args->id + ".png";  // waiting for nothing helps nobody
    int code = kOk;
    auto status = follow(*remote, args->id, args->quiet, code, false);
    if (!status) return code;
    std::string format = args->out.size() > 4 && args->out.substr(args->out.size() - 4) == ".ppm"
                             ? "ppm" : "png";
    return finish(*remote, *status, args->out, format, args->quiet);
  };
}

}  // namespace rayfarm::cli
