#include "core/bake/surface_function.h"

#include <limits>

#include "core/pdsm/compression.h"

namespace pdsm {

std::vector<Vertex> SurfaceFunction(std::span<const Event> events,
                                    std::span<const DepthWindow> windows, int total_samples,
                                    double epsilon, CompressionMetric metric, double depth_scale) {
  if (events.empty()) return {};
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  std::vector<Vertex> out = {Vertex{kUndefinedFrom, kNaN}};
  const auto value = [total_samples](int64_t hidden) {
    return static_cast<float>(static_cast<double>(hidden) / total_samples);
  };
  size_t next = 0;     // first event not yet counted
  int64_t hidden = 0;  // sum of the counts before `next`
  std::vector<Vertex> piece;
  for (const DepthWindow& window : windows) {
    const float lo = static_cast<float>(window.lo);
    const float hi = static_cast<float>(window.hi);
    for (; next < events.size() && events[next].z <= lo; ++next) hidden += events[next].count;
    piece.assign(1, Vertex{lo, value(hidden)});
    for (; next < events.size() && events[next].z < hi; ++next) {
      piece.push_back(Vertex{events[next].z, value(hidden)});
      hidden += events[next].count;
      piece.push_back(Vertex{events[next].z, value(hidden)});
    }
    piece.push_back(Vertex{hi, value(hidden)});
    const std::vector<Vertex> compressed = CompressFunction(piece, epsilon, metric, depth_scale);
    out.insert(out.end(), compressed.begin(), compressed.end());
    out.push_back(Vertex{hi, kNaN});
  }
  return out;
}

std::vector<Vertex> EmitterSurfaceFunction(std::span<const Event> events,
                                           std::span<const DepthWindow> windows, EmitterRay* ray,
                                           double tolerance, double epsilon,
                                           CompressionMetric metric, double depth_scale) {
  if (events.empty()) return {};
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  std::vector<Vertex> out = {Vertex{kUndefinedFrom, kNaN}};
  for (const DepthWindow& window : windows) {
    // The window's ends as the counted function places them: float depths.
    const float lo = static_cast<float>(window.lo);
    const float hi = static_cast<float>(window.hi);
    const std::vector<Vertex> piece = EmitterWeightedPiece(events, ray, lo, hi, tolerance);
    const std::vector<Vertex> compressed = CompressFunction(piece, epsilon, metric, depth_scale);
    out.insert(out.end(), compressed.begin(), compressed.end());
    out.push_back(Vertex{hi, kNaN});
  }
  return out;
}

}  // namespace pdsm
