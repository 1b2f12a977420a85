// Root-form error analysis on a scene's primary rays.
#include "rayfarm/stability.h"

#include <cmath>

#include "rayfarm/intersect.h"

namespace rayfarm {
namespace {

template <class T>
struct Closest {
  int sphere = -1;
  T t = 0;
};

template <class T>
Closest<T> closest_sphere(const Scene& scene, const Vec3<T>& o, const Vec3<T>& d, RootForm form) {
  Closest<T> best;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const Sphere* sp = scene.objects[i].as<Sphere>();
    if (!sp) continue;
    const Sphere& s = *sp;
    Vec3<T> c(static_cast<T>(s.center.x), static_cast<T>(s.center.y), static_cast<T>(s.center.z));
    T r = static_cast<T>(s.radius);
    auto roots = form == RootForm::stable ? sphere_roots(o, d, c, r) : sphere_roots_naive(o, d, c, r);
    if (!roots) continue;
    T t = roots->near > 0 ? roots->near : roots->far;
    if (t > 0 && (best.sphere < 0 || t < best.t)) best = {static_cast<int>(i), t};
  }
  return best;
}

template <class T>
Vec3<T> ray_direction(const Camera& cam, int w, int h, double fx, double fy, Vec3<T>& eye) {
  eye = Vec3<T>(static_cast<T>(cam.viewpoint.x), static_cast<T>(cam.viewpoint.y),
                static_cast<T>(cam.viewpoint.z));
  T px = (w == 1 ? T(0.5) : static_cast<T>(fx) / static_cast<T>(w - 1)) *
         static_cast<T>(cam.world_width);
  T py = (h == 1 ? T(0.5) : static_cast<T>(fy) / static_cast<T>(h - 1)) *
         static_cast<T>(cam.world_height);
  return glm::normalize(Vec3<T>(px, py, T(0)) - eye);
}

}  // namespace

std::string_view to_string(RootForm form) { return form == RootForm::stable ? "stable" : "naive"; }

RootErrors root_errors(const Scene& scene, const RenderOptions& options, RootForm form,
                       Precision precision, long long max_rays) {
  RootErrors out;
  out.form = form;
  out.precision = precision;
  auto cam_index = scene.find_camera(options.camera);
  if (!cam_index) return out;
  const Camera& cam = scene.cameras[*cam_index];
  int w = options.width > 0 ? options.width : cam.width;
  int h = options.height > 0 ? options.height : cam.height;
  // Sample a grid of at most max_rays pixels of the full-size image.
  long long pixels = static_cast<long long>(w) * h;
  int step = 1;
  while (pixels / (static_cast<long long>(step) * step) > max_rays) ++step;
  for (int y = 0; y < h; y += step)
    for (int x = 0; x < w; x += step) {
      ++out.rays;
      Vec3<long double> eye_ref;
      Vec3<long double> d_ref = ray_direction<long double>(cam, w, h, x, y, eye_ref);
      Closest<long double> ref = closest_sphere(scene, eye_ref, d_ref, RootForm::stable);
      int got_sphere;
      long double got_t;
      if (precision == Precision::f32) {
        Vec3<float> eye;
        Vec3<float> d = ray_direction<float>(cam, w, h, x, y, eye);
        auto c = closest_sphere(scene, eye, d, form);
        got_sphere = c.sphere;
        got_t = c.t;
      } else {
        Vec3<double> eye;
        Vec3<double> d = ray_direction<double>(cam, w, h, x, y, eye);
        auto c = closest_sphere(scene, eye, d, form);
        got_sphere = c.sphere;
        got_t = c.t;
      }
      out.reference_hits += ref.sphere >= 0;
      if ((ref.sphere >= 0) != (got_sphere >= 0)) {
        ++out.wrong_hit_miss;
      } else if (ref.sphere != got_sphere) {
        ++out.wrong_object;
      } else if (ref.sphere >= 0) {
        double rel = static_cast<double>(std::fabs(got_t - ref.t) / ref.t);
        if (rel > out.max_relative_t_error) out.max_relative_t_error = rel;
      }
    }
  return out;
}

}  // namespace rayfarm
