// Exact attenuation for planar polygonal lights and triangle occluders: the fraction of the
// light's area hidden from a point p is area(light ∩ ∪ projections of the occluders from p
// onto the light plane) / area(light), in double precision. The union's area comes from its
// boundary (Green's theorem, shared edges recognised exactly): Boost.Geometry 1.74's booleans
// return wrong areas on tessellated meshes (boostorg/geometry #838, #1068, #1229), so it only
// cross-checks this code in the tests. This is the ground truth the bake is measured against.
#ifndef PDSM_CORE_REFERENCE_EXACT_VISIBILITY_H_
#define PDSM_CORE_REFERENCE_EXACT_VISIBILITY_H_

#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "core/reference/light_weighting.h"
#include "core/scene/scene.h"

namespace pdsm {

// All in light space (light plane z = 0, scene at z > 0). `light_polygon` is a simple polygon
// in the plane (x, y), either orientation. `triangles` holds 3 vertices per triangle; parts
// of triangles at z <= 0 or at z >= p.z (not between light and point) are clipped away.
// Returns a value in [0, 1]: the hidden share of the light's area, or with `weighting`
// (light_weighting.h) of its solid angle from p (emitter) or its projected solid angle on the
// plane through p of unit normal `normal_light` (irradiance; NaN when a vertex of the light is
// not strictly in front of that plane).
double ExactHiddenFraction(std::span<const glm::dvec2> light_polygon,
                           std::span<const glm::dvec3> triangles, const glm::dvec3& p_light,
                           LightWeighting weighting = LightWeighting::kUnweighted,
                           const glm::dvec3& normal_light = glm::dvec3(0.0));

// Exact attenuation of world points for a scene's casters, NaN behind the light. Rect lights are
// exact; disk lights use an inscribed 512-gon (relative area error < 3e-5). Sun: UNIMPLEMENTED.
// `weighting` (light_weighting.h): the hidden share of the light's area, of its solid angle
// (emitter), or of its projected solid angle on the receiver plane of `weighting.normal_world`
// (irradiance; NaN at a point where part of the light lies behind that plane).
absl::StatusOr<std::vector<double>> ExactAttenuation(const Scene& scene,
                                                     std::span<const glm::dvec3> points_world,
                                                     const WeightingSpec& weighting = {});

}  // namespace pdsm

#endif  // PDSM_CORE_REFERENCE_EXACT_VISIBILITY_H_
