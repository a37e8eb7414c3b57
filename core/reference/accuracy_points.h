// The points a bake's accuracy is measured on (`pdsm sweep`, `pdsm bake --target-error`): points on
// receiver surfaces, area-weighted, placed exactly on the triangles (like the end-to-end accuracy
// test: a receiver must not shadow itself, in the bake or the reference), points in free space,
// uniform in the PDSM window and in depth between the nearest caster and the farthest geometry,
// and points in a band just above the receivers (where dynamic objects receive shadows: free
// space is mostly far from any penumbra and dilutes a mean). All drawn from a fixed seed: the
// same scene gives the same points.
#ifndef PDSM_CORE_REFERENCE_ACCURACY_POINTS_H_
#define PDSM_CORE_REFERENCE_ACCURACY_POINTS_H_

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "core/scene/scene.h"

namespace pdsm {

struct AccuracyPoints {
  std::vector<glm::dvec3> surface;     // world
  std::vector<glm::dvec3> free_space;  // world
  std::vector<glm::dvec3> band;        // world: the volume band just above the receivers
  double band_height = 0;              // what the band was drawn with
};

// How many points of each kind. The band is where objects added after the bake go: a receiver
// point (area-weighted, as `surface`) moved along its triangle's normal, on the side facing the
// light, by a height uniform in (0, band_height]. band_height 0 means DefaultBandHeight.
struct AccuracyPointCounts {
  int surface = 0, free_space = 0, band = 0;
  double band_height = 0;
};

// Every point lies inside the PDSM frustum the scene's bake plan fits (its window does not depend
// on the resolution or sample knobs), no nearer than its z_valid_min; a band point that would not
// is drawn again. A scene without receivers in front of the light gets no surface or band
// points. INVALID_ARGUMENT for a negative or non-finite band_height; otherwise the errors of
// PlanBake.
absl::StatusOr<AccuracyPoints> MakeAccuracyPoints(const Scene& scene,
                                                  const AccuracyPointCounts& counts, uint64_t seed);

// Half the depth range that holds the casters above the farthest geometry (the plan's
// z_far - z_near, along the light's normal): the band reaches halfway up to the casters, where
// penumbrae are widest and objects stand. World units. Errors: those of PlanBake.
absl::StatusOr<double> DefaultBandHeight(const Scene& scene);

// Mean, 95th percentile and maximum of |estimate - reference| over the points whose reference
// is finite (`count` of them). An estimate that is NaN there -- the PDSM does not know the point:
// nearer than its z_valid_min, or off a surfaces-only bake's windows -- counts as the worst
// error, 1, and in `unknown`: a bake is never scored on fewer points than another.
struct ErrorStats {
  double mean = 0, p95 = 0, max = 0;
  size_t count = 0;
  size_t unknown = 0;
};
ErrorStats CompareAttenuation(const std::vector<double>& estimate,
                              const std::vector<double>& reference);

}  // namespace pdsm

#endif  // PDSM_CORE_REFERENCE_ACCURACY_POINTS_H_
