#include "core/bake/adaptive_sampling.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace pdsm {

std::vector<SampleRange> AdaptiveStageRanges(int stage, int min_samples, int max_samples) {
  const int64_t half = std::max(1, (min_samples + 1) / 2);
  auto clamp = [&](int64_t x) { return static_cast<int>(std::min<int64_t>(x, max_samples)); };
  std::vector<SampleRange> ranges;
  if (stage == 0) {
    ranges.push_back({0, clamp(half)});
    if (half < max_samples) ranges.push_back({clamp(half), clamp(2 * half)});
    return ranges;
  }
  if (stage > 40) return ranges;
  const int64_t begin = half << stage;  // 2^stage h
  if (begin >= max_samples) return ranges;
  ranges.push_back({clamp(begin), clamp(2 * begin)});
  return ranges;
}

double SplitHalfPixelError(std::span<const Event> first, int n1, std::span<const Event> second,
                           int n2, double min_interval, EventKeying keying) {
  const double weight = static_cast<double>(n2) / (n1 + n2);
  int64_t c1 = 0, c2 = 0;  // samples in shadow at the current depth, per half
  size_t i = 0, j = 0;
  double worst = 0;
  while (i < first.size() || j < second.size()) {
    // Next depth of either list; apply every event at it.
    const float z = std::min(i < first.size() ? first[i].z : std::numeric_limits<float>::max(),
                             j < second.size() ? second[j].z : std::numeric_limits<float>::max());
    while (i < first.size() && first[i].z == z) c1 += ShadowChange(first[i++], keying);
    while (j < second.size() && second[j].z == z) c2 += ShadowChange(second[j++], keying);
    const float next =
        std::min(i < first.size() ? first[i].z : std::numeric_limits<float>::infinity(),
                 j < second.size() ? second[j].z : std::numeric_limits<float>::infinity());
    if (static_cast<double>(next) - z < min_interval) continue;  // within a surface
    const double diff = std::abs(static_cast<double>(c2) / n2 - static_cast<double>(c1) / n1);
    worst = std::max(worst, weight * diff);
  }
  return worst;
}

double SplitHalfError(const TileEvents& first, int n1, const TileEvents& second, int n2,
                      double min_interval, EventKeying keying) {
  double worst = 0;
  for (size_t p = 0; p < first.PixelCount(); ++p) {
    worst = std::max(
        worst, SplitHalfPixelError(first.Pixel(p), n1, second.Pixel(p), n2, min_interval, keying));
  }
  return worst;
}

bool JudgeAdaptiveStage(const PdsmHeader& header, const std::vector<SampleRange>& ranges,
                        std::vector<TileEvents> stage_results, std::vector<TileEvents>* earlier) {
  for (size_t r = 0; r + 1 < stage_results.size(); ++r) {
    earlier->push_back(std::move(stage_results[r]));
  }
  TileEvents last = std::move(stage_results.back());
  const int n1 = ranges.back().begin, n2 = ranges.back().end - ranges.back().begin;
  bool done = ranges.back().end >= header.samples;
  const EventKeying keying = KeyingOf(header);
  if (!done) {
    const PdsmGeometry& g = header.geometry;
    TileEvents first = MergeTileEvents(*earlier, keying);
    done = SplitHalfError(first, n1, last, n2, kAdaptiveSurfaceDepthFraction * (g.z_far - g.z_near),
                          keying) <= header.adaptive_tolerance;
    earlier->clear();
    earlier->push_back(std::move(first));
  }
  earlier->push_back(std::move(last));
  if (earlier->size() > 1) {  // keep one merged list, not one per range
    TileEvents all = MergeTileEvents(*earlier, keying);
    earlier->clear();
    earlier->push_back(std::move(all));
  }
  return done;
}

}  // namespace pdsm
