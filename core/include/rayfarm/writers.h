// Writing a scene out: model file, JSON (both exact round trips of a SceneDesc) and
// POV-Ray SDL (the same geometry, lights, reflectivity and recursion for side-by-side runs).
#pragma once

#include <string>

#include "rayfarm/options.h"
#include "rayfarm/scene.h"
#include "rayfarm/scene_desc.h"

namespace rayfarm {

std::string write_model(const SceneDesc& desc);
// `with_render`: also the scene's own "render" block (the content key leaves it out: it keys
// the options in effect, however they were given).
std::string write_json(const SceneDesc& desc, bool with_render = true);
std::string write_pov(const Scene& scene, const RenderOptions& options);

}  // namespace rayfarm
