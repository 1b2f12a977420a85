// The handlers of the routes (docs/http-api.md), one function each, named after method and path;
// HttpApi binds them to their paths.
#pragma once

#include <httplib.h>

#include <map>
#include <optional>
#include <set>
#include <string>

#include "service.h"

namespace rayfarm::server {

using RouteHandler = void (*)(Service&, const httplib::Request&, httplib::Response&);

// routes_render.cpp
void post_render(Service& svc, const httplib::Request& req, httplib::Response& res);

// routes_jobs.cpp
void get_job(Service& svc, const httplib::Request& req, httplib::Response& res);
void delete_job(Service& svc, const httplib::Request& req, httplib::Response& res);
void get_job_image(Service& svc, const httplib::Request& req, httplib::Response& res);
void get_job_events(Service& svc, const httplib::Request& req, httplib::Response& res);
void get_jobs(Service& svc, const httplib::Request& req, httplib::Response& res);

// routes_compare.cpp
void post_compare(Service& svc, const httplib::Request& req, httplib::Response& res);
// Submits a render and waits for its image, holding the caller's waiting slot.
std::optional<Image> render_and_wait(Service& svc, const Slot& slot, const std::string& scene,
                                     const Params& params, const std::string& client,
                                     const TextureFiles& textures, const SubmitHow& how,
                                     ApiError& error, std::string* job_id);
// The query parameters, and the multipart fields (parts without a file name) named in `names`;
// the first name given twice goes to `repeated` (the first value is kept).
std::map<std::string, std::string> request_fields(const httplib::Request& req,
                                                  const std::set<std::string>& names,
                                                  std::string* repeated = nullptr);

// routes_grade.cpp
void post_grade(Service& svc, const httplib::Request& req, httplib::Response& res);

// routes_check.cpp
void post_check(Service& svc, const httplib::Request& req, httplib::Response& res);

// http_api.cpp: GET / lists the routes; the methods a known path takes ("" when unknown).
void get_index(Service& svc, const httplib::Request& req, httplib::Response& res);
std::string allowed_methods(const std::string& path);

// routes_web.cpp: the web page (for a request that accepts text/html) and its files.
bool wants_page(const httplib::Request& req);
void get_page(Service& svc, const httplib::Request& req, httplib::Response& res);
void get_web_file(Service& svc, const httplib::Request& req, httplib::Response& res);

// routes_info.cpp
void get_samples(Service& svc, const httplib::Request& req, httplib::Response& res);
void get_healthz(Service& svc, const httplib::Request& req, httplib::Response& res);
void get_metrics(Service& svc, const httplib::Request& req, httplib::Response& res);

}  // namespace rayfarm::server
