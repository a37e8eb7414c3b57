// The frustum a PDSM is fitted to (docs/algorithms.md, "Depth range"): the bounds of what lies
// in front of the light, projected. Two ways to the same bits: every triangle, or the scene's
// clusters (core/bake/scene_index.h) pruned where their box cannot move any bound. Every bound
// is a minimum or a maximum of per-triangle values computed the same way, so the order and the
// pruning change nothing.
#ifndef PDSM_CORE_BAKE_WINDOW_FIT_H_
#define PDSM_CORE_BAKE_WINDOW_FIT_H_

#include <limits>
#include <vector>

#include "core/bake/scene_index.h"
#include "core/pdsm/pdsm_geometry.h"
#include "core/scene/scene.h"

namespace pdsm {

// Light-space bounds: s, t are x / z (perspective, clamped to the light's widest window) or
// x, y (the sun); depths are z.
struct WindowFit {
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  double s_lo = kInf, s_hi = -kInf, t_lo = kInf, t_hi = -kInf;
  double z_near_casters = kInf, z_far_all = -kInf;
  double z_near_receivers = kInf;
  // The nearest caster depth anywhere in front of the light, inside the window or not: where
  // the window is stretched by geometry near the light plane (the refit in PlanBake).
  double z_near_casters_anywhere = kInf;
  bool empty() const { return s_lo > s_hi; }
};

// What is fitted: the light (its frame and projection from `g`), the depth from which
// perspective triangles count (they are clipped there; triangles wholly nearer are skipped for
// either projection), and whether only receivers count.
struct FitRequest {
  const LightSpec& light;
  const PdsmGeometry& g;
  double z_min = 0;
  bool receivers_only = false;
};

// Every triangle of `meshes`, one by one.
WindowFit FitEveryTriangle(const std::vector<TriangleMesh>& meshes, const FitRequest& request);

// The same bits from the index's clusters: a box whose light-space bounds cannot lower or
// raise any bound found so far is skipped with everything in it. REQUIRES: the index was
// built from a scene with these meshes.
// `triangles_fitted`, when given, counts the triangles it computed (a light's neighbourhood,
// the farthest and the nearest, not the world).
WindowFit FitIndexed(const SceneIndex& index, const FitRequest& request,
                     size_t* triangles_fitted = nullptr);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_WINDOW_FIT_H_
