#include "client/view/cpu_attenuation.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>

#include "core/pdsm/pdsm_query.h"
#include "core/util/work_queue.h"

namespace pdsm::view {

namespace {

// Whether the bilinear lookup at `point` reads a pixel that is not baked yet (the same
// neighbours BilinearAttenuation blends, clamped at the border).
bool ReadsPendingPixel(const PdsmGeometry& g, const PdsmPoint& point,
                       const std::vector<uint8_t>& pending) {
  const int x0 = static_cast<int>(std::floor(point.px - 0.5));
  const int y0 = static_cast<int>(std::floor(point.py - 0.5));
  for (int y : {std::clamp(y0, 0, g.height - 1), std::clamp(y0 + 1, 0, g.height - 1)}) {
    for (int x : {std::clamp(x0, 0, g.width - 1), std::clamp(x0 + 1, 0, g.width - 1)}) {
      if (pending[static_cast<size_t>(y) * g.width + x] != 0) return true;
    }
  }
  return false;
}

}  // namespace

std::vector<float> EvaluateAttenuationImage(const PdsmImage& pdsm,
                                            const std::vector<float>& gbuffer, int width,
                                            int height, const std::vector<uint8_t>& pending,
                                            float pending_value) {
  std::vector<float> out(static_cast<size_t>(width) * height,
                         std::numeric_limits<float>::quiet_NaN());
  const LightFrame& frame = pdsm.header.geometry.frame;
  std::atomic<int> next_row{0};
  RunOnAllCores(static_cast<size_t>(height), [&] {
    for (int y = next_row++; y < height; y = next_row++) {
      for (int x = 0; x < width; ++x) {
        const size_t p = static_cast<size_t>(y) * width + x;
        const float* g = &gbuffer[4 * p];
        if (g[3] != 1.0f) continue;
        // Back to world in double, then exactly what `pdsm query` does with a world point.
        const glm::dvec3 p_world = frame.WorldFromLight(glm::dvec3(g[0], g[1], g[2]));
        if (!pending.empty()) {
          const std::optional<PdsmPoint> point = pdsm.header.geometry.Locate(p_world);
          if (point && ReadsPendingPixel(pdsm.header.geometry, *point, pending)) {
            out[p] = pending_value;
            continue;
          }
        }
        out[p] = static_cast<float>(QueryAttenuation(pdsm, p_world));
      }
    }
  });
  return out;
}

}  // namespace pdsm::view
