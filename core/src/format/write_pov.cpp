// Scene to POV-Ray 3.7 SDL with the same geometry, lights, reflectivity and recursion depth,
// so both renderers do the same work. POV-Ray is left-handed: z is negated. Its lighting is
// not the course's: the ambient term is divided by one typical eye distance instead of each
// ray's length, and lights fade as 1/(1+d) instead of 1/d.
#include <cmath>
#include <sstream>

#include <glm/geometric.hpp>

#include "rayfarm/writers.h"

namespace rayfarm {
namespace {

std::string vec(glm::dvec3 v) {
  v += 0.0;  // -0 (from negating z) prints as 0
  return "<" + format_number(v.x) + ", " + format_number(v.y) + ", " + format_number(v.z) + ">";
}
glm::dvec3 pov(glm::dvec3 v) { return {v.x, v.y, -v.z}; }

}  // namespace

std::string write_pov(const Scene& scene, const RenderOptions& options) {
  std::ostringstream out;
  int ci = scene.find_camera(options.camera).value_or(0);
  const Camera& cam = scene.cameras.at(ci);
  int w = options.width > 0 ? options.width : cam.width;
  int h = options.height > 0 ? options.height : cam.height;

  out << "// Exported by rayfarm. Render with:\n"
      << "//   povray +I<this file> +W" << w << " +H" << h << " -A +WT2 +O<out.png>\n"
      << "#version 3.7;\n"
      << "global_settings { max_trace_level " << options.effective_max_depth() + 1
      << " assumed_gamma 1.0 ambient_light rgb <1, 1, 1> }\n"
      << "background { color rgb " << vec({options.background[0], options.background[1],
                                          options.background[2]})
      << " }\n\n";

  // rayfarm puts pixel x at x/(W-1)*ww; POV-Ray puts pixel centres at (x+0.5)/W of `right`,
  // so `right` is stretched by W/(W-1) to land the same rays on the same pixels.
  double sx = w > 1 ? static_cast<double>(w) / (w - 1) : 1.0;
  double sy = h > 1 ? static_cast<double>(h) / (h - 1) : 1.0;
  glm::dvec3 eye = pov(cam.viewpoint);
  glm::dvec3 centre = pov({cam.world_width / 2, cam.world_height / 2, 0});
  out << "camera {\n  perspective\n  location " << vec(eye) << "\n  direction "
      << vec(centre - eye) << "\n  right " << vec({cam.world_width * sx, 0, 0}) << "\n  up "
      << vec({0, cam.world_height * sy, 0}) << "\n}\n\n";

  for (const Light& l : scene.lights)
    out << "light_source { " << vec(pov(l.location)) << " color rgb " << vec(l.emissivity)
        << " fade_distance 1 fade_power 1" << (options.shadows ? "" : " shadowless") << " }\n";
  out << '\n';

  double typical = 0;
  for (const Sphere& s : scene.spheres) typical += glm::length(s.center - cam.viewpoint);
  typical = scene.spheres.empty() ? 5.0 : typical / scene.spheres.size();
  if (!(typical > 1e-9)) typical = 1;

  for (size_t i = 0; i < scene.materials.size(); ++i) {
    const Material& m = scene.materials[i];
    double highlight = (m.specular.x + m.specular.y + m.specular.z) / 3;
    out << "#declare M" << i << " = texture { // " << m.name << "\n  pigment { color rgb "
        << vec(m.diffuse) << " }\n  finish { ambient " << vec(m.ambient / typical)
        << " diffuse 1";
    if (highlight > 0) {
      out << (options.highlight == Highlight::blinn ? " specular " : " phong ")
          << format_number(highlight) << (options.highlight == Highlight::blinn ? " roughness "
                                                                                 : " phong_size ")
          << format_number(options.highlight == Highlight::blinn ? 1 / m.shininess : m.shininess)
          << " reflection { " << vec(m.specular) << " }";
    }
    out << " }\n}\n";
  }
  out << '\n';

  for (const Sphere& s : scene.spheres)
    out << "sphere { " << vec(pov(s.center)) << ", " << format_number(s.radius)
        << " texture { M" << s.material << " } }\n";
  for (const Plane& p : scene.planes) {
    glm::dvec3 n = glm::normalize(pov(p.normal));
    out << "plane { " << vec(n) << ", " << format_number(glm::dot(n, pov(p.point)))
        << " texture { M" << p.material << " } }\n";
  }
  return out.str();
}

}  // namespace rayfarm
