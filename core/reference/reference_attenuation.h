// The reference attenuation `pdsm reference`, `pdsm sweep` and `pdsm bake --target-error` measure
// bakes against: the exact polygon-projection method (exact_visibility.h) or Embree's Monte-Carlo
// estimate (embree_visibility.h), chosen by ReferenceMethod.
#ifndef PDSM_CORE_REFERENCE_REFERENCE_ATTENUATION_H_
#define PDSM_CORE_REFERENCE_REFERENCE_ATTENUATION_H_

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "core/reference/embree_visibility.h"
#include "core/reference/light_weighting.h"
#include "core/scene/scene.h"

namespace pdsm {

// kAuto: exact for rect lights (no sampling error at all), Embree otherwise (disk: the exact
// method's 512-gon is close but Embree samples the true disk; sun: only Embree applies; and
// alpha-tested casters, whose holes only Embree's per-hit test sees).
enum class ReferenceMethod { kAuto, kExact, kEmbree };

// "auto", "exact", "embree"; INVALID_ARGUMENT naming `flag` otherwise.
absl::StatusOr<ReferenceMethod> ParseReferenceMethod(const std::string& text,
                                                     const std::string& flag);
// What kAuto resolves to for this scene's light and casters.
ReferenceMethod ResolveReferenceMethod(ReferenceMethod method, const Scene& scene);
// Whether any caster of `scene` is alpha-tested (core/scene/alpha_mask.h).
bool HasAlphaTestedCasters(const Scene& scene);
const char* ReferenceMethodName(ReferenceMethod method);

struct ReferenceOptions {
  ReferenceMethod method = ReferenceMethod::kAuto;
  int samples = kDefaultReferenceSamples;  // Embree only
  uint64_t seed = 1;                       // Embree only
  WeightingSpec weighting = {};            // light_weighting.h; default unweighted (the bake's)
};

// Attenuation of world points, NaN behind the light. Errors: UNIMPLEMENTED for the exact method on
// a sun light; INVALID_ARGUMENT for irradiance weighting without a finite non-zero normal (it is
// normalised here); see ExactAttenuation and EmbreeAttenuation for the rest.
absl::StatusOr<std::vector<double>> ReferenceAttenuation(const Scene& scene,
                                                         std::span<const glm::dvec3> points,
                                                         const ReferenceOptions& options);

}  // namespace pdsm

#endif  // PDSM_CORE_REFERENCE_REFERENCE_ATTENUATION_H_
