// What each kind's POV-Ray export (scene/entities/*.cpp) shares: POV-Ray is left-handed, so
// z is negated; numbers print in their shortest exact form; material i is texture M<i>.
#pragma once

#include <cmath>
#include <limits>
#include <ostream>
#include <string>

#include <glm/vec3.hpp>

#include "rayfarm/options.h"
#include "rayfarm/scene.h"

namespace rayfarm {

struct PovWriter {
  const Scene& scene;
  const RenderOptions& options;
  std::ostream& out;

  static glm::dvec3 flip(glm::dvec3 v) { return {v.x, v.y, -v.z}; }
  // A position or direction of the scene, in POV-Ray's space.
  static std::string at(glm::dvec3 v) { return vec(flip(v)); }
  // A colour or any triple as it is.
  static std::string vec(glm::dvec3 v) {
    v += 0.0;  // -0 prints as 0
    return "<" + num(v.x) + ", " + num(v.y) + ", " + num(v.z) + ">";
  }
  // A number POV-Ray reads: one that overflowed here (a highlight from a specular of 1e308,
  // a texture's scale) is written as the largest finite double, which it takes.
  static std::string num(double v) {
    if (std::isinf(v)) v = std::copysign(std::numeric_limits<double>::max(), v);
    return format_number(v);
  }
  static std::string texture(int material) {
    return "texture { M" + std::to_string(material) + " }";
  }
  // An image file for image_map: its type by its extension, the path a POV-Ray string
  // (a '"' or '\\' in it escaped, so that no path can end the string and write SDL).
  static std::string image_file(const std::string& path) {
    std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
    for (char& c : ext) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
    std::string out = ext == ".png" ? "png \"" : "ppm \"";
    for (char c : path) {
      if (c == '"' || c == '\\') out += '\\';
      out += c;
    }
    return out + "\"";
  }
};

}  // namespace rayfarm
