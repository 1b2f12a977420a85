// The reference program's trace (docs/profiles.md §2–§10), object by object in file order.
#include "render/cpsc102/reference_tracer.h"

#include <algorithm>
#include <cmath>

#include "render/cpsc102/revsurf_ref.h"
#include "util/saturate.h"

namespace rayfarm::cpsc102 {
namespace {

// A texel of `image` for the frame coordinates (qx, qy) of a window w × h: mode 0 stretches
// the image over the window, bottom row of the file at qy = 0. As in the program, an index
// one past the end reads on in memory; it is kept inside the image here.
const std::uint8_t* texel(const Image& image, double qx, double qy, double w, double h) {
  const int tx = saturating_trunc(static_cast<X>(qx) / w * image.width);
  const int ty = saturating_trunc(static_cast<X>(qy) / h * image.height);
  long long index = static_cast<long long>(image.height - 1 - ty) * image.width + tx;
  index = std::clamp<long long>(index, 0, static_cast<long long>(image.width) * image.height - 1);
  return image.rgb.data() + 3 * index;
}

// Colour channels times a texel, over 256 as the program divided.
V3 filtered(const V3& c, const std::uint8_t* t) {
  V3 out;
  for (int i = 0; i < 3; ++i) out[i] = R(static_cast<X>(c[i]) * t[i] / 256);
  return out;
}

}  // namespace

double ReferenceSearch::test(int k, const V3& base, const V3& dir) {
  const RefObject& o = s_.objects[k];
  if (o.kind == RefObject::sphere) {
    const V3 v = sub(base, o.center);
    const double a = dot(dir, dir);
    const double b = R(2 * static_cast<X>(dot(v, dir)));
    const double c = R(static_cast<X>(dot(v, v)) - static_cast<X>(o.radius) * o.radius);
    const double disc = R(static_cast<X>(b) * b - 4 * static_cast<X>(a) * c);
    if (!(disc > 0)) return kMiss;
    const double t = R((-static_cast<X>(b) - std::sqrt(static_cast<X>(disc))) / (2 * static_cast<X>(a)));
    stored_[k] = along(base, dir, t);
    return t > 0 ? t : kMiss;
  }
  if (o.kind == RefObject::revsurf) {
    double t;
    if (!revsurf_hit(o, base, dir, t)) return kMiss;
    stored_[k] = along(base, dir, t);
    return t;
  }
  // The plane kinds and triangles: the plane first.
  const double nd = dot(dir, o.normal);
  if (nd == 0) return kMiss;
  const double t = R((static_cast<X>(o.n_dot_point) - dot(o.normal, base)) / nd);
  if (!(t > 0)) return kMiss;
  const V3 p = along(base, dir, t);
  stored_[k] = p;
  if (p.z > 0.01) return kMiss;  // in front of the screen
  switch (o.kind) {
    case RefObject::fplane:
    case RefObject::texplane: {
      const V3 q = sub(p, o.point);
      const double qx = dot(o.frame.row0, q), qy = dot(o.frame.row1, q);
      if (!(qx >= 0 && qx <= o.width && qy >= 0 && qy <= o.height)) return kMiss;
      break;
    }
    case RefObject::triangle: {
      const V3 q = sub(p, o.point);
      const double qx = dot(o.frame.row0, q), qy = dot(o.frame.row1, q);
      // Inside or on an edge: the point is on the same side of all three edges.
      int pos = 0, neg = 0;
      for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3;
        const X side = (static_cast<X>(o.tx[j]) - o.tx[i]) * (static_cast<X>(qy) - o.ty[i]) -
                       (static_cast<X>(o.ty[j]) - o.ty[i]) * (static_cast<X>(qx) - o.tx[i]);
        pos += side > 0;
        neg += side < 0;
      }
      if (pos > 0 && neg > 0) return kMiss;
      break;
    }
    default:
      break;
  }
  return t;
}

int ReferenceSearch::closest(const V3& base, const V3& dir, int skip, double& t) {
  if (!s_.bvh.empty()) return closest_bvh(base, dir, skip, t);
  int best = -1;
  t = 0;
  const int n = static_cast<int>(s_.objects.size());
  for (int k = 0; k < n; ++k) {
    if (k == skip) continue;
    const double tk = test(k, base, dir);
    if (tk > 0 && (best < 0 || tk < t)) {
      best = k;
      t = tk;
    }
  }
  return best;
}

int ReferenceSearch::closest_bvh(const V3& base, const V3& dir, int skip, double& t) {
  int best = -1;
  t = 0;
  auto consider = [&](int k) {
    if (k == skip) return;
    const double tk = test(k, base, dir);
    if (tk > 0 && (best < 0 || tk < t || (tk == t && k < best))) {
      best = k;
      t = tk;
    }
  };
  for (std::int32_t k : s_.always) consider(k);
  BvhRay ray;
  if (ray.init(base, dir, s_.bvh.scale)) {
    const float no_limit = std::numeric_limits<float>::infinity();
    bvh_closest(s_.bvh, ray, best < 0 ? no_limit : float_limit_up(t),
                [&](std::int32_t first, std::int32_t count) {
                  for (std::int32_t i = first; i < first + count; ++i) consider(s_.bvh.order[i]);
                  return best < 0 ? no_limit : float_limit_up(t);
                });
  } else {  // too far out for the hierarchy's float boxes: every object
    for (int k = 0; k < static_cast<int>(s_.objects.size()); ++k) consider(k);
  }
  for (int k : watched_)
    if (k != skip) test(k, base, dir);  // its stored point, as the program's full search left it
  return best;
}

V3 ReferenceSearch::normal_at(int k, const V3& p) const {
  const RefObject& o = s_.objects[k];
  if (o.kind == RefObject::sphere) return unit(sub(p, o.center));
  if (o.kind == RefObject::revsurf) return revsurf_normal(o, p);
  return o.normal;
}

void ReferenceSearch::surface(int k, const V3& p, V3& ambient, V3& diffuse) const {
  const RefObject& o = s_.objects[k];
  const RefMaterial* m = &s_.materials[o.material];
  if (o.kind == RefObject::tiled) {
    int ix, iy;
    if (o.world_xz) {
      ix = saturating_trunc((static_cast<X>(p.x) + 10000) / o.width);
      iy = saturating_trunc((static_cast<X>(p.z) + 10000) / o.height);
      // 2009: even squares are the foreground; only the ambient colour alternates.
      ambient = (ix + iy) % 2 == 0 ? m->ambient : s_.materials[o.alt_material].ambient;
      diffuse = m->diffuse;
      return;
    }
    const double qx = dot(o.frame.row0, p), qy = dot(o.frame.row1, p);
    ix = saturating_trunc(static_cast<X>(qx) / o.width + 10000);
    iy = saturating_trunc(static_cast<X>(qy) / o.height + 10000);
    if ((ix + iy) % 2 == 0) m = &s_.materials[o.alt_material];
    ambient = m->ambient;
    diffuse = m->diffuse;
    return;
  }
  ambient = m->ambient;
  diffuse = m->diffuse;
  if (o.kind == RefObject::texplane && o.texture && o.texture->width > 0) {
    const V3 q = sub(p, o.point);
    const double qx = dot(o.frame.row0, q), qy = dot(o.frame.row1, q);
    const Image& img = *o.texture;
    const std::uint8_t* t;
    if (o.mode == 0) {
      t = texel(img, qx, qy, o.width, o.height);
    } else {
      // One texel per pixel of world size, repeated.
      int tx = saturating_trunc(static_cast<X>(qx) / s_.texel_width) % img.width;
      int ty = saturating_trunc(static_cast<X>(qy) / s_.texel_height) % img.height;
      if (tx < 0) tx += img.width;  // only off the window, where no hit is
      if (ty < 0) ty += img.height;
      t = img.rgb.data() + 3 * (static_cast<long long>(img.height - 1 - ty) * img.width + tx);
    }
    ambient = filtered(ambient, t);
    diffuse = filtered(diffuse, t);
  }
}

template <bool kRecord>
V3 ReferenceTracer<kRecord>::illuminate(int j, int k, const V3& p, const V3& n, int base_owner,
                                        const V3& origin, const V3& diffuse) {
  const RefLight& light = s_.lights[j];
  const V3 lv = sub(light.location, p);
  const double d = length(lv);
  const V3 l = unit(lv);
  const double cos = dot(n, l);
  RecordedLight* lr =
      recording() ? &rec_->light(static_cast<int>(rec_->hits.size()) - 1, j) : nullptr;
  if (lr) {
    lr->distance = d;
    lr->n_dot_l = cos;
    lr->diffuse_distance = d;
  }
  if (!(cos > 0)) {
    if (lr) lr->status = d > 0 ? RecordedLight::faces_away : RecordedLight::at_point;
    return {};
  }
  V3 e = light.emissivity;
  auto missed = [&](RecordedLight::Status status) {
    if (lr) lr->status = status;
    return V3{};
  };
  if (light.kind == LightKind::spot) {
    if (!(dot(unit(sub(p, light.location)), light.direction) > light.cos_theta))
      return missed(RecordedLight::outside_cone);
  } else if (light.kind == LightKind::projector) {
    const V3 v = unit(sub(p, light.location));
    const double nd = dot(v, light.normal);
    if (nd == 0) return missed(RecordedLight::off_slide);
    const double t = R((static_cast<X>(light.n_dot_point) - dot(light.normal, light.location)) / nd);
    if (!(t > 0)) return missed(RecordedLight::off_slide);
    const V3 q = sub(along(light.location, v, t), light.point);
    const double qx = dot(light.frame.row0, q), qy = dot(light.frame.row1, q);
    if (!(qx >= 0 && qx <= light.width && qy >= 0 && qy <= light.height))
      return missed(RecordedLight::off_slide);
    if (!light.texture || light.texture->width == 0) return missed(RecordedLight::off_slide);
    e = filtered(e, texel(*light.texture, qx, qy, light.width, light.height));
  }
  // The shadow ray walks on through translucent objects, each filtering the light. (With
  // shadows off no search runs, so no hit point is overwritten by one either.)
  V3 from = p;
  int skip = k;
  double remaining = d;
  double d_diffuse = d;
  const int last = static_cast<int>(s_.objects.size()) - 1;
  if (s_.shadows) ++counts.shadow;
  // Each step passes one object, which a straight line meets a few times at most; coincident
  // translucent surfaces could otherwise hand the ray back and forth without end.
  const int max_steps = 4 * static_cast<int>(s_.objects.size()) + 8;
  for (int step = 0; s_.shadows; ++step) {
    if (step == max_steps) return missed(RecordedLight::shadowed);
    double t;
    const int m = closest(from, l, skip, t);
    if (m < 0 || !(t < remaining)) break;
    const RefMaterial& mm = s_.materials[s_.objects[m].material];
    if (lr && (mm.transparency == 0 || lr->blocker < 0)) lr->blocker = m;
    if (mm.transparency == 0) return missed(RecordedLight::shadowed);
    if (lr) lr->status = RecordedLight::filtered;
    e = mul(e, mm.filter);
    from = stored_[m];
    // docs/profiles.md §6: a translucent sphere that is the last object the search tested leaves the
    // diffuse term divided by the distance from where the shadow ray met it to the light.
    if (s_.objects[m].kind == RefObject::sphere && m == (skip == last ? last - 1 : last))
      d_diffuse = length(sub(light.location, from));
    skip = m;
    remaining = length(sub(light.location, from));
  }
  V3 c;
  for (int i = 0; i < 3; ++i)
    c[i] = R(static_cast<X>(diffuse[i]) * e[i] * cos / d_diffuse);
  if (lr) {
    lr->emissivity = {e.x, e.y, e.z};
    lr->diffuse = {c.x, c.y, c.z};
    lr->diffuse_distance = d_diffuse;
  }
  const RefMaterial& mat = s_.materials[s_.objects[k].material];
  if (mat.shininess != 0) {
    // The glint looks from the ray's origin, which for a secondary ray is the point its
    // object's hit test last stored: the shadow searches above may have moved it.
    const V3 base = base_owner < 0 ? origin : stored_[base_owner];
    const V3 v = unit(sub(base, p));
    const V3 h = unit(add(v, l));
    const double glint = std::pow(dot(n, h), mat.shininess);
    for (int i = 0; i < 3; ++i)
      c[i] = R(c[i] + static_cast<X>(R(static_cast<X>(e[i]) * mat.specular[i])) * glint);
    if (lr) {
      lr->highlight_base = dot(n, h);
      for (int i = 0; i < 3; ++i) lr->specular[i] = R(static_cast<X>(c[i]) - lr->diffuse[i]);
    }
  }
  return c;
}

template <bool kRecord>
V3 ReferenceTracer<kRecord>::trace(const V3& base, int base_owner, const V3& dir, double total,
                                   int last, int depth) {
  const int rec = recording() ? record_ray(base, dir, total, depth) : -1;
  if (total > s_.max_dist || rays_left_-- <= 0) {
    if (recording()) rec_->hits[rec].capped = total > s_.max_dist;
    return s_.background;
  }
  return shade(base, base_owner, dir, total, last, depth, rec);
}

template <bool kRecord>
V3 ReferenceTracer<kRecord>::shade(const V3& base, int base_owner, const V3& dir, double total,
                                   int last, int depth, int rec) {
  double t;
  const int k = closest(base, dir, last, t);
  if (k < 0) return s_.background;
  total = R(static_cast<X>(total) + t);
  const V3 p = stored_[k];
  const V3 n = normal_at(k, p);
  const RefMaterial& m = s_.materials[s_.objects[k].material];
  // A reflected ray leaves from stored_[k] as the program passed it, after this hit's
  // shadow walks and the transmitted ray's searches (which may test k) have run: it must
  // change as the program's searches changed it.
  const bool secondary = depth < s_.max_depth && (m.transparency != 0 || m.reflects);
  if (secondary) watched_.push_back(k);
  V3 ambient, diffuse;
  surface(k, p, ambient, diffuse);
  if (recording()) {
    RecordedHit& h = rec_->hits[rec];
    h.object = k;
    h.t = t;
    h.travelled = total;
    h.point = {p.x, p.y, p.z};
    h.normal = {n.x, n.y, n.z};
    h.ambient = {ambient.x, ambient.y, ambient.z};
    h.diffuse_colour = {diffuse.x, diffuse.y, diffuse.z};
    h.specular = {m.specular.x, m.specular.y, m.specular.z};
    h.shininess = m.shininess;
  }
  V3 c = ambient;
  for (int j = 0; j < static_cast<int>(s_.lights.size()); ++j)
    c = add(c, illuminate(j, k, p, n, base_owner, base, diffuse));
  for (int i = 0; i < 3; ++i) c[i] = R(static_cast<X>(c[i]) / total);
  if (recording()) rec_->hits[rec].local = rec_->hits[rec].value = {c.x, c.y, c.z};
  if (!secondary) return c;
  if (m.transparency != 0) {
    ++counts.reflection;
    if (recording()) {
      RecordedHit& h = rec_->hits[rec];
      h.keep = R(1 - static_cast<X>(m.transparency));
      h.filter = {m.filter.x, m.filter.y, m.filter.z};
      h.transmitted = static_cast<int>(rec_->hits.size());
      next_ray_ = RecordedHit::Ray::transmitted;
      next_parent_ = rec;
    }
    const V3 through = trace(p, k, dir, total, k, depth + 1);
    c = add(scale(c, R(1 - static_cast<X>(m.transparency))), mul(through, m.filter));
  }
  if (m.reflects) {
    // The reflected ray leaves from the object's stored hit point, as the program passed it.
    ++counts.reflection;
    const V3 from = stored_[k];
    const V3 nk = normal_at(k, from);
    const V3 r = sub(dir, scale(nk, R(2 * static_cast<X>(dot(nk, dir)))));
    if (recording()) {
      RecordedHit& h = rec_->hits[rec];
      h.weight = {m.specular.x, m.specular.y, m.specular.z};
      h.reflected = static_cast<int>(rec_->hits.size());
      next_ray_ = RecordedHit::Ray::reflected;
      next_parent_ = rec;
    }
    c = add(c, mul(m.specular, trace(from, k, r, total, k, depth + 1)));
  }
  watched_.pop_back();
  if (recording()) rec_->hits[rec].value = {c.x, c.y, c.z};
  return c;
}

template <bool kRecord>
int ReferenceTracer<kRecord>::record_ray(const V3& base, const V3& dir, double total, int depth) {
  const int rec = rec_->begin(next_ray_, next_parent_, depth);
  RecordedHit& h = rec_->hits[rec];
  h.origin = {base.x, base.y, base.z};
  h.direction = {dir.x, dir.y, dir.z};
  h.travelled = total;
  h.value = h.local = {s_.background.x, s_.background.y, s_.background.z};
  return rec;
}

template <bool kRecord>
V3 ReferenceTracer<kRecord>::primary(double wx, double wy) {
  ++counts.primary;
  const V3 dir = unit(sub(V3{wx, wy, 0}, s_.eye));
  rays_left_ = kMaxRaysPerPixel;
  if constexpr (kRecord) {
    next_ray_ = RecordedHit::Ray::primary;
    next_parent_ = -1;
  }
  return trace(s_.eye, -1, dir, 0, -1, 0);
}

template class ReferenceTracer<false>;
template class ReferenceTracer<true>;

}  // namespace rayfarm::cpsc102
