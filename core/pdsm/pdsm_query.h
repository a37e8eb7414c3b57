// Attenuation at any world point from a PDSM (thesis ch. 4): project the point into the PDSM,
// evaluate the four neighbouring pixels' functions at its depth and blend the results
// bilinearly (results are filtered, never depths).
#ifndef PDSM_CORE_PDSM_PDSM_QUERY_H_
#define PDSM_CORE_PDSM_PDSM_QUERY_H_

#include <algorithm>
#include <cmath>
#include <span>

#include <glm/glm.hpp>

#include "core/pdsm/attenuation_function.h"
#include "core/pdsm/pdsm_image.h"
#include "core/pdsm/refined_pixel.h"

namespace pdsm {

// Fraction of the light hidden from p_world, in [0, 1]; NaN outside the PDSM frustum (behind
// the light plane or outside the window). Pixels at the border clamp to the edge.
double QueryAttenuation(const PdsmImage& pdsm, const glm::dvec3& p_world);

// The same at a located point (pixel coordinates with centres at k + 0.5).
double BilinearAttenuation(const PdsmImage& pdsm, const PdsmPoint& point);

// BilinearAttenuation's blend, with the pixels' functions from `function_at(x, y)` (any
// callable giving std::span<const Vertex>, called once for each of the four pixels; every span
// it gives must stay valid until this returns): a PDSM held whole or read tile by tile gives
// the same number, bit for bit.
//
// Refined pixels (core/pdsm/refined_pixel.h): where one of the four pixels is refined at the
// point's depth (by f, the finest such), the point blends the four rays around it of the
// lattice of sub-pixels of refinement f, each read from the pixel holding it
// (LatticeAttenuation: its sub-pixel's function, or its own function where that is undefined),
// provided one of them is a sub-pixel defined there (a receiver within a sub-pixel). So a
// refined pixel's rays meet its neighbours' own functions at its edge, not their centres half a
// pixel away. Everywhere else the four pixels' own functions are blended: unrefined files, and
// refined ones away from their receivers, read exactly as the unrefined bake. The lattice rays
// around a point lie in the four pixels around it, so the rule reads no other pixel.
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
  const std::span<const Vertex> f00 = function_at(x0, y0), f10 = function_at(x1, y0),
                                f01 = function_at(x0, y1), f11 = function_at(x1, y1);
  int f = 1;
  for (const std::span<const Vertex> p : {f00, f10, f01, f11}) {
    if (RefinedAt(p, point.z)) f = std::max(f, RefinementOf(p));
  }
  if (f > 1) {
    // Lattice coordinates, ray centres at integers.
    const double u = point.px * f - 0.5, v = point.py * f - 0.5;
    const double i_floor = std::floor(u), j_floor = std::floor(v);
    const double sx = u - i_floor, sy = v - j_floor;
    double value[4];
    bool defined = false;
    for (int k = 0; k < 4; ++k) {
      const int i = std::clamp(static_cast<int>(i_floor) + (k & 1), 0, g.width * f - 1);
      const int j = std::clamp(static_cast<int>(j_floor) + (k >> 1), 0, g.height * f - 1);
      const bool right = i / f != x0, up = j / f != y0;
      const std::span<const Vertex> pixel = up ? (right ? f11 : f01) : (right ? f10 : f00);
      bool sub = false;
      value[k] = LatticeAttenuation(pixel, f, i % f, j % f, point.z, &sub);
      defined = defined || sub;
    }
    if (defined) {
      return (1 - sy) * ((1 - sx) * value[0] + sx * value[1]) +
             sy * ((1 - sx) * value[2] + sx * value[3]);
    }
  }
  const double a00 = EvaluateAttenuation(OwnFunction(f00), point.z);
  const double a10 = EvaluateAttenuation(OwnFunction(f10), point.z);
  const double a01 = EvaluateAttenuation(OwnFunction(f01), point.z);
  const double a11 = EvaluateAttenuation(OwnFunction(f11), point.z);
  return (1 - wy) * ((1 - wx) * a00 + wx * a10) + wy * ((1 - wx) * a01 + wx * a11);
}

// Light samples behind the attenuation at p_world: header.samples for fixed-count bakes, the
// tile's count (of the pixel holding the point) for adaptive ones; 0 outside the frustum.
// The attenuation's sampling resolution is 1 / this.
int SamplesAt(const PdsmImage& pdsm, const glm::dvec3& p_world);

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_PDSM_QUERY_H_
