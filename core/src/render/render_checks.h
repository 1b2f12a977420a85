// What a render refuses before it starts, in one place for RenderJob::create and the
// explanations (explain.cpp), so that both refuse the same things with the same words.
#pragma once

#include <optional>
#include <string>

#include "rayfarm/options.h"
#include "rayfarm/scene.h"

namespace rayfarm {

// An unknown camera, an image too large, a texture not read, options the profile cannot
// follow. The camera's index, or nullopt with `error` (optional) set.
std::optional<int> check_render(const Scene& scene, const RenderOptions& options,
                                std::string* error);

}  // namespace rayfarm
