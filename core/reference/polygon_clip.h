// Convex polygon clipping and the small 2-D helpers the exact reference builds on. Internal to
// core/reference (not a public API). Every function is deterministic in its inputs, and the
// cut points of an edge do not depend on the edge's direction, so an edge shared by two mesh
// triangles is cut at bit-identical points in both.
#ifndef PDSM_CORE_REFERENCE_POLYGON_CLIP_H_
#define PDSM_CORE_REFERENCE_POLYGON_CLIP_H_

#include <utility>
#include <vector>

#include <glm/glm.hpp>

namespace pdsm::internal {

// The z component of the 3-D cross product: twice the signed area of the triangle (0, a, b).
inline double Cross(const glm::dvec2& a, const glm::dvec2& b) { return a.x * b.y - a.y * b.x; }

// Lexicographic order of glm vectors (x first): a canonical order for an edge's two ends.
template <typename Vec>
bool LexLess(const Vec& a, const Vec& b) {
  for (int i = 0; i < Vec::length(); ++i) {
    if (a[i] != b[i]) return a[i] < b[i];
  }
  return false;
}

// Twice the signed area (counter-clockwise positive), relative to the first vertex.
double TwiceSignedArea(const std::vector<glm::dvec2>& poly);

// Removes vertices within `tolerance` of their predecessor or of the line through their
// neighbours (collinear points, spikes). Moves the boundary by at most `tolerance`. Leaves
// `ring` empty when fewer than 3 vertices would remain.
void RemoveNearlyCollinear(double tolerance, std::vector<glm::dvec2>* ring);

// Where segment ab crosses {f = 0}, given fa = f(a) and fb = f(b) of opposite signs (or one of
// them 0). Interpolated from the lexicographically smaller end, so an edge shared by two mesh
// triangles is cut at bit-identical points in both.
template <typename Vec>
Vec Crossing(Vec a, double fa, Vec b, double fb) {
  if (LexLess(b, a)) {
    std::swap(a, b);
    std::swap(fa, fb);
  }
  if (fa == 0.0) return a;
  if (fb == 0.0) return b;
  return a + (fa / (fa - fb)) * (b - a);
}

// Sutherland–Hodgman step: keeps the part of convex `poly` where f >= 0 (f > 0 if `strict`),
// for a function f that is affine along each edge. `poly` keeps its orientation; it is left
// as is when wholly inside and cleared when wholly outside. `scratch` and `values` are
// buffers the caller reuses between calls; their contents on return are unspecified.
template <typename Vec, typename F>
void ClipConvex(const F& f, bool strict, std::vector<Vec>* poly, std::vector<Vec>* scratch,
                std::vector<double>* values) {
  const size_t n = poly->size();
  if (n == 0) return;
  values->resize(n);
  bool any_in = false, any_out = false;
  for (size_t i = 0; i < n; ++i) {
    const double v = f((*poly)[i]);
    (*values)[i] = v;
    const bool in = strict ? v > 0.0 : v >= 0.0;
    any_in |= in;
    any_out |= !in;
  }
  if (!any_out) return;
  if (!any_in) {
    poly->clear();
    return;
  }
  scratch->clear();
  for (size_t i = 0; i < n; ++i) {
    const size_t j = (i + 1) % n;
    const double vi = (*values)[i], vj = (*values)[j];
    const bool in_i = strict ? vi > 0.0 : vi >= 0.0;
    const bool in_j = strict ? vj > 0.0 : vj >= 0.0;
    if (in_i) scratch->push_back((*poly)[i]);
    if (in_i != in_j) scratch->push_back(Crossing((*poly)[i], vi, (*poly)[j], vj));
  }
  poly->swap(*scratch);
}

}  // namespace pdsm::internal

#endif  // PDSM_CORE_REFERENCE_POLYGON_CLIP_H_
