// The JSON scene format (docs/json-format.md): parsing into a SceneDesc and writing one out.
#pragma once

#include <string>
#include <string_view>

#include "rayfarm/diagnostic.h"
#include "rayfarm/scene_desc.h"

namespace rayfarm {

constexpr int kMaxJsonDepth = 64;

SceneDesc parse_json_scene(std::string_view text, Diagnostics& diags);

}  // namespace rayfarm
