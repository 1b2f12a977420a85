// Responses, query parameters and client identity shared by the routes.
#include "http_util.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>
#include <vector>

#include "rayfarm/diagnostic.h"
#include "rayfarm/image_io.h"
#include "rayfarm/sha256.h"

namespace rayfarm::server {

using httplib::Request;
using httplib::Response;

void send_json(Response& res, int status, const nlohmann::json& body) {
  res.status = status;
  res.set_content(json_text(body) + "\n", "application/json");
}

void send_error(Response& res, const ApiError& e) {
  if (e.retry_after > 0) res.set_header("Retry-After", std::to_string(e.retry_after));
  send_json(res, e.status, e.body());
}

void send_error(Response& res, int status, const std::string& code, const std::string& message) {
  send_error(res, api_error(status, code, message));
}

void send_image(Response& res, const Image& image, bool ppm) {
  auto bytes = encode_image(image, ppm ? ImageFormat::ppm : ImageFormat::png);
  res.status = 200;
  res.set_content(reinterpret_cast<const char*>(bytes.data()), bytes.size(),
                  ppm ? "image/x-portable-pixmap" : "image/png");
}

std::string lower_ascii(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view trim(std::string_view s) {
  const size_t a = s.find_first_not_of(" \t");
  if (a == std::string_view::npos) return {};
  return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}

std::string origin_form(std::string_view target) {
  for (std::string_view scheme : {"http://", "https://"}) {
    if (target.size() < scheme.size() || lower_ascii(target.substr(0, scheme.size())) != scheme)
      continue;
    const std::string_view rest = target.substr(scheme.size());
    const size_t end = rest.find_first_of("/?#");  // where the authority ends
    if (end == std::string_view::npos) return "/";
    return (rest[end] == '/' ? "" : "/") + std::string(rest.substr(end));
  }
  return std::string(target);
}

bool none_match_hits(const Request& req, std::string_view etag) {
  // Outside GET and HEAD a met condition is a 412 (RFC 9110 §13.1.2), never a 304: a POST
  // that waits for its image ignores it.
  if (req.method != "GET" && req.method != "HEAD") return false;
  std::string header;  // repeated header lines are one list (§5.3)
  for (std::size_t i = 0; i < req.get_header_value_count("If-None-Match"); ++i)
    header += (i ? "," : "") + req.get_header_value("If-None-Match", i);
  std::string_view rest = header;
  while (!rest.empty()) {
    const std::size_t comma = rest.find(',');
    std::string_view tag = rest.substr(0, comma);
    rest = comma == std::string_view::npos ? std::string_view{} : rest.substr(comma + 1);
    while (!tag.empty() && (tag.front() == ' ' || tag.front() == '\t')) tag.remove_prefix(1);
    while (!tag.empty() && (tag.back() == ' ' || tag.back() == '\t')) tag.remove_suffix(1);
    if (tag == "*") return true;
    if (tag.substr(0, 2) == "W/") tag.remove_prefix(2);
    if (tag == etag) return true;
  }
  return false;
}

bool send_result(Service& service, const Request& req, Response& res, const JobRecord& job) {
  auto png = service.result_png(job);
  if (!png) return false;
  std::string etag = "\"" + job.image_name + (wants_ppm(req, job) ? "-ppm" : "") + "\"";
  res.set_header("ETag", etag);
  res.set_header("Cache-Control", "private, max-age=86400");
  res.set_header("X-Job-Id", job.id);
  res.set_header("X-Render-Ms", std::to_string(std::llround(job.stats.render_ms)));
  res.set_header("X-Cache", job.cache_hit ? "hit" : "miss");
  if (none_match_hits(req, etag)) {
    res.status = 304;
    return true;
  }
  if (wants_ppm(req, job)) {
    std::string error;
    auto image = decode_image(*png, &error);
    if (!image) return false;
    send_image(res, *image, true);
    return true;
  }
  res.status = 200;
  res.set_content(*png, "image/png");
  return true;
}

bool check_query(const Request& req, Response& res, std::string_view route,
                 std::initializer_list<QueryParam> taken) {
  for (const auto& [name, value] : req.params) {
    const QueryParam* param = nullptr;
    for (const QueryParam& p : taken)
      if (p.name == name) param = &p;
    std::string message;
    if (!param) {
      std::vector<std::string_view> names;
      std::string list;
      for (const QueryParam& p : taken) {
        names.push_back(p.name);
        list += (list.empty() ? "" : ", ") + std::string(p.name);
      }
      const std::string near = nearest_word(name, names);
      message = "unknown option '" + name.substr(0, 64) + "' for " + std::string(route) +
                (near.empty() ? "" : " (did you mean '" + near + "'?)") +
                (list.empty() ? "; it takes no options" : "; it takes: " + list);
    } else if (req.params.count(name) > 1) {
      message = "'" + name + "' is given more than once";
    } else if (param->values.size() > 0 &&
               std::find(param->values.begin(), param->values.end(), value) ==
                   param->values.end()) {
      std::string list;
      for (std::string_view v : param->values) list += (list.empty() ? "" : ", ") + std::string(v);
      message = "'" + name + "' is '" + value.substr(0, 64) + "'; it takes " + list;
    } else {
      continue;
    }
    ApiError e = api_error(400, "invalid_option", message);
    e.path = name.substr(0, 64);
    send_error(res, e);
    return false;
  }
  return true;
}

bool wants_ppm(const Request& req, const JobRecord& job) {
  if (req.has_param("format")) return req.get_param_value("format") == "ppm";
  return job.options.format == ImageFormat::ppm;
}

ApiError failed_job_error(const JobRecord& job) {
  const std::string& code = job.error_code;
  ApiError e;
  e.status = code == "timeout"         ? 422
             : code == "bad_request"   ? 400
             : code == "storage_error" ? 503
                                       : 500;
  e.code = code.empty() ? "render_failed" : code;
  e.message = job.error;
  if (code == "timeout") e.limit = "job_timeout";
  return e;
}

std::optional<bool> yes_no(std::string_view word) {
  if (word == "1" || word == "true" || word == "yes") return true;
  if (word == "0" || word == "false" || word == "no") return false;
  return std::nullopt;
}

ApiError not_yes_no(const std::string& name, const std::string& value) {
  ApiError e = api_error(400, "invalid_option",
                         name + " must be 1, true, yes, 0, false or no, got '" + value.substr(0, 32) + "'");
  e.path = name;
  return e;
}

bool param_true(const Request& req, const char* name) {
  return req.has_param(name) && yes_no(req.get_param_value(name)).value_or(false);
}

ApiError ambiguous_query(std::string_view target) {
  const size_t q = target.find('?');
  if (q == std::string_view::npos) return {};
  std::string_view query = target.substr(q + 1);
  std::set<std::string> names;
  while (!query.empty()) {
    const size_t amp = query.find('&');
    const std::string_view piece = query.substr(0, amp);
    const size_t eq = piece.find('=');
    // A name given twice, the same pair too: the library keeps one of identical pairs, so
    // its params cannot tell.
    if (!piece.empty()) {
      const std::string name =
          httplib::detail::decode_url(std::string(piece.substr(0, eq)), true);
      if (!names.insert(name).second) {
        ApiError e = api_error(400, "invalid_option",
                               "'" + name.substr(0, 64) + "' is given more than once");
        e.path = name.substr(0, 64);
        return e;
      }
    }
    if (eq != std::string_view::npos && piece.find('=', eq + 1) != std::string_view::npos) {
      const std::string name = httplib::detail::decode_url(std::string(piece.substr(0, eq)), true);
      ApiError e = api_error(400, "invalid_option",
                             "query option '" + std::string(piece.substr(0, 64)) +
                                 "' holds a second '=': separate options with '&', and write an "
                                 "'=' inside a value as %3D");
      e.path = name.substr(0, 64);
      return e;
    }
    if (amp == std::string_view::npos) break;
    query.remove_prefix(amp + 1);
  }
  return {};
}

bool check_yes_no(const Request& req, Response& res, const char* name) {
  if (!req.has_param(name)) return true;
  const std::string v = req.get_param_value(name);
  if (yes_no(v)) return true;
  send_error(res, not_yes_no(name, v));
  return false;
}

ApiError texture_parts(const Request& req, std::initializer_list<std::string_view> own,
                       TextureFiles& out) {
  for (const auto& [name, part] : req.files) {
    if (std::find(own.begin(), own.end(), name) != own.end()) continue;
    if (!out.emplace(name, part.content).second)
      return api_error(400, "duplicate_part",
                       "part '" + name.substr(0, 200) + "' is sent more than once");
  }
  return {};
}

std::string bearer_token(const Request& req) {
  // One Authorization header (two could name two clients); its scheme in any case (RFC 9110
  // §11.1).
  if (req.get_header_value_count("Authorization") != 1) return {};
  std::string auth = req.get_header_value("Authorization");
  // The scheme, then one or more spaces (RFC 9110 §11.4: 1*SP) before the token.
  const std::string prefix = "bearer ";
  if (auth.size() <= prefix.size()) return {};
  for (std::size_t i = 0; i < prefix.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(auth[i])) != prefix[i]) return {};
  const std::size_t token = auth.find_first_not_of(' ', prefix.size());
  return token == std::string::npos ? std::string() : auth.substr(token);
}

std::string client_of(const Request& req) {
  // Set by the server itself for a roster token (any such header a client sent is dropped).
  if (req.has_header(kClientHeader)) return req.get_header_value(kClientHeader);
  std::string token = bearer_token(req);
  if (!token.empty()) return "token:" + sha256_hex(token).substr(0, 16);
  return "addr:" + req.remote_addr;
}

}  // namespace rayfarm::server
