#include "core/reference/cell_grid.h"

#include <cmath>

namespace pdsm::internal {

void CellGrid::Build(const ConvexSet& set, const glm::dvec2& lo, const glm::dvec2& hi, double pad) {
  const size_t n = set.size();
  cells_ = std::clamp(static_cast<int>(std::sqrt(static_cast<double>(n))), 1, 256);
  lo_ = lo;
  cell_size_ = glm::max((hi - lo) / static_cast<double>(cells_), glm::dvec2(1e-300));
  pad_ = glm::dvec2(pad);
  // Counting pass, then filling pass (compressed rows).
  start_.assign(static_cast<size_t>(cells_) * cells_ + 1, 0);
  for (size_t i = 0; i < n; ++i) {
    ForCells(set.lo[i], set.hi[i], [&](int c) {
      ++start_[c + 1];
      return true;
    });
  }
  for (size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
  items_.resize(start_.back());
  fill_.assign(start_.begin(), start_.end() - 1);
  for (size_t i = 0; i < n; ++i) {
    ForCells(set.lo[i], set.hi[i], [&](int c) {
      items_[fill_[c]++] = static_cast<uint32_t>(i);
      return true;
    });
  }
}

}  // namespace pdsm::internal
