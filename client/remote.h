// Talking to rayfarmd: submit, follow, fetch, cancel (docs/http-api.md, docs/cli.md).
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "http.h"
#include "rayfarm/options.h"

namespace rayfarm::cli {

struct Remote {
  std::string url;    // http://host:port
  std::string token;  // bearer token, optional

  std::unique_ptr<HttpClient> client() const;
  HttpHeaders headers() const;
};

// The server URL from the flag or RAYFARM_SERVER; empty when neither is set, or for "none".
std::string server_url(const std::string& flag);
// What is wrong with a server URL (another scheme, a path, a bad port); empty when it is fine.
std::string check_server_url(const std::string& url);
// Why a token cannot be sent (empty: it can): it goes into a header line as it is.
std::string check_token(const std::string& token);
std::string server_token(const std::string& flag);

// Prints a server error body (with FILE:LINE:COL for scene errors) and returns the exit code
// it maps to: 2 for the request's fault (4xx), 3 for the server's (5xx, 429, network).
// With the scene's text, scene errors are shown with their source line and a caret.
int report_http_error(const HttpResult& result, const std::string& what,
                      const std::string& scene_name = "", const std::string* scene_text = nullptr);

// `rayfarm render --server`: submits, shows progress, saves the image; Ctrl-C cancels.
// `textures` (path as the scene writes it -> bytes) go up as multipart parts with the scene.
// With `detach`, prints the job's ID and returns once it is queued.
int remote_render(const std::string& scene_path, const std::string& text,
                  const std::map<std::string, std::string>& textures, const std::string& out,
                  const OptionSet& options, const std::string& format, const Remote& remote,
                  bool quiet, bool detach);

// Follows a job until it ends, with a progress bar on a terminal (a line every few seconds
// otherwise) unless `quiet`: through its event stream, or by polling GET /jobs/ID where the
// stream is not available. Ctrl-C cancels the job when `cancel_on_interrupt`. The final
// status, or nullopt with `exit_code` set and the reason printed.
std::optional<nlohmann::json> follow_job(const Remote& remote, const std::string& id, bool quiet,
                                         bool cancel_on_interrupt, int& exit_code);

// A job's status for people: one labelled line per fact, and what to run next.
std::string status_text(const nlohmann::json& status, const std::string& url);
// `rayfarm jobs`: one row per job of GET /jobs's list.
std::string jobs_table(const nlohmann::json& jobs);
// "cho.png: 800x600, spp 16, 52.1 ms on URL, 6.79 Mrays/s (job ID)", or "cached on URL".
std::string summary_line(const nlohmann::json& status, const std::string& out,
                         const std::string& url);

}  // namespace rayfarm::cli
