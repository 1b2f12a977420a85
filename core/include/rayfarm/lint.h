// Warnings for legal but suspicious scenes (`rayfarm check`).
#pragma once

#include "rayfarm/diagnostic.h"
#include "rayfarm/options.h"
#include "rayfarm/scene.h"

namespace rayfarm {

// Adds warnings: a light inside a sphere, the eye inside a sphere, an object behind the eye,
// a material never used, a scene that renders entirely black, a camera option naming no camera.
void lint_scene(const Scene& scene, const RenderOptions& options, Diagnostics& diags);

}  // namespace rayfarm
