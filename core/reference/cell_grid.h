// The polygons of a ConvexSet near a box, found through a uniform grid. Internal to
// core/reference (not a public API).
#ifndef PDSM_CORE_REFERENCE_CELL_GRID_H_
#define PDSM_CORE_REFERENCE_CELL_GRID_H_

#include <algorithm>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "core/reference/convex_set.h"

namespace pdsm::internal {

// A uniform grid of ~sqrt(n) x sqrt(n) cells over a region, listing the polygons whose
// (padded) bounding boxes touch each cell: finds the polygons near an edge. Boxes beyond the
// region fall into the border cells. Reusable: Build replaces what an earlier Build listed.
class CellGrid {
 public:
  // Lists the polygons of `set`, which lie within [lo, hi], with boxes padded by `pad`.
  void Build(const ConvexSet& set, const glm::dvec2& lo, const glm::dvec2& hi, double pad);

  // Calls f(polygon index) for the polygons listed in the cells under the padded box, with
  // repeats, until f returns false.
  template <typename F>
  void ForNear(const glm::dvec2& box_lo, const glm::dvec2& box_hi, const F& f) const {
    ForCells(box_lo, box_hi, [&](int c) {
      for (uint32_t s = start_[c]; s < start_[c + 1]; ++s) {
        if (!f(items_[s])) return false;
      }
      return true;
    });
  }

 private:
  template <typename F>
  void ForCells(const glm::dvec2& box_lo, const glm::dvec2& box_hi, const F& f) const {
    auto cell = [&](double v, double origin, double size) {
      return std::clamp(static_cast<int>((v - origin) / size), 0, cells_ - 1);
    };
    const glm::dvec2 a = box_lo - pad_, b = box_hi + pad_;
    const int x0 = cell(a.x, lo_.x, cell_size_.x), x1 = cell(b.x, lo_.x, cell_size_.x);
    const int y0 = cell(a.y, lo_.y, cell_size_.y), y1 = cell(b.y, lo_.y, cell_size_.y);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        if (!f(y * cells_ + x)) return;
      }
    }
  }

  int cells_ = 1;
  glm::dvec2 lo_{0.0}, cell_size_{1.0}, pad_{0.0};
  std::vector<uint32_t> start_, items_, fill_;
};

}  // namespace pdsm::internal

#endif  // PDSM_CORE_REFERENCE_CELL_GRID_H_
