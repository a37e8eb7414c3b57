// Attenuation at any world point from a PDSM (thesis ch. 4): project the point into the PDSM,
// evaluate the four neighbouring pixels' functions at its depth and blend the results
// bilinearly (results are filtered, never depths).
#ifndef PDSM_CORE_PDSM_PDSM_QUERY_H_
#define PDSM_CORE_PDSM_PDSM_QUERY_H_

#include <glm/glm.hpp>

#include "core/pdsm/pdsm_image.h"

namespace pdsm {

// Fraction of the light hidden from p_world, in [0, 1]; NaN outside the PDSM frustum (behind
// the light plane or outside the window). Pixels at the border clamp to the edge.
double QueryAttenuation(const PdsmImage& pdsm, const glm::dvec3& p_world);

// The same at a located point (pixel coordinates with centres at k + 0.5).
double BilinearAttenuation(const PdsmImage& pdsm, const PdsmPoint& point);

// Light samples behind the attenuation at p_world: header.samples for fixed-count bakes, the
// tile's count (of the pixel holding the point) for adaptive ones; 0 outside the frustum.
// The attenuation's sampling resolution is 1 / this.
int SamplesAt(const PdsmImage& pdsm, const glm::dvec3& p_world);

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_PDSM_QUERY_H_
