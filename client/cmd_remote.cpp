// The command line as rayfarmd's client: `render --server`, `status`, `cancel`, `wait`,
// `jobs`.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>

#include "cli_common.h"
#include "commands.h"
#include "remote.h"

namespace rayfarm::cli {
namespace {

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

// Why `bytes` are not a whole image in `format` as a server sends one (empty: they are): a
// PNG from its signature to its IEND chunk, a binary PPM whose pixels fill it exactly. An
// HTML page, a cut-off transfer or the other format is never saved as the image.
std::string not_whole_image(const std::string& bytes, const std::string& format) {
  if (format == "ppm") {
    std::istringstream in(bytes);
    std::string magic;
    long long w = 0, h = 0, maxval = 0;
    in >> magic >> w >> h >> maxval;
    if (!in || magic != "P6" || w <= 0 || h <= 0 || maxval != 255 || in.get() == EOF)
      return "it is not a PPM image";
    const auto header = static_cast<long long>(in.tellg());
    if (static_cast<long long>(bytes.size()) - header != 3 * w * h)
      return "its PPM pixels are cut off or followed by other bytes";
    return "";
  }
  static const std::string kSignature("\x89PNG\r\n\x1a\n", 8);
  static const std::string kEnd("\0\0\0\0IEND\xae\x42\x60\x82", 12);
  if (!bytes.starts_with(kSignature)) return "it is not a PNG image";
  if (bytes.size() < kSignature.size() + kEnd.size() || !bytes.ends_with(kEnd))
    return "the PNG image is cut off";
  return "";
}

// A job that ended: saves its image, or says why there is none. The server's warnings about
// the scene (a sphere behind the eye) are shown with the scene's lines when it is at hand.
int finish(const Remote& remote, const nlohmann::json& status, const std::string& out,
           const std::string& format, bool quiet, const std::string& scene_name = "",
           const std::string* scene_text = nullptr) {
  std::string id = status.value("id", "");
  std::string state = status.value("state", "");
  if (!quiet && status.contains("warnings") && status["warnings"].is_array())
    for (const auto& w : status["warnings"]) {
      if (!w.is_object()) continue;
      Diagnostic d{Severity::warning,
                   w.value("code", ""),
                   w.value("message", ""),
                   {w.value("line", 0), w.value("column", 0), w.value("path", "")}};
      std::cerr << format_diagnostic(d, scene_name.empty() ? "job " + id : scene_name,
                                     scene_text ? *scene_text : "");
    }
  if (state != "done") {
    std::string message = status.contains("error") && status["error"].is_object()
                              ? status["error"].value("message", "")
                              : std::string(state == "canceled" ? "the job was canceled" : "");
    std::cerr << "rayfarm: job " << id << " " << state << (message.empty() ? "" : ": " + message)
              << "\n";
    return kNo;
  }
  auto res = remote.client()->get("/jobs/" + id + "/image?format=" + format, remote.headers());
  if (!res || res->status != 200) return report_http_error(res, "fetching the image");
  if (const std::string bad = not_whole_image(res->body, format); !bad.empty()) {
    std::cerr << "rayfarm: the server's answer to fetching the image of job " << id
              << " is not the image: " << bad << " (" << res->body.size()
              << " bytes); nothing was written\n";
    return kServerError;
  }
  if (!write_output(out, res->body.data(), res->body.size())) return kBadInput;
  if (!quiet) std::cerr << summary_line(status, out, remote.url) << "\n";
  return kOk;
}

struct IdArgs {
  std::string id;
  std::string server;
  std::string token;
  std::string out;
  bool quiet = false;
  bool json = false;
};

std::shared_ptr<IdArgs> add_id_args(CLI::App& app, bool with_id = true) {
  auto args = std::make_shared<IdArgs>();
  if (with_id)
    app.add_option("id", args->id, "job ID (32 hex digits), as render --detach prints it")
        ->required();
  app.add_option("--server", args->server,
                 "rayfarmd's URL, http://HOST[:PORT] (default: $RAYFARM_SERVER)");
  app.add_option("--token", args->token, "bearer token (default: $RAYFARM_TOKEN)");
  return args;
}

std::optional<Remote> remote_for(const IdArgs& args, bool with_id = true) {
  Remote r{server_url(args.server), server_token(args.token)};
  if (r.url.empty()) {
    std::cerr << "rayfarm: no server: give --server URL or set RAYFARM_SERVER\n";
    return std::nullopt;
  }
  for (const std::string& bad : {check_server_url(r.url), check_token(r.token)})
    if (!bad.empty()) {
      std::cerr << "rayfarm: " << bad << "\n";
      return std::nullopt;
    }
  if (with_id && !valid_id(args.id)) {
    std::cerr << "rayfarm: '" << args.id << "' is not a job id (32 hex digits)\n";
    return std::nullopt;
  }
  return r;
}

}  // namespace

int remote_render(const std::string& scene_path, const std::string& text,
                  const std::map<std::string, std::string>& textures, const std::string& out,
                  const OptionSet& options, const std::string& format, const Remote& remote,
                  bool quiet, bool detach) {
  std::string query;
  for (const OptionValue& v : options) {
    if (v.name == "format") continue;
    query += (query.empty() ? "?" : "&") + v.name + "=" + url_encode(v.value);
  }
  auto client = remote.client();
  auto post = [&] {
    if (textures.empty())
      return client->post("/render" + query, remote.headers(), text, "text/plain");
    // Part names are the paths exactly as the scene writes them (docs/http-api.md#textures).
    std::vector<HttpPart> parts = {{"scene", text, "scene", "text/plain"}};
    for (const auto& [path, bytes] : textures)
      parts.push_back({path, bytes, std::filesystem::path(path).filename().string(),
                       "application/octet-stream"});
    return client->post_multipart("/render" + query, remote.headers(), parts);
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
  if (detach) {
    // The ID alone on standard output, for `id=$(rayfarm render ... --detach)`.
    std::cout << id << std::endl;
    if (!quiet)
      std::cerr << "rayfarm: job " << id << " queued on " << remote.url
                << "; status: " << remote.url << "/jobs/" << id << "\n"
                << "rayfarm: then: rayfarm wait " << id << " -o " << out << "\n";
    return kOk;
  }
  if (!quiet) std::cerr << "rayfarm: job " << id << " on " << remote.url << "\n";
  int code = kOk;
  auto status = follow_job(remote, id, quiet, true, code);
  if (!status) return code;
  return finish(remote, *status, out, format, quiet, display_name(scene_path), &text);
}

Runner add_status(CLI::App& app) {
  auto args = add_id_args(app);
  app.add_flag("--json", args->json, "print the server's status document as it is");
  app.footer(help_footer(
      "  rayfarm status 3f0c8e6d9a2b4c1e8f7a6b5c4d3e2f1a --server http://localhost:8080\n"
      "  rayfarm status $id --json | jq .progress\n",
      "", true));
  return [args]() -> int {
    auto remote = remote_for(*args);
    if (!remote) return kBadInput;
    auto res = remote->client()->get("/jobs/" + args->id, remote->headers());
    if (!res || res->status != 200) return report_http_error(res, "job " + args->id);
    auto status = nlohmann::json::parse(res->body, nullptr, false);
    if (status.is_discarded() || !status.is_object()) {
      std::cerr << "rayfarm: the server sent a status that is not JSON\n";
      return kServerError;
    }
    if (args->json)
      std::cout << status.dump(2) << "\n";
    else
      std::cout << status_text(status, remote->url);
    return kOk;
  };
}

Runner add_cancel(CLI::App& app) {
  auto args = add_id_args(app);
  app.footer(help_footer("  rayfarm cancel $id --server http://localhost:8080\n", "", true));
  return [args]() -> int {
    auto remote = remote_for(*args);
    if (!remote) return kBadInput;
    auto res = remote->client()->del("/jobs/" + args->id, remote->headers());
    if (!res || res->status != 200) return report_http_error(res, "canceling " + args->id);
    auto status = nlohmann::json::parse(res->body, nullptr, false);
    const std::string state = status.is_object() ? status.value("state", "") : "";
    // The answer is the state after the cancel: a job that had already ended says so.
    if (state == "canceled" || state.empty())
      std::cout << "canceled " << args->id << "\n";
    else
      std::cout << args->id << " is " << state << "\n";
    return kOk;
  };
}

Runner add_wait(CLI::App& app) {
  auto args = add_id_args(app);
  file_name(app.add_option("-o,--output", args->out,
                           "save the image here when done: .png or .ppm, - for standard output "
                           "(default: ID.png)"));
  app.add_flag("-q,--quiet", args->quiet, "no progress bar or summary line");
  app.footer(
      help_footer("  rayfarm wait $id -o cho.png --server http://localhost:8080\n"
                  "  # where id=$(rayfarm render scenes/cho.txt --server URL --detach)\n",
                  "the job failed or was canceled", true));
  return [args]() -> int {
    auto remote = remote_for(*args);
    if (!remote) return kBadInput;
    if (args->out.empty()) args->out = args->id + ".png";  // waiting for nothing helps nobody
    if (std::string bad = check_output(args->out, ""); !bad.empty()) {
      std::cerr << "rayfarm: " << bad << "\n";
      return kBadInput;
    }
    int code = kOk;
    // Ctrl-C here stops waiting; the job is someone's to cancel with `rayfarm cancel`.
    auto status = follow_job(*remote, args->id, args->quiet, false, code);
    if (!status) return code;
    return finish(*remote, *status, args->out, std::string(to_string(output_format(args->out))),
                  args->quiet);
  };
}

Runner add_jobs(CLI::App& app) {
  auto args = add_id_args(app, false);
  app.add_flag("--json", args->json, "print the server's list as it is");
  app.footer(
      help_footer("  rayfarm jobs --server http://localhost:8080\n"
                  "  RAYFARM_SERVER=http://localhost:8080 rayfarm jobs --json\n",
                  "", true));
  return [args]() -> int {
    auto remote = remote_for(*args, false);
    if (!remote) return kBadInput;
    auto res = remote->client()->get("/jobs", remote->headers());
    if (!res || res->status != 200) return report_http_error(res, "listing jobs");
    auto body = nlohmann::json::parse(res->body, nullptr, false);
    if (body.is_discarded() || !body.contains("jobs") || !body["jobs"].is_array()) {
      std::cerr << "rayfarm: the server's list of jobs is not JSON\n";
      return kServerError;
    }
    if (args->json) {
      std::cout << body.dump(2) << "\n";
    } else if (body["jobs"].empty()) {
      std::cerr << "rayfarm: no jobs of yours on " << remote->url << "\n";
    } else {
      std::cout << jobs_table(body["jobs"]);
    }
    return kOk;
  };
}

}  // namespace rayfarm::cli
