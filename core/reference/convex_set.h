// A set of convex polygons stored flat, with the direction and length of every edge and each
// polygon's bounding box and area: the input of UnionArea, reused between points. Internal to
// core/reference (not a public API).
#ifndef PDSM_CORE_REFERENCE_CONVEX_SET_H_
#define PDSM_CORE_REFERENCE_CONVEX_SET_H_

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace pdsm::internal {

// Convex polygons, counter-clockwise, stored flat with their edges.
struct ConvexSet {
  std::vector<glm::dvec2> vertex;  // polygon i: vertex[start[i] .. start[i + 1])
  std::vector<glm::dvec2> unit;    // direction of the edge leaving each vertex
  std::vector<double> length;      // and its length
  std::vector<uint32_t> start{0};
  std::vector<glm::dvec2> lo, hi;
  std::vector<double> area;

  size_t size() const { return area.size(); }
  void Clear() {
    vertex.clear();
    unit.clear();
    length.clear();
    start.assign(1, 0);
    lo.clear();
    hi.clear();
    area.clear();
  }
  // REQUIRES: `ccw` is convex and counter-clockwise with no zero-length edge; `twice_area` is
  // twice its area (the caller has it already).
  void Add(const std::vector<glm::dvec2>& ccw, double twice_area) {
    const size_t n = ccw.size();
    glm::dvec2 box_lo = ccw[0], box_hi = ccw[0];
    for (size_t k = 0; k < n; ++k) {
      const glm::dvec2 d = ccw[(k + 1) % n] - ccw[k];
      const double len = glm::length(d);
      vertex.push_back(ccw[k]);
      unit.push_back(d / len);
      length.push_back(len);
      box_lo = glm::min(box_lo, ccw[k]);
      box_hi = glm::max(box_hi, ccw[k]);
    }
    start.push_back(static_cast<uint32_t>(vertex.size()));
    lo.push_back(box_lo);
    hi.push_back(box_hi);
    area.push_back(0.5 * twice_area);
  }
};

}  // namespace pdsm::internal

#endif  // PDSM_CORE_REFERENCE_CONVEX_SET_H_
