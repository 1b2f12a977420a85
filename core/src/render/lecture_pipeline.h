// The lecture profile's way of turning a tile of pixels into colours: its camera mapping
// and stratified sampler, screen bins for primary rays where they were built, and the
// Whitted tracer (tracer.h).
#pragma once

#include <algorithm>
#include <optional>
#include <vector>

#include "render/prepared_scene.h"
#include "render/sampler.h"
#include "render/tile_grid.h"
#include "render/tracer.h"

namespace rayfarm {

template <class T>
class LecturePipeline {
 public:
  explicit LecturePipeline(PreparedScene<T> scene)
      : s_(std::move(scene)), sampler_(s_.spp) {}

  int width() const { return s_.width; }
  int height() const { return s_.height; }
  int spp() const { return s_.spp; }
  int samples_per_pass() const { return 1; }
  std::vector<std::string> parts() const { return s_.features.parts(); }

  // The colours of one pass (one sample per pixel) of a tile, rows top to bottom; false
  // when canceled part way. The error of the pixel means is the caller's (one sample each).
  template <class Canceled>
  bool render_tile(const TileBounds& b, int pass, std::vector<glm::dvec3>& out,
                   RayCounts& counts, double& /*error*/, Canceled&& canceled) const {
    out.resize(static_cast<size_t>(b.width()) * b.rows());
    Tracer<T> tracer(s_);
    // Where each sample is its pixel's byte (Features::byte_cutoff: one pass of TiledRender),
    // paths stop once that is settled.
    tracer.stop_at_settled_bytes(Film{s_.rounding});
    const bool binned = !s_.screen_bins.empty() || !s_.mirror_bins.empty();
    // Kept by each render thread from tile to tile. Made anew, these buffers (the bounces
    // growing a dozen times) took malloc's lock some ten times a tile, which the render
    // threads contend for when they share an arena (the command line keeps one, for a heap
    // on huge pages: docs/performance.md, nineteenth round).
    thread_local std::vector<PrimaryRay> rays;
    thread_local std::vector<BounceRay> bounces;
    rays.clear();
    bounces.clear();
    if (binned) {
      first_hits(b, pass, tracer, rays);
      if (!s_.mirror_bins.empty()) bounce_hits(b, tracer, rays, bounces);
    }
    glm::dvec3* px = out.data();
    for (int r = b.r0; r < b.r1; ++r) {
      if (canceled()) return false;
      const int y = s_.height - 1 - r;  // the top image row is world row H-1
      for (int x = b.x0; x < b.x1; ++x) {
        Vec3<T> c;
        if (binned) {
          const PrimaryRay& ray = rays[static_cast<size_t>(r - b.r0) * b.width() + (x - b.x0)];
          c = ray.dir ? tracer.primary(*ray.dir, ray.hit,
                                       ray.bounce >= 0 ? &bounces[ray.bounce].hit : nullptr)
                      : tracer.primary(pixel_point(x, y, pass));
        } else {
          c = tracer.primary(pixel_point(x, y, pass));
        }
        *px++ = glm::dvec3(c);
      }
    }
    counts = tracer.counts;
    return true;
  }

  const PreparedScene<T>& scene() const { return s_; }

  // The world point on the screen of pixel (x, image row r) in pass `pass`: the one
  // render_tile traces (whose closest hit, found through screen bins or not, is the one
  // Tracer::closest finds).
  Vec3<T> screen_point_of(int x, int r, int pass) const {
    return pixel_point(x, s_.height - 1 - r, pass);
  }

 private:
  struct PrimaryRay {
    std::optional<Vec3<T>> dir;
    Hit<T> hit;
    int bounce = -1;  // its reflection ray's entry in the tile's BounceRays, if it has one
  };

  // A reflection ray off a plane with mirror bins, sent by a primary ray.
  struct BounceRay {
    typename Tracer<T>::Bounce ray;
    int plane;   // index into s_.planes
    T t_primary;  // the primary ray's distance to the plane
    Hit<T> hit;
  };

  // The closest hit of every primary ray of the tile, from its screen bin: each sphere is
  // tested only on the pixels of its rectangle, nearest spheres first, and skipped on pixels
  // where something nearer than all of it was already hit. Ties go by Hit::beaten_by, as in
  // Tracer::closest, so the hits are the loop's.
  void first_hits(const TileBounds& b, int pass, const Tracer<T>& tracer,
                  std::vector<PrimaryRay>& rays) const {
    const int w = b.width();
    rays.resize(static_cast<size_t>(w) * b.rows());
    const T t_max = s_.max_dist;
    const bool binned = !s_.screen_bins.empty();
    for (int r = b.r0; r < b.r1; ++r) {
      for (int x = b.x0; x < b.x1; ++x) {
        PrimaryRay& ray = rays[static_cast<size_t>(r - b.r0) * w + (x - b.x0)];
        ray = {tracer.primary_direction(pixel_point(x, s_.height - 1 - r, pass)), Hit<T>{}};
        if (!ray.dir) continue;
        // Planes and other shapes first, so spheres behind their hits are skipped (shapes
        // with bins of their own come next).
        if (binned)
          tracer.closest_plane(s_.eye, *ray.dir, Origin{}, t_max, ray.hit, s_.shape_bins.empty());
        else  // mirror bins only: the primary hits come from the hierarchy
          ray.hit = tracer.closest(s_.eye, *ray.dir, Origin{}, t_max);
      }
    }
    if (!binned) return;
    const TileGrid grid(s_.width, s_.height);
    const int tile = (b.r0 / kTileSize) * grid.tiles_x + b.x0 / kTileSize;
    const int shape_base = s_.shape_base();
    const std::span<const ScreenBinEntry> shapes =
        s_.shape_bins.empty() ? std::span<const ScreenBinEntry>() : s_.shape_bins.of_tile(tile);
    thread_local RevsurfBatch<T, PrimaryRay*> batch;  // per thread, as render_tile's buffers
    batch.clear();  // nothing left from a tile that threw part way
    auto test_shapes = [&](bool searched) {
      for (const ScreenBinEntry& e : shapes) {
        const PreparedShape<T>& shape = s_.shapes[e.sphere];
        if (is_searched(shape) != searched) continue;
        const int index = shape_base + e.sphere;
        auto take = [&](PrimaryRay* ray, T t) {
          if (t > 0 && t <= t_max && ray->hit.beaten_by(t, index)) ray->hit = {t, index};
        };
        if (searched) {  // all of the rectangle's rays searched at once
          for_rectangle(e, b, rays.data(), [&](PrimaryRay& ray) {
            if (ray.dir && !(e.near > static_cast<double>(ray.hit.t)))
              batch.add(shape, s_.eye, *ray.dir, &ray);
          });
          batch.run(shape, take);
          continue;
        }
        for_rectangle(e, b, rays.data(), [&](PrimaryRay& ray) {
          if (ray.dir) take(&ray, shape_t(shape, s_.eye, *ray.dir, index, Origin{}));
        });
      }
    };
    test_shapes(false);
    for (const ScreenBinEntry& e : s_.screen_bins.of_tile(tile)) {
      const PreparedSphere<T>& sp = s_.spheres[e.sphere];
      const double near = e.near;
      for_rectangle(e, b, rays.data(), [&](PrimaryRay& ray) {
        Hit<T>& best = ray.hit;
        if (!ray.dir || near > static_cast<double>(best.t)) return;
        const T t = sphere_t(s_.eye, *ray.dir, sp.centre, sp.radius, e.sphere, Origin{});
        if (t > 0 && t <= t_max && best.beaten_by(t, e.sphere)) best = {t, e.sphere};
      });
    }
    test_shapes(true);
  }

  // Flat shapes go before the spheres and are never skipped by their near bound: a grazing
  // ray's plane distance can fall short of it by far more than the rounding of the point it
  // finds. A surface of revolution is searched, at tens of times a sphere's cost, so it goes
  // after them and is skipped where a nearer hit than all of it is known: its crossing is a
  // point where the computed |radial|² − r² changes sign, within rounding of the surface,
  // hence in the widened sphere about its box, at a distance no less than that sphere's.
  static bool is_searched(const PreparedShape<T>& shape) {
    return shape.kind == PreparedShape<T>::revsurf;
  }

  // The closest hit of each reflection ray the tile's primary rays send off planes with
  // mirror bins, from those bins: each mirrored sphere is tested only on the pixels of its
  // rectangle, nearest the eye first, and skipped where a hit nearer than all of it (by
  // mirror_near) is known. Planes and other shapes go first, as in Tracer::closest, and ties
  // go by Hit::beaten_by, so the hits are the loop's. Rays starting beyond mirror_reach are
  // left to the tracer.
  void bounce_hits(const TileBounds& b, const Tracer<T>& tracer, std::vector<PrimaryRay>& rays,
                   std::vector<BounceRay>& bounces) const {
    const int base = s_.plane_base();
    const int planes = static_cast<int>(s_.mirror_bins.size());
    unsigned used = 0;  // planes with rays here (bit 31: any beyond the 31st)
    for (PrimaryRay& ray : rays) {
      const int j = ray.hit.object - base;
      if (!ray.dir || j < 0 || j >= planes || s_.mirror_bins[j].empty()) continue;
      const auto bounce = tracer.primary_bounce(*ray.dir, ray.hit);
      if (!bounce) continue;
      const glm::dvec3 o = glm::abs(glm::dvec3(bounce->origin));
      if (!(std::max({o.x, o.y, o.z}) <= s_.mirror_reach)) continue;
      ray.bounce = static_cast<int>(bounces.size());
      bounces.push_back({*bounce, j, ray.hit.t, Hit<T>{}});
      BounceRay& br = bounces.back();
      tracer.closest_plane(br.ray.origin, br.ray.dir, br.ray.from, br.ray.t_max, br.hit,
                           shape_bins(j) == nullptr);
      used |= 1u << std::min(j, 31);
    }
    if (bounces.empty()) return;
    thread_local RevsurfBatch<T, BounceRay*> batch;
    batch.clear();
    const TileGrid grid(s_.width, s_.height);
    const int tile = (b.r0 / kTileSize) * grid.tiles_x + b.x0 / kTileSize;
    for (int j = 0; j < planes; ++j) {
      if (!(used & (1u << std::min(j, 31))) || s_.mirror_bins[j].empty()) continue;
      // Flat shapes first, on every pixel of their rectangles, then the spheres, then the
      // searched shapes where no hit nearer than all of them is known (as in first_hits).
      const std::span<const ScreenBinEntry> shapes =
          shape_bins(j) ? shape_bins(j)->of_tile(tile) : std::span<const ScreenBinEntry>();
      auto test_shapes = [&](bool searched) {
        for (const ScreenBinEntry& e : shapes) {
          const PreparedShape<T>& shape = s_.shapes[e.sphere];
          if (is_searched(shape) != searched) continue;
          const int index = s_.shape_base() + e.sphere;
          auto take = [&](BounceRay* br, T t) {
            if (t > 0 && t <= br->ray.t_max && br->hit.beaten_by(t, index)) br->hit = {t, index};
          };
          for_rectangle(e, b, rays.data(), [&](const PrimaryRay& ray) {
            if (ray.bounce < 0) return;
            BounceRay& br = bounces[ray.bounce];
            if (br.plane != j ||
                (searched && mirror_near(e.near, static_cast<double>(br.t_primary),
                                         s_.mirror_slack) > static_cast<double>(br.hit.t)))
              return;
            // A searched shape's rays are searched at once, unless one leaves it (which a
            // ray off a plane does not).
            if (searched && index != br.ray.from.object)
              batch.add(shape, br.ray.origin, br.ray.dir, &br);
            else
              take(&br, shape_t(shape, br.ray.origin, br.ray.dir, index, br.ray.from));
          });
          if (searched) batch.run(shape, take);
        }
      };
      test_shapes(false);
      for (const ScreenBinEntry& e : s_.mirror_bins[j].of_tile(tile)) {
        const PreparedSphere<T>& sp = s_.spheres[e.sphere];
        for_rectangle(e, b, rays.data(), [&](const PrimaryRay& ray) {
          if (ray.bounce < 0) return;
          BounceRay& br = bounces[ray.bounce];
          if (br.plane != j || mirror_near(e.near, static_cast<double>(br.t_primary),
                                           s_.mirror_slack) > static_cast<double>(br.hit.t))
            return;
          const T t =
              sphere_t(br.ray.origin, br.ray.dir, sp.centre, sp.radius, e.sphere, br.ray.from);
          if (t > 0 && t <= br.ray.t_max && br.hit.beaten_by(t, e.sphere)) br.hit = {t, e.sphere};
        });
      }
      test_shapes(true);
    }
  }

  // Calls f on each of the tile's rays (row by row, `rays` of width b.width()) that lies in
  // entry e's pixel rectangle.
  template <class F>
  static void for_rectangle(const ScreenBinEntry& e, const TileBounds& b, PrimaryRay* rays, F&& f) {
    const int w = b.width();
    const int ex0 = std::max<int>(e.x0, b.x0), ex1 = std::min<int>(e.x1, b.x1 - 1);
    const int er0 = std::max<int>(e.r0, b.r0), er1 = std::min<int>(e.r1, b.r1 - 1);
    for (int r = er0; r <= er1; ++r) {
      PrimaryRay* ray = rays + static_cast<size_t>(r - b.r0) * w + (ex0 - b.x0);
      for (int x = ex0; x <= ex1; ++x, ++ray) f(*ray);
    }
  }

  // Plane j's mirror bins over the other shapes, if the scene has shapes and they were built.
  const ScreenBins* shape_bins(int j) const {
    return j < static_cast<int>(s_.mirror_shape_bins.size()) && !s_.mirror_shape_bins[j].empty()
               ? &s_.mirror_shape_bins[j]
               : nullptr;
  }

  // The world point of pixel (x, y) in pass `pass` (jittered when supersampling).
  Vec3<T> pixel_point(int x, int y, int pass) const {
    if (s_.spp <= 1) return screen_point(x, y, 0, 0);
    PixelOffset o = sampler_.offset(s_.seed, x, y, pass);
    return screen_point(x, y, o.u, o.v);
  }

  // The world point of pixel (x, y) displaced by (u, v) pixels (the lecture's camera).
  Vec3<T> screen_point(int x, int y, double u, double v) const {
    auto fraction = [](int i, int count, double offset) {
      if (count == 1) return T(0.5) + static_cast<T>(offset);
      return (static_cast<T>(i) + static_cast<T>(offset)) / static_cast<T>(count - 1);
    };
    return {fraction(x, s_.width, u) * s_.world_width, fraction(y, s_.height, v) * s_.world_height,
            T(0)};
  }

  PreparedScene<T> s_;
  StratifiedSampler sampler_;
};

}  // namespace rayfarm
