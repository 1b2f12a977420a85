// Warnings for legal but suspicious scenes (`rayfarm check`).
#pragma once

#include <string_view>

#include "rayfarm/diagnostic.h"
#include "rayfarm/options.h"
#include "rayfarm/scene.h"

namespace rayfarm {

// Adds warnings: a light inside a sphere, the eye inside a sphere, an object behind the eye,
// a material never used, a scene that renders entirely black, a camera option naming no camera;
// and one error, "image-too-large": an image that render_image would refuse for its size, for
// the camera the options choose and, with `every_camera` (check), for each other camera at
// its own size. A render looks only at its own camera.
void lint_scene(const Scene& scene, const RenderOptions& options, Diagnostics& diags,
                bool every_camera = true);

// Its one error alone, where warnings would not be shown (render --quiet): a scene's objects
// are not walked.
void lint_image_size(const Scene& scene, const RenderOptions& options, Diagnostics& diags);

// Adds a warning (codes "course-...") wherever the course's reference program (CPSC 102,
// 2014-18) would stop on or misread this model file: comments, unknown entities or attributes,
// attribute order, missing or undefined materials, value counts, long names, `<x,y,z>` vectors,
// glued braces. Works on the raw text, so also on files rayfarm itself rejects.
void lint_course(std::string_view text, Diagnostics& diags);

}  // namespace rayfarm
