#include "core/pdsm/pdsm_query.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pdsm {

double BilinearAttenuation(const PdsmImage& pdsm, const PdsmPoint& point) {
  const PdsmGeometry& g = pdsm.header.geometry;
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
  const double a00 = EvaluateAttenuation(pdsm.Function(x0, y0), point.z);
  const double a10 = EvaluateAttenuation(pdsm.Function(x1, y0), point.z);
  const double a01 = EvaluateAttenuation(pdsm.Function(x0, y1), point.z);
  const double a11 = EvaluateAttenuation(pdsm.Function(x1, y1), point.z);
  return (1 - wy) * ((1 - wx) * a00 + wx * a10) + wy * ((1 - wx) * a01 + wx * a11);
}

double QueryAttenuation(const PdsmImage& pdsm, const glm::dvec3& p_world) {
  const std::optional<PdsmPoint> point = pdsm.header.geometry.Locate(p_world);
  if (!point) return std::numeric_limits<double>::quiet_NaN();
  return BilinearAttenuation(pdsm, *point);
}

int SamplesAt(const PdsmImage& pdsm, const glm::dvec3& p_world) {
  const PdsmHeader& h = pdsm.header;
  const std::optional<PdsmPoint> point = h.geometry.Locate(p_world);
  if (!point) return 0;
  if (h.tile_samples.empty() || h.tile_size <= 0) return h.samples;
  const int x = std::clamp(static_cast<int>(point->px), 0, h.geometry.width - 1);
  const int y = std::clamp(static_cast<int>(point->py), 0, h.geometry.height - 1);
  const int tiles_x = (h.geometry.width + h.tile_size - 1) / h.tile_size;
  return h.TileSamples(static_cast<size_t>(y / h.tile_size) * tiles_x + x / h.tile_size);
}

}  // namespace pdsm
