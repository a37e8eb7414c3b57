#include "core/reference/polygon_clip.h"

#include <cmath>
#include <vector>

namespace pdsm::internal {

double TwiceSignedArea(const std::vector<glm::dvec2>& poly) {
  double sum = 0.0;
  for (size_t i = 1; i + 1 < poly.size(); ++i) {
    sum += Cross(poly[i] - poly[0], poly[i + 1] - poly[0]);
  }
  return sum;
}

void RemoveNearlyCollinear(double tolerance, std::vector<glm::dvec2>* ring) {
  auto close = [tolerance](const glm::dvec2& a, const glm::dvec2& b) {
    return glm::length(b - a) <= tolerance;
  };
  auto redundant = [tolerance](const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
    const double base = glm::length(c - a);
    return base <= tolerance || std::abs(Cross(c - a, b - a)) <= tolerance * base;
  };
  std::vector<glm::dvec2> out;
  out.reserve(ring->size());
  for (const glm::dvec2& q : *ring) {
    if (!out.empty() && close(out.back(), q)) continue;
    while (out.size() >= 2 && redundant(out[out.size() - 2], out.back(), q)) out.pop_back();
    out.push_back(q);
  }
  // The same across the wrap-around, until nothing changes.
  size_t first = 0;
  for (bool changed = true; changed && out.size() - first >= 3;) {
    changed = false;
    const size_t n = out.size();
    if (close(out[n - 1], out[first]) || redundant(out[n - 2], out[n - 1], out[first])) {
      out.pop_back();
      changed = true;
    } else if (redundant(out[n - 1], out[first], out[first + 1])) {
      ++first;
      changed = true;
    }
  }
  if (out.size() - first < 3) {
    ring->clear();
    return;
  }
  ring->assign(out.begin() + first, out.end());
}

}  // namespace pdsm::internal
