// How a light's points count towards the attenuation (issue #15 item 4). pdsm bakes the
// *unweighted* fraction: the share of the light's area (a sun's cone of directions) hidden from a
// point. A renderer's shadow ratio weights each light point by what it sends to the point. Two
// weighted definitions, both available in the references (`pdsm reference --weighting`):
//
// - kEmitter: each point of the light by cos θ_light / r² (per unit area), i.e. by the solid angle
//   it covers seen from the point: the attenuation is the fraction of the light's *solid angle*
//   hidden. It depends only on the point's position, so a PDSM could store it. A sun's directions
//   and a sphere's (already sampled by solid angle) weigh the same under it as unweighted.
// - kIrradiance: cos θ_light · cos θ_receiver / r², with the receiver's normal given: the ratio of
//   a Lambertian surface's direct irradiance with and without the casters, what Cycles, Lightmass
//   or any path tracer computes on that surface. It needs the normal, which a PDSM cannot know
//   for points it has never seen (objects added after the bake).
#ifndef PDSM_CORE_REFERENCE_LIGHT_WEIGHTING_H_
#define PDSM_CORE_REFERENCE_LIGHT_WEIGHTING_H_

#include <string>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "core/geometry/light_frame.h"
#include "core/scene/scene.h"  // LightWeighting

namespace pdsm {

struct WeightingSpec {
  LightWeighting kind = LightWeighting::kUnweighted;
  // kIrradiance only: the receiver's unit normal in world space (the side facing the light).
  glm::dvec3 normal_world{0.0};

  // The normal in `frame`'s light space (rotated only).
  glm::dvec3 NormalInLightSpace(const LightFrame& frame) const {
    return {glm::dot(normal_world, frame.u), glm::dot(normal_world, frame.v),
            glm::dot(normal_world, frame.n)};
  }
};

// "unweighted", "emitter", "irradiance"; INVALID_ARGUMENT naming `flag` otherwise.
absl::StatusOr<LightWeighting> ParseLightWeighting(const std::string& text,
                                                   const std::string& flag);
const char* LightWeightingName(LightWeighting weighting);

}  // namespace pdsm

#endif  // PDSM_CORE_REFERENCE_LIGHT_WEIGHTING_H_
