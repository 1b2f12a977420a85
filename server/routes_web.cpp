// The web page: GET / for browsers (curl and scripts still get the JSON index) and
// GET /web/NAME for its scripts and styles, all built into the binary (web_files.h).
#include <optional>
#include <string>
#include <string_view>

#include "http_util.h"
#include "rayfarm/model_parser.h"
#include "routes.h"
#include "web_files.h"

namespace rayfarm::server {
namespace {

using httplib::Request;
using httplib::Response;

// Nothing but this server's own files and the API, images also from blob: and data: URLs (the
// renders the page fetched with its token); no inline script, no framing.
constexpr const char* kPagePolicy =
    "default-src 'self'; img-src 'self' blob: data:; script-src 'self'; style-src 'self'; "
    "connect-src 'self'; object-src 'none'; base-uri 'none'; form-action 'self'; "
    "frame-ancestors 'none'";

void send_web_file(const Request& req, Response& res, const WebFile& file) {
  res.set_header("ETag", std::string(file.etag));
  // Revalidated on every load (a 304 is cheap), so a new rayfarmd's page is never mixed with
  // an old one's scripts.
  res.set_header("Cache-Control", "no-cache");
  res.set_header("X-Content-Type-Options", "nosniff");
  if (file.content_type.rfind("text/html", 0) == 0) {
    res.set_header("Content-Security-Policy", kPagePolicy);
    res.set_header("Referrer-Policy", "no-referrer");
  }
  if (none_match_hits(req, file.etag)) {
    res.status = 304;
    return;
  }
  res.status = 200;
  res.set_content(file.body.data(), file.body.size(), std::string(file.content_type));
}

// The next item of a list separated by `sep`, trimmed; `rest` keeps what follows it.
std::string_view next_item(std::string_view& rest, char sep) {
  const std::size_t at = rest.find(sep);
  const std::string_view item = rest.substr(0, at);
  rest = at == std::string_view::npos ? std::string_view() : rest.substr(at + 1);
  return trim(item);
}

}  // namespace

bool wants_page(const Request& req) {
  const std::string accept = lower_ascii(req.get_header_value("Accept"));  // any case
  // text/html among the media ranges, unless its weight is 0 ("not acceptable", RFC 9110).
  for (std::string_view ranges(accept); !ranges.empty();) {
    std::string_view range = next_item(ranges, ',');
    if (next_item(range, ';') != "text/html") continue;
    double q = 1;
    while (!range.empty()) {
      const std::string_view param = next_item(range, ';');
      if (param.starts_with("q="))
        if (const std::optional<double> w = parse_number(param.substr(2))) q = *w;
    }
    return q > 0;
  }
  return false;
}

void get_page(Service&, const Request& req, Response& res) {
  const WebFile* page = find_web_file("index.html");
  if (!page) return send_error(res, 404, "not_found", "this rayfarmd was built without its page");
  send_web_file(req, res, *page);
}

void get_web_file(Service&, const Request& req, Response& res) {
  const std::string name = req.matches[1];
  const WebFile* file = find_web_file(name);
  if (!file) return send_error(res, 404, "not_found", "no file /web/" + name.substr(0, 100));
  send_web_file(req, res, *file);
}

}  // namespace rayfarm::server
