// ApiError's JSON body and its constructors.
#include "api_error.h"

#include <utility>

namespace rayfarm::server {

ApiError api_error(int status, std::string code, std::string message) {
  ApiError e;
  e.status = status;
  e.code = std::move(code);
  e.message = std::move(message);
  return e;
}

ApiError limit_error(const std::string& limit, const std::string& message) {
  ApiError e = api_error(422, "limit_exceeded", message);
  e.limit = limit;
  return e;
}

ApiError scene_error(const Diagnostics& diags) {
  const Diagnostic* first = diags.first_error();
  ApiError e = api_error(400, "invalid_scene", first ? first->message : "invalid scene");
  if (first) {
    e.line = first->where.line;
    e.column = first->where.column;
    e.path = first->where.path;
  }
  e.details = nlohmann::json::array();
  for (const Diagnostic& d : diags.items())
    if (d.severity == Severity::error) e.details.push_back(diagnostic_json(d));
  return e;
}

nlohmann::json diagnostic_json(const Diagnostic& d) {
  nlohmann::json item = {{"code", d.code}, {"message", d.message}};
  if (d.where.line > 0) {
    item["line"] = d.where.line;
    item["column"] = d.where.column;
  }
  if (!d.where.path.empty()) item["path"] = d.where.path;
  return item;
}

nlohmann::json ApiError::body() const {
  nlohmann::json e = {{"code", code}, {"message", message}};
  if (line > 0) {
    e["line"] = line;
    e["column"] = column;
  }
  if (!path.empty()) e["path"] = path;
  if (!limit.empty()) e["limit"] = limit;
  if (!details.is_null()) e["errors"] = details;
  return {{"error", e}};
}

}  // namespace rayfarm::server
