#include "core/reference/union_area.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <span>

#include "core/reference/polygon_clip.h"

namespace pdsm::internal {
namespace {

// Whether segments a and b lie on one line, within `tolerance`. Measured against the longer
// one's line, with both put in a canonical order first: the answer is bit-for-bit the same
// whichever of the two edges asks, so coincident edges are treated alike from both sides.
bool OnOneLine(glm::dvec2 a0, glm::dvec2 a1, glm::dvec2 b0, glm::dvec2 b1, double tolerance) {
  if (LexLess(a1, a0)) std::swap(a0, a1);
  if (LexLess(b1, b0)) std::swap(b0, b1);
  double la = glm::length(a1 - a0), lb = glm::length(b1 - b0);
  const bool b_is_reference =
      lb > la || (lb == la && (LexLess(b0, a0) || (b0 == a0 && LexLess(b1, a1))));
  if (b_is_reference) {
    std::swap(a0, b0);
    std::swap(a1, b1);
    std::swap(la, lb);
  }
  const glm::dvec2 d = a1 - a0;
  return std::abs(Cross(d, b0 - a0)) <= tolerance * la &&
         std::abs(Cross(d, b1 - a0)) <= tolerance * la;
}

// The parameter interval of edge e (of polygon i, from a to b) covered by polygon j, if any.
// A point of e counts as covered when it is inside j, or on an edge of j that e runs along in
// the opposite direction (then both sides of it are in the union), or on one that e runs along
// in the same direction when j < i (so that one of a set of coincident edges survives).
std::optional<std::pair<double, double>> CoveredBy(const ConvexSet& set, size_t j, size_t i,
                                                   const glm::dvec2& a, const glm::dvec2& b,
                                                   const glm::dvec2& e_unit, double e_length,
                                                   double tolerance) {
  double t0 = 0.0, t1 = 1.0;
  const uint32_t first = set.start[j], last = set.start[j + 1];
  for (uint32_t k = first; k < last; ++k) {
    const glm::dvec2& fa = set.vertex[k];
    const glm::dvec2& fu = set.unit[k];
    const double g0 = Cross(fu, a - fa);  // signed distances to f's line, inside positive
    const double g1 = Cross(fu, b - fa);
    // Only a candidate for "one line" when both ends are near f's line; the slack covers a
    // short f whose direction, extended along a long e, is less certain.
    const double reach = tolerance * (2.0 + 2.0 * e_length / set.length[k]);
    if (std::abs(g0) <= reach && std::abs(g1) <= reach) {
      const glm::dvec2& fb = set.vertex[k + 1 < last ? k + 1 : first];
      if (OnOneLine(a, b, fa, fb, tolerance)) {
        if (glm::dot(e_unit, fu) > 0.0 && !(j < i)) return std::nullopt;
        continue;
      }
    }
    if (g0 >= 0.0 && g1 >= 0.0) continue;
    if (g0 <= 0.0 && g1 <= 0.0) return std::nullopt;
    const double t = g0 / (g0 - g1);
    if (g0 < 0.0) {
      t0 = std::max(t0, t);
    } else {
      t1 = std::min(t1, t);
    }
    if (t0 >= t1) return std::nullopt;
  }
  return std::make_pair(t0, t1);
}

// Neumaier's compensated sum: the union's area is a sum of many terms that mostly cancel.
class CompensatedSum {
 public:
  void Add(double x) {
    const double t = sum_ + x;
    compensation_ += std::abs(sum_) >= std::abs(x) ? (sum_ - t) + x : (x - t) + sum_;
    sum_ = t;
  }
  double Value() const { return sum_ + compensation_; }

 private:
  double sum_ = 0.0, compensation_ = 0.0;
};

// What edge k of polygon i contributes to the union's measure, from its boundary (Green's
// theorem for the area): the terms of the parts of the edge no other polygon covers.
double EdgeTerm(const ConvexSet& set, const CellGrid& grid, size_t i, uint32_t k, uint64_t edge_id,
                double tolerance, const BoundaryMeasure& measure, UnionScratch* ws) {
  const uint32_t first = set.start[i], last = set.start[i + 1];
  const glm::dvec2& a = set.vertex[k];
  const glm::dvec2& b = set.vertex[k + 1 < last ? k + 1 : first];
  const glm::dvec2 e_lo = glm::min(a, b) - tolerance, e_hi = glm::max(a, b) + tolerance;
  ws->intervals.clear();
  bool fully_covered = false;
  grid.ForNear(e_lo, e_hi, [&](uint32_t j) {
    if (j == i || ws->visited[j] == edge_id) return true;
    ws->visited[j] = edge_id;
    if (glm::any(glm::lessThan(set.hi[j], e_lo)) || glm::any(glm::greaterThan(set.lo[j], e_hi))) {
      return true;
    }
    const auto covered = CoveredBy(set, j, i, a, b, set.unit[k], set.length[k], tolerance);
    if (!covered.has_value()) return true;
    fully_covered = covered->first <= 0.0 && covered->second >= 1.0;
    ws->intervals.push_back(*covered);
    return !fully_covered;
  });
  if (fully_covered) return 0.0;
  std::sort(ws->intervals.begin(), ws->intervals.end());
  auto at = [&](double t) { return t <= 0.0 ? a : t >= 1.0 ? b : a + t * (b - a); };
  double term = 0.0, reached = 0.0;
  for (const auto& [t0, t1] : ws->intervals) {
    if (t0 > reached) term += measure.Segment(at(reached), at(t0));
    reached = std::max(reached, t1);
  }
  if (reached < 1.0) term += measure.Segment(at(reached), b);
  return term;
}

}  // namespace

double UnionMeasure(const ConvexSet& set, const glm::dvec2& lo, const glm::dvec2& hi,
                    double tolerance, const BoundaryMeasure& measure, UnionScratch* scratch) {
  const size_t n = set.size();
  if (n == 0) return 0.0;
  if (n == 1) {
    if (measure.is_area()) return set.area[0];
    return measure.Polygon(
        std::span<const glm::dvec2>(set.vertex.data() + set.start[0], set.start[1] - set.start[0]));
  }
  scratch->grid.Build(set, lo, hi, tolerance);
  scratch->visited.assign(n, std::numeric_limits<uint64_t>::max());
  uint64_t edge_id = 0;
  CompensatedSum sum;
  for (size_t i = 0; i < n; ++i) {
    for (uint32_t k = set.start[i]; k < set.start[i + 1]; ++k, ++edge_id) {
      sum.Add(EdgeTerm(set, scratch->grid, i, k, edge_id, tolerance, measure, scratch));
    }
  }
  return sum.Value();
}

double UnionArea(const ConvexSet& set, const glm::dvec2& lo, const glm::dvec2& hi, double tolerance,
                 UnionScratch* scratch) {
  return UnionMeasure(set, lo, hi, tolerance, BoundaryMeasure::Area(), scratch);
}

}  // namespace pdsm::internal
