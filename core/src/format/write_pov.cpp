// Scene to POV-Ray 3.7 SDL with the same geometry, lights, reflectivity and recursion depth,
// so both renderers do the same work. POV-Ray is left-handed: z is negated. Its lighting is
// not the course's: the ambient term is divided by one typical eye distance instead of each
// ray's length, and lights fade as 1/(1+d) instead of 1/d.
#include <cmath>
#include <sstream>

#include <glm/geometric.hpp>

#include "rayfarm/writers.h"
#include "scene/registry.h"

namespace rayfarm {
namespace {

std::string vec(glm::dvec3 v) { return PovWriter::vec(v); }
std::string num(double v) { return PovWriter::num(v); }
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

  PovWriter writer{scene, options, out};
  for (size_t i = 0; i < scene.lights.size(); ++i)
    entity_hooks(kind_of(scene.lights[i])).pov(writer, static_cast<int>(i));
  out << '\n';

  double typical = 0;
  std::size_t spheres = 0;
  for (const Object& o : scene.objects)
    if (const Sphere* s = o.as<Sphere>()) {
      typical += glm::length(s->center - cam.viewpoint);
      ++spheres;
    }
  typical = spheres == 0 ? 5.0 : typical / spheres;
  if (!(typical > 1e-9)) typical = 1;

  for (size_t i = 0; i < scene.materials.size(); ++i) {
    const Material& m = scene.materials[i];
    const double shininess = m.shininess.value_or(32);
    double highlight = (m.specular.x + m.specular.y + m.specular.z) / 3;
    out << "#declare M" << i << " = texture { // " << m.name << "\n  pigment { color rgb "
        << vec(m.diffuse);
    if (m.transparency > 0) out << " transmit " << num(m.transparency);
    out << " }\n  finish { ambient " << vec(m.ambient / typical) << " diffuse 1";
    if (highlight > 0) {
      out << (options.highlight == Highlight::blinn ? " specular " : " phong ")
          << num(highlight) << (options.highlight == Highlight::blinn ? " roughness "
                                                                                 : " phong_size ")
          << num(options.highlight == Highlight::blinn ? 1 / std::max(shininess, 1e-9)
                                                                 : shininess)
          << " reflection { " << vec(m.specular) << " }";
    }
    out << " }\n}\n";
  }
  out << '\n';

  for (size_t i = 0; i < scene.objects.size(); ++i)
    entity_hooks(scene.objects[i].kind).pov(writer, static_cast<int>(i));
  return out.str();
}

}  // namespace rayfarm
