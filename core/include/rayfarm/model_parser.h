// The brace-delimited model file of the course (docs/model-format.md) into a SceneDesc.
#pragma once

#include <string_view>

#include "rayfarm/diagnostic.h"
#include "rayfarm/scene_desc.h"

namespace rayfarm {

// Parses syntax and value shapes; reports every error found (up to the cap). The result is
// meaningful only when `diags` has no errors.
SceneDesc parse_model(std::string_view text, Diagnostics& diags);

// Strict decimal number: [+-]? (digits [. digits?] | . digits) ([eE] [+-]? digits)?
// Rejects nan, inf, hex, trailing garbage and overflow. On failure returns nullopt and sets
// `why` to a short reason.
std::optional<double> parse_number(std::string_view token, std::string* why = nullptr);

}  // namespace rayfarm
