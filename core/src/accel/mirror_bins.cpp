// Mirror bin construction: each widened sphere reflected in the plane, then binned as the
// primary rays' spheres are (screen_bins.cpp).
#include "accel/mirror_bins.h"

#include <glm/geometric.hpp>
#include <vector>

namespace rayfarm {

ScreenBins build_mirror_bins(const ScreenCamera& camera, std::span<const WidenedSphere> spheres,
                             const glm::dvec3& normal, const glm::dvec3& point, int tile,
                             double max_coverage) {
  const glm::dvec3 n = glm::normalize(normal);
  if (!(glm::dot(n, camera.eye - point) != 0)) return {};  // every primary ray grazes it
  // Spheres wholly behind the plane mirror to the eye's side, where they cannot be met; they
  // are kept (their indices are the bins' sphere numbers) and cost only their rectangles.
  std::vector<WidenedSphere> mirrored(spheres.begin(), spheres.end());
  for (WidenedSphere& s : mirrored) s.centre -= 2 * glm::dot(n, s.centre - point) * n;
  return build_screen_bins(camera, mirrored, tile, max_coverage);
}

}  // namespace rayfarm
