// The points a bake's accuracy is measured on (`pdsm sweep`, `pdsm bake --target-error`): points on
// receiver surfaces, area-weighted, placed exactly on the triangles (like the end-to-end accuracy
// test: a receiver must not shadow itself, in the bake or the reference), and points in free space,
// uniform in the PDSM window and in depth between the nearest caster and the farthest geometry
// (where dynamic objects would receive shadows). All drawn from a fixed seed: the same scene gives
// the same points.
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
};

// Every point lies inside the PDSM frustum the scene's bake plan fits (its window does not depend
// on the resolution or sample knobs), no nearer than its z_valid_min. A scene without receivers in
// front of the light gets no surface points. Errors: those of PlanBake.
absl::StatusOr<AccuracyPoints> MakeAccuracyPoints(const Scene& scene, int surface_count,
                                                  int free_space_count, uint64_t seed);

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
