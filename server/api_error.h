// An error as the API answers it: HTTP status, a stable code, a message, and where in the
// scene or which limit when known.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "rayfarm/diagnostic.h"

namespace rayfarm::server {

struct ApiError {
  int status = 0;  // 0: no error
  std::string code;
  std::string message;
  int line = 0;
  int column = 0;
  std::string path;   // JSON path
  std::string limit;  // the limit's name, for 422
  int retry_after = 0;
  nlohmann::json details;  // e.g. all errors of a scene

  explicit operator bool() const { return status != 0; }
  nlohmann::json body() const;
};

ApiError api_error(int status, std::string code, std::string message);
// 422 over the named limit.
ApiError limit_error(const std::string& limit, const std::string& message);
// 400 invalid_scene: the first error's place, and every error.
ApiError scene_error(const Diagnostics& diags);
// One error or warning as the API shows it: code, message, and line/column or path.
nlohmann::json diagnostic_json(const Diagnostic& d);

}  // namespace rayfarm::server
