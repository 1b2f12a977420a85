// The course's reference program as a tracer (the cpsc102 profile): its trace and
// illumination as docs/profiles.md states them, every object in file order, its arithmetic
// (x87.h), and its accidents: hits in front of the screen ignored, paths cut at max_dist,
// and reflected rays whose glint looks from a hit point that later hit tests overwrote.
#pragma once

#include <cstdint>
#include <vector>

#include "render/cpsc102/reference_scene.h"
#include "render/ray_counts.h"
#include "render/recorder.h"

namespace rayfarm::cpsc102 {

// The program recursed for every reflected and transmitted ray; so does this tracer, up to
// this depth (options.h).
inline constexpr int kMaxRecursion = kCpsc102MaxDepth;
// Rays one primary ray may spawn: reflection and transmission together branch, so a scene
// of translucent mirrors would otherwise double its rays at every bounce.
inline constexpr int kMaxRaysPerPixel = 1 << 14;

// The program's searches: its hit tests, which leave their points behind, and the
// surfaces they find. Shared by the tracers with and without a recorder.
class ReferenceSearch {
 public:
  explicit ReferenceSearch(const RefScene& scene) : s_(scene), stored_(scene.objects.size()) {}

  RayCounts counts;

 protected:
  static constexpr double kMiss = -1;

  // One object's hit test: t > 0 when hit. Like the program's, it leaves behind in
  // stored_[k] the point it computed, even for a hit it then rejects.
  double test(int k, const V3& base, const V3& dir);
  // The nearest object (file order breaks ties) with t > 0, skipping `skip` entirely.
  int closest(const V3& base, const V3& dir, int skip, double& t);
  // The same through the hierarchy.
  int closest_bvh(const V3& base, const V3& dir, int skip, double& t);
  V3 normal_at(int k, const V3& p) const;
  // The material colours at p: tiles and textures change ambient and diffuse.
  void surface(int k, const V3& p, V3& ambient, V3& diffuse) const;

  const RefScene& s_;
  std::vector<V3> stored_;  // per object: the last point its hit test computed
  // Objects whose stored point is still to be read (by a glint, or by a reflected ray still
  // to leave). The program tested every object in every search; with a hierarchy that skips
  // some, these are tested anyway, so their stored points are the program's.
  std::vector<int> watched_;
};

// With kRecord, a tracer can write each path it traces to a recorder (explain.cpp); a
// render's tracer has none of that code compiled in.
template <bool kRecord = false>
class ReferenceTracer : public ReferenceSearch {
 public:
  using ReferenceSearch::ReferenceSearch;

  // The colour of the primary ray through the screen point (wx, wy, 0), unclamped.
  V3 primary(double wx, double wy);

  // From now on each traced path is written to `recorder` (cleared by the caller per
  // sample); null: none is.
  void record(Recorder* recorder) requires kRecord { rec_ = recorder; }

 private:
  bool recording() const { return kRecord && rec_; }

  V3 trace(const V3& base, int base_owner, const V3& dir, double total, int last, int depth);
  // The rest of trace() once the ray is followed (`rec`: its recorder entry). Out of line,
  // so that the rays cut short (past max_dist) cost trace() only its first test.
  [[gnu::noinline]] V3 shade(const V3& base, int base_owner, const V3& dir, double total, int last,
                             int depth, int rec);
  // `origin` is the ray's origin: the eye for a primary ray; a secondary ray's glint looks
  // from its `base_owner`'s stored point instead.
  V3 illuminate(int light, int object, const V3& p, const V3& n, int base_owner, const V3& origin,
                const V3& diffuse);
  // The recorder's entry for a ray about to be traced (as next_ray_ from next_parent_).
  int record_ray(const V3& base, const V3& dir, double total, int depth);

  int rays_left_ = 0;  // of the current primary ray's budget
  Recorder* rec_ = nullptr;  // only with kRecord
  RecordedHit::Ray next_ray_ = RecordedHit::Ray::primary;
  int next_parent_ = -1;
};

}  // namespace rayfarm::cpsc102
