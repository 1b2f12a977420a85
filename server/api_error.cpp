// ApiError's JSON body and the plain constructor.
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
