// Attenuation at any world point from a PDSM (thesis ch. 4): project the point into the PDSM,
// evaluate the four neighbouring pixels' functions at its depth and blend the results
// bilinearly (results are filtered, never depths).
#ifndef PDSM_CORE_PDSM_PDSM_QUERY_H_
#define PDSM_CORE_PDSM_PDSM_QUERY_H_

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

#include "core/pdsm/attenuation_function.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

// Fraction of the light hidden from p_world, in [0, 1]; NaN outside the PDSM frustum (behind
// the light plane or outside the window). Pixels at the border clamp to the edge.
double QueryAttenuation(const PdsmImage& pdsm, const glm::dvec3& p_world);

// The same at a located point (pixel coordinates with centres at k + 0.5).
double BilinearAttenuation(const PdsmImage& pdsm, const PdsmPoint& point);

// The blend of BilinearAttenuation with the pixels' functions from `function_at(x, y)` (any
// callable giving std::span<const Vertex>): a PDSM held whole or read tile by tile gives the
// same number, bit for bit.
template <typename FunctionAt>
double BilinearAttenuationOf(const PdsmGeometry& g, const PdsmPoint& point,
                             FunctionAt&& function_at) {
  const double fx = point.px - 0.5;
  const double fy = point.py - 0.5;
  const double x_floor = std::floor(fx);
  const double y_floor = std::floor(fy);
  const double wx = fx - x_floor;
  const double wy = fy - y_floor;
  const int x0 = std::clamp(static_cast<int>(x_floor), 0, g.width - 1);
  const int y0 = std::clamp(static_cast<int>(y_floor), 0, g.height - 1);
  const int x1 = std::clamp(static_cast<int>(x_floor) + 1, 0, g.width - 1);
  const int y1 = std::clamp(static_cast<int>(y_floor) + 1, 0, g.height - 1);
  const double a00 = EvaluateAttenuation(function_at(x0, y0), point.z);
  const double a10 = EvaluateAttenuation(function_at(x1, y0), point.z);
  const double a01 = EvaluateAttenuation(function_at(x0, y1), point.z);
  const double a11 = EvaluateAttenuation(function_at(x1, y1), point.z);
  return (1 - wy) * ((1 - wx) * a00 + wx * a10) + wy * ((1 - wx) * a01 + wx * a11);
}

// Light samples behind the attenuation at p_world: header.samples for fixed-count bakes, the
// tile's count (of the pixel holding the point) for adaptive ones; 0 outside the frustum.
// The attenuation's sampling resolution is 1 / this.
int SamplesAt(const PdsmImage& pdsm, const glm::dvec3& p_world);

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_PDSM_QUERY_H_
