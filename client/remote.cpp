// HTTP client helpers.
#include "remote.h"

#include <cstdlib>
#include <iostream>

#include "cli_common.h"
#include "rayfarm/diagnostic.h"

namespace rayfarm::cli {

std::unique_ptr<HttpClient> Remote::client() const { return http_client(url); }

HttpHeaders Remote::headers() const {
  HttpHeaders h;
  if (!token.empty()) h.emplace_back("Authorization", "Bearer " + token);
  return h;
}

std::string server_url(const std::string& flag) {
  std::string url = flag;
  if (url.empty())
    if (const char* env = std::getenv("RAYFARM_SERVER")) url = env;
  if (url == "none") return "";  // render here, whatever RAYFARM_SERVER says
  if (!url.empty() && url.find("://") == std::string::npos) url = "http://" + url;
  while (!url.empty() && url.back() == '/') url.pop_back();
  return url;
}

std::string check_server_url(const std::string& url) {
  const size_t colon = url.find("://");
  const std::string scheme = url.substr(0, colon);
  if (scheme != "http" && scheme != "https")
    return "'" + url + "' is not a server URL: rayfarmd speaks http:// (or https:// behind a proxy)";
  const std::string rest = url.substr(colon + 3);
  if (rest.find('/') != std::string::npos)
    return "'" + url + "' has a path: give the server's root, http://HOST[:PORT] (rayfarmd's " +
           "routes start at /)";
  const size_t port_at = rest.rfind(':');
  const std::string host = port_at == std::string::npos || rest.back() == ']' ? rest : rest.substr(0, port_at);
  if (host.empty()) return "'" + url + "' names no host";
  if (port_at != std::string::npos && rest.back() != ']') {
    const std::string port = rest.substr(port_at + 1);
    const bool digits = !port.empty() && port.size() <= 5 &&
                        port.find_first_not_of("0123456789") == std::string::npos;
    if (!digits || std::stoi(port) < 1 || std::stoi(port) > 65535)
      return "'" + url + "': the port must be a number in 1..65535";
  }
  return "";
}

std::string server_token(const std::string& flag) {
  if (!flag.empty()) return flag;
  const char* env = std::getenv("RAYFARM_TOKEN");
  return env ? env : "";
}

std::string check_token(const std::string& token) {
  for (char c : token)
    if (c <= ' ' || c == 0x7f)  // (char may be signed: bytes past 0x7f are refused too)
      return "the token holds a space, a line break or another control character, which "
             "cannot go in an HTTP header: check --token or RAYFARM_TOKEN (a file with "
             "Windows line endings leaves a carriage return at its end)";
  return "";
}

int report_http_error(const HttpResult& result, const std::string& what,
                      const std::string& scene_name, const std::string* scene_text) {
  if (!result) {
    const HttpError e = result.error();
    std::string why = result.why();
    if (e == HttpError::connection)
      why = "cannot connect (connection refused, or no such host): is rayfarmd running there?";
    else if (e == HttpError::read || e == HttpError::write)
      why = "the connection broke off (" + why + "): the server may have stopped or timed out";
    else if (e == HttpError::too_large)
      why = "the server's answer is " + too_large(HttpLimits{}.max_body);
    std::cerr << "rayfarm: " << what << ": " << why << "\n";
    return kServerError;
  }
  int status = result->status;
  auto body = nlohmann::json::parse(result->body, nullptr, false);
  std::string message = "HTTP " + std::to_string(status);
  if (!body.is_discarded() && body.contains("error") && body["error"].is_object()) {
    const auto& e = body["error"];
    if (e.contains("errors") && e["errors"].is_array() && !scene_name.empty()) {
      for (const auto& item : e["errors"]) {
        Diagnostic d;
        d.code = item.value("code", "");
        d.message = item.value("message", "");
        d.where = {item.value("line", 0), item.value("column", 0), item.value("path", "")};
        std::cerr << format_diagnostic(d, scene_name, scene_text ? *scene_text : "");
      }
      return kBadInput;
    }
    message = e.value("message", message);
    if (e.contains("limit") && e["limit"].is_string())
      message += " (limit: " + e["limit"].get<std::string>() + ")";
  }
  if (status == 401)
    message +=
        ": give your token with --token TOKEN or in RAYFARM_TOKEN (a token that was "
        "given is not one the server knows)";
  std::cerr << "rayfarm: " << what << ": " << message << "\n";
  bool client_fault = status >= 400 && status < 500 && status != 429 && status != 408;
  return client_fault ? kBadInput : kServerError;
}

}  // namespace rayfarm::cli
