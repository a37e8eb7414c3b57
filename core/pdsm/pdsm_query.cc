#include "core/pdsm/pdsm_query.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pdsm {

double BilinearAttenuation(const PdsmImage& pdsm, const PdsmPoint& point) {
  return BilinearAttenuationOf(pdsm.header.geometry, point,
                               [&pdsm](int x, int y) { return pdsm.Function(x, y); });
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
