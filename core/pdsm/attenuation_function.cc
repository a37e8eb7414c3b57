#include "core/pdsm/attenuation_function.h"

#include <algorithm>

namespace pdsm {

float EvaluateAttenuation(std::span<const Vertex> function, double z) {
  if (function.empty() || z < function.front().z) return 0.0f;
  // Last vertex with vertex.z <= z: right-continuous at jumps.
  const auto after = std::upper_bound(function.begin(), function.end(), z,
                                      [](double zz, const Vertex& v) { return zz < v.z; });
  const Vertex& lo = *(after - 1);
  if (after == function.end()) return std::clamp(lo.a, 0.0f, 1.0f);
  const Vertex& hi = *after;
  const double f = (z - lo.z) / (static_cast<double>(hi.z) - lo.z);
  // Clamping can only bring a compressed function closer to the true one, which is in [0, 1].
  return static_cast<float>(std::clamp(lo.a + f * (static_cast<double>(hi.a) - lo.a), 0.0, 1.0));
}

}  // namespace pdsm
