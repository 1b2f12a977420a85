// Numerical stability of the ray/sphere root: the textbook and the cancellation-free forms
// in float and double against a long-double reference, on the primary rays of a scene.
#pragma once

#include <string>

#include "rayfarm/options.h"
#include "rayfarm/scene.h"

namespace rayfarm {

enum class RootForm { stable, naive };
std::string_view to_string(RootForm form);

struct RootErrors {
  RootForm form = RootForm::stable;
  Precision precision = Precision::f64;
  long long rays = 0;
  long long reference_hits = 0;
  long long wrong_hit_miss = 0;  // hit where the reference misses, or the other way round
  long long wrong_object = 0;    // both hit, but not the same sphere
  double max_relative_t_error = 0;  // over rays where both hit the same sphere
};

// Primary rays through the pixel points of the camera (at most `max_rays`, by sampling the
// image at a reduced size), closest sphere hit by `form` in `precision`, against the stable
// form in long double. Planes are left out: both forms treat them alike.
RootErrors root_errors(const Scene& scene, const RenderOptions& options, RootForm form,
                       Precision precision, long long max_rays = 160 * 120);

}  // namespace rayfarm
