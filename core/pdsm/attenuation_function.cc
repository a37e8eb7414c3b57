#include "core/pdsm/attenuation_function.h"

#include <algorithm>

namespace pdsm {

float EvaluateAttenuation(std::span<const Vertex> function, double z) {
  if (function.empty() || z < function.front().z) return 0.0f;
  // Last vertex with vertex.z <= z: right-continuous at jumps.
  const auto after = std::upper_bound(function.begin(), function.end(), z,
                                      [](double zz, const Vertex& v) { return zz < v.z; });
  const Vertex& lo = *(after - 1);
  if (after == function.end()) return lo.a;
  const Vertex& hi = *after;
  const double f = (z - lo.z) / (static_cast<double>(hi.z) - lo.z);
  return static_cast<float>(lo.a + f * (static_cast<double>(hi.a) - lo.a));
}

}  // namespace pdsm
