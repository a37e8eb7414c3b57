#include "core/bake/refinement_selection.h"

#include <algorithm>
#include <cmath>

namespace pdsm {

int RefinementForGap(double gap, int max_refinement, double threshold) {
  if (!(gap > threshold)) return 1;  // NaN too: an undefined side is no evidence
  int f = 1;
  while (f < max_refinement && gap / f > threshold) f *= 2;
  return f;
}

TileRect GrownByOnePixel(const PdsmGeometry& geometry, const TileRect& rect) {
  TileRect grown = rect;
  grown.x0 = std::max(0, rect.x0 - 1);
  grown.y0 = std::max(0, rect.y0 - 1);
  grown.width = std::min(geometry.width, rect.x0 + rect.width + 1) - grown.x0;
  grown.height = std::min(geometry.height, rect.y0 + rect.height + 1) - grown.y0;
  return grown;
}

PairReceivers ComputePairReceivers(const BakePlan& plan, const TileRect& rect) {
  // A sliver of a pixel around each point between two pixel centres: the receiver depths on
  // that ray, padded as every window is.
  constexpr double kSliver = 1.0 / 256;
  const TileRect grown = GrownByOnePixel(plan.geometry(), rect);
  // Only the receivers that may be refined (`refine`): the others' shadows keep the base's
  // resolution, and no band is placed at their depths.
  const LightSpaceMesh& receivers = plan.RefinableReceivers();
  return PairReceivers{
      ComputeReceiverWindowsAt(plan, receivers, grown, glm::dvec2(0.5), 1.0),
      ComputeReceiverWindowsAt(plan, receivers, grown, glm::dvec2(1.0, 0.5), kSliver),
      ComputeReceiverWindowsAt(plan, receivers, grown, glm::dvec2(0.5, 1.0), kSliver)};
}

void MergeBands(std::vector<DepthWindow>* bands) {
  std::sort(bands->begin(), bands->end(), [](const DepthWindow& a, const DepthWindow& b) {
    return a.lo < b.lo || (a.lo == b.lo && a.hi < b.hi);
  });
  size_t out = 0;
  for (const DepthWindow& band : *bands) {
    if (out > 0 && band.lo <= (*bands)[out - 1].hi) {
      (*bands)[out - 1].hi = std::max((*bands)[out - 1].hi, band.hi);
    } else {
      (*bands)[out++] = band;
    }
  }
  bands->resize(out);
}

}  // namespace pdsm
