#include "client/view/cpu_attenuation.h"

#include <atomic>
#include <limits>
#include <optional>

#include "absl/synchronization/mutex.h"
#include "core/util/work_queue.h"

namespace pdsm::view {

absl::StatusOr<std::vector<float>> EvaluateAttenuationImage(PdsmTiles& pdsm,
                                                            const std::vector<float>& gbuffer,
                                                            int width, int height,
                                                            float pending_value) {
  std::vector<float> out(static_cast<size_t>(width) * height,
                         std::numeric_limits<float>::quiet_NaN());
  const LightFrame& frame = pdsm.header().geometry.frame;
  std::atomic<int> next_row{0};
  absl::Mutex mu;
  absl::Status status;
  RunOnAllCores(static_cast<size_t>(height), [&] {
    for (int y = next_row++; y < height; y = next_row++) {
      for (int x = 0; x < width; ++x) {
        const size_t p = static_cast<size_t>(y) * width + x;
        const float* g = &gbuffer[4 * p];
        if (g[3] != 1.0f) continue;
        // Back to world in double, then exactly what `pdsm query` does with a world point.
        const glm::dvec3 p_world = frame.WorldFromLight(glm::dvec3(g[0], g[1], g[2]));
        absl::StatusOr<std::optional<double>> a = pdsm.Attenuation(p_world);
        if (!a.ok()) {
          absl::MutexLock lock(&mu);
          status.Update(a.status());
          next_row = height;  // the others stop at their next row
          return;
        }
        out[p] = *a ? static_cast<float>(**a) : pending_value;
      }
    }
  });
  if (!status.ok()) return status;
  return out;
}

}  // namespace pdsm::view
