// What the service offers and how it is: GET /samples, /healthz and /metrics.
#include "http_util.h"
#include "routes.h"

namespace rayfarm::server {

using httplib::Request;
using httplib::Response;
using Json = nlohmann::json;

void get_samples(Service& svc, const Request& req, Response& res) {
  if (!check_query(req, res, "GET /samples", {})) return;
  Json list = Json::array();
  for (const Sample& s : svc.samples())
    list.push_back({{"name", s.name},
                    {"description", s.description},
                    {"render", "/render?sample=" + s.name}});
  send_json(res, 200, {{"samples", list}});
}

void get_healthz(Service& svc, const Request& req, Response& res) {
  if (!check_query(req, res, "GET /healthz", {})) return;
  Json health = svc.health();
  const bool redis_down = health.contains("redis") && health["redis"]["status"] != "ok";
  if (redis_down) res.set_header("Retry-After", "2");
  send_json(res, svc.shutting_down() || redis_down ? 503 : 200, health);
}

void get_metrics(Service& svc, const Request& req, Response& res) {
  if (!check_query(req, res, "GET /metrics", {})) return;
  res.set_content(svc.metrics_text(), "text/plain; version=0.0.4");
}

}  // namespace rayfarm::server
