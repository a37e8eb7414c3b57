#include "core/sampling/blue_noise.h"

#include <algorithm>
#include <bit>
#include <cstdlib>

#include "core/sampling/hash_rng.h"

namespace pdsm {
namespace {

struct FixedPoint {
  uint32_t x, y;  // coordinate / 2^32
};

// Squared distance on the unit torus, in (2^-32)^2 units; at most 2^63.
uint64_t TorusDistance2(FixedPoint a, FixedPoint b) {
  const uint64_t dx =
      static_cast<uint64_t>(std::abs(static_cast<int64_t>(static_cast<int32_t>(a.x - b.x))));
  const uint64_t dy =
      static_cast<uint64_t>(std::abs(static_cast<int64_t>(static_cast<int32_t>(a.y - b.y))));
  return dx * dx + dy * dy;
}

// A grid of 2^k x 2^k cells over the torus holding point indices.
class PointGrid {
 public:
  explicit PointGrid(int expected_points) {
    // About two points per cell once all are placed.
    const uint32_t cells_wanted = std::max<uint32_t>(1, static_cast<uint32_t>(expected_points) / 2);
    log2_side_ = std::max(0, (static_cast<int>(std::bit_width(cells_wanted)) - 1) / 2);
    side_ = 1 << log2_side_;
    cells_.resize(static_cast<size_t>(side_) * side_);
  }

  void Add(FixedPoint p, int index) { cells_[CellOf(p)].push_back(index); }

  // Squared distance from p to the nearest of `points` (all in the grid); UINT64_MAX if none.
  uint64_t Nearest2(FixedPoint p, const std::vector<FixedPoint>& points) const {
    if (points.empty()) return UINT64_MAX;
    const int cx = CellX(p.x), cy = CellX(p.y);
    const uint64_t cell_size = uint64_t{1} << (32 - log2_side_);
    uint64_t best = UINT64_MAX;
    for (int r = 0;; ++r) {
      if (2 * r + 1 >= side_) {  // the ring would wrap onto itself: look at everything
        for (const FixedPoint& q : points) best = std::min(best, TorusDistance2(p, q));
        return best;
      }
      VisitRing(cx, cy, r,
                [&](int index) { best = std::min(best, TorusDistance2(p, points[index])); });
      // Cells of ring r + 1 are at least r cell sizes away from any point of cell (cx, cy).
      const uint64_t reach = static_cast<uint64_t>(r) * cell_size;
      if (best != UINT64_MAX && best <= reach * reach) return best;
    }
  }

 private:
  int CellX(uint32_t coordinate) const {
    return log2_side_ == 0 ? 0 : static_cast<int>(coordinate >> (32 - log2_side_));
  }
  size_t CellOf(FixedPoint p) const { return static_cast<size_t>(CellX(p.y)) * side_ + CellX(p.x); }

  template <typename F>
  void VisitRing(int cx, int cy, int r, F&& visit) const {
    auto cell = [&](int x, int y) {
      const int wx = (x % side_ + side_) % side_, wy = (y % side_ + side_) % side_;
      for (int index : cells_[static_cast<size_t>(wy) * side_ + wx]) visit(index);
    };
    if (r == 0) return cell(cx, cy);
    for (int x = cx - r; x <= cx + r; ++x) {
      cell(x, cy - r);
      cell(x, cy + r);
    }
    for (int y = cy - r + 1; y <= cy + r - 1; ++y) {
      cell(cx - r, y);
      cell(cx + r, y);
    }
  }

  int log2_side_ = 0;
  int side_ = 1;
  std::vector<std::vector<int>> cells_;
};

}  // namespace

std::vector<glm::dvec2> BlueNoiseUnitSquare(int count, uint64_t seed) {
  std::vector<glm::dvec2> result;
  if (count <= 0) return result;
  std::vector<FixedPoint> points;
  points.reserve(count);
  PointGrid grid(count);
  SplitMix64 rng(HashInts(seed, 0xb1e5));
  for (int i = 0; i < count; ++i) {
    FixedPoint best{};
    uint64_t best_distance2 = 0;
    for (int c = 0; c < kBestCandidateTries; ++c) {
      const uint64_t bits = rng.Next();
      const FixedPoint candidate{static_cast<uint32_t>(bits >> 32), static_cast<uint32_t>(bits)};
      const uint64_t d2 = grid.Nearest2(candidate, points);
      if (c == 0 || d2 > best_distance2) {  // ties keep the earlier candidate
        best = candidate;
        best_distance2 = d2;
      }
    }
    grid.Add(best, i);
    points.push_back(best);
  }
  result.reserve(count);
  for (const FixedPoint& p : points) {
    result.emplace_back(static_cast<double>(p.x) * 0x1.0p-32, static_cast<double>(p.y) * 0x1.0p-32);
  }
  return result;
}

}  // namespace pdsm
