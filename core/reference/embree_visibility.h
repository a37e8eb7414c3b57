// Monte-Carlo reference attenuation by ray tracing (Embree 3): from each point, occlusion rays to
// `samples` stratified samples on the light (rect, disk) or in the sun's cone; the attenuation is
// the hidden count / samples. Works for every light shape, unlike the exact polygon-projection
// method (exact_visibility.h), and is what `pdsm reference --method embree` prints.
//
// Convergence (docs/accuracy.md, measured against the exact method on examples/plates): each point
// draws its own jittered stratification, so errors are independent between points and unbiased; the
// standard deviation per point is at most sqrt(A(1-A)/N) <= 0.5/sqrt(N) (the plain Monte-Carlo
// bound) and, for a point whose light is cut by a straight shadow edge, falls like N^-3/4.
// EmbreeErrorBound below is the stated bound; measured: mean error N^-0.74.
//
// Robustness: geometry is rebased in double on the light centre (the casters' centre for a sun)
// before it is rounded to Embree's floats. A point on a surface is never shadowed by that surface:
// hits on a triangle whose plane holds the point (to 1e-9 of the scene's size, the exact method's
// margin) are rejected in double precision by a filter, and the ray starts a few float roundings
// away from the point, so rounding cannot make a receiver hide itself.
#ifndef PDSM_CORE_REFERENCE_EMBREE_VISIBILITY_H_
#define PDSM_CORE_REFERENCE_EMBREE_VISIBILITY_H_

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "core/reference/light_weighting.h"
#include "core/scene/scene.h"

namespace pdsm {

inline constexpr int kDefaultReferenceSamples = 4096;

// The worst-case standard deviation of one point's estimate with N samples (plain Monte Carlo;
// stratification only lowers it).
inline double EmbreeErrorBound(int samples) { return 0.5 / std::sqrt(double(samples)); }

// Attenuation (hidden fraction of the light, [0,1]) of world points; NaN for a point at or behind
// the light plane (rect, disk) or not finite. Deterministic in (scene, points, samples, seed)
// whatever the thread count. INVALID_ARGUMENT for samples outside [1, 1<<20] or a bad mesh;
// INTERNAL when Embree fails.
// `weighting` (light_weighting.h): each sample counts with its weight (cos θ_light / r² for a
// planar light's emitter weighting, times max(0, cos θ_receiver) for irradiance) instead of 1;
// NaN where every weight is 0 (the light wholly behind the receiver's plane).
absl::StatusOr<std::vector<double>> EmbreeAttenuation(const Scene& scene,
                                                      std::span<const glm::dvec3> points_world,
                                                      int samples, uint64_t seed = 1,
                                                      const WeightingSpec& weighting = {});

}  // namespace pdsm

#endif  // PDSM_CORE_REFERENCE_EMBREE_VISIBILITY_H_
