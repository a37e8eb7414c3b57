// The hidden area is the area of a union of convex polygons (each triangle clipped and
// projected from the point onto the light, then clipped to the light). It is computed with
// Green's theorem over the union's boundary: area = 1/2 ∮ (x dy - y dx), where the boundary is
// every polygon edge minus the parts covered by another polygon.
//
// Why not Boost.Geometry's union_: Boost 1.74 (Debian 12) fails on exactly the input this
// module sees most, meshes whose projected edges meet at T-junctions that are collinear only
// up to rounding. It returns invalid multipolygons (pieces that share an edge left unmerged),
// and later unions of those return areas off by tens of percent without throwing
// (boostorg/geometry #838, #1068, #1229; the rescaling overlay was replaced in 1.80+).
// The boundary integral has no topology to get wrong: a rounding error in deciding whether a
// point of an edge is covered moves the area by at most (error x edge length), and the one
// discontinuous decision, coincident edges, is made by a test that gives the same answer from
// both sides.
#include "core/reference/exact_visibility.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/util/work_queue.h"

namespace pdsm {
namespace {

// Geometry within this distance (relative to p.z) below the point's height is ignored: its
// projection runs off to infinity. A consequence, wanted: the surface a point lies on (its
// own receiver, within rounding) never shadows it.
constexpr double kNearPointMargin = 1e-9;
// The disk light's stand-in. Relative area error 1 - sin(2π/n)/(2π/n) = 2.51e-5 for n = 512.
constexpr int kDiskSides = 512;
// Relative to the light's extent: vertices this close to a neighbour or to the line through
// their neighbours are dropped, and edges this close to one line are coincident. Far above
// rounding noise (1e-16), far below detail that matters; each use moves the hidden area by
// at most this times an edge length.
constexpr double kTolerance = 1e-10;
// Pieces below this share of the light are degenerate (edge-on triangles, clipping slivers).
constexpr double kDegenerateAreaFraction = 1e-14;

bool Finite(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

double Cross(const glm::dvec2& a, const glm::dvec2& b) { return a.x * b.y - a.y * b.x; }

template <typename Vec>
bool LexLess(const Vec& a, const Vec& b) {
  for (int i = 0; i < Vec::length(); ++i) {
    if (a[i] != b[i]) return a[i] < b[i];
  }
  return false;
}

// Twice the signed area (counter-clockwise positive), relative to the first vertex.
double TwiceSignedArea(const std::vector<glm::dvec2>& poly) {
  double sum = 0.0;
  for (size_t i = 1; i + 1 < poly.size(); ++i) {
    sum += Cross(poly[i] - poly[0], poly[i + 1] - poly[0]);
  }
  return sum;
}

// Removes vertices within `tolerance` of their predecessor or of the line through their
// neighbours (collinear points, spikes). Moves the boundary by at most `tolerance`.
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

// Where segment ab crosses {f = 0}. Interpolated from the lexicographically smaller end, so
// an edge shared by two mesh triangles is cut at bit-identical points in both.
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

// Sutherland–Hodgman step: keeps the part of convex `poly` where f >= 0 (f > 0 if `strict`).
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

// A convex part of the light; the parts tile it. A convex light is one region; others are
// ear-clipped into triangles, and the hidden area is the sum over regions.
struct Region {
  std::vector<glm::dvec2> ccw;
  glm::dvec2 lo{0.0}, hi{0.0};
  double area = 0.0;
  // Points within inner_radius of inner_center are inside: most pieces need no clipping.
  glm::dvec2 inner_center{0.0};
  double inner_radius = 0.0;
};

Region MakeRegion(std::vector<glm::dvec2> ccw) {
  Region region;
  region.ccw = std::move(ccw);
  region.area = 0.5 * TwiceSignedArea(region.ccw);
  region.lo = region.hi = region.ccw[0];
  glm::dvec2 sum(0.0);
  for (const glm::dvec2& q : region.ccw) {
    region.lo = glm::min(region.lo, q);
    region.hi = glm::max(region.hi, q);
    sum += q;
  }
  region.inner_center = sum / static_cast<double>(region.ccw.size());
  double radius = std::numeric_limits<double>::infinity();
  const size_t n = region.ccw.size();
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec2 e = region.ccw[(i + 1) % n] - region.ccw[i];
    radius = std::min(radius, Cross(e, region.inner_center - region.ccw[i]) / glm::length(e));
  }
  // Shrunk a little so that rounding in the distance test never skips a needed clip.
  region.inner_radius = std::max(0.0, radius * (1.0 - 1e-9));
  return region;
}

// Convex (and simple) iff every turn is a left turn and they add up to one full turn.
bool IsConvexCcw(const std::vector<glm::dvec2>& poly) {
  const size_t n = poly.size();
  double turning = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec2 e0 = poly[(i + 1) % n] - poly[i];
    const glm::dvec2 e1 = poly[(i + 2) % n] - poly[(i + 1) % n];
    const double cross = Cross(e0, e1);
    if (cross < 0.0) return false;
    turning += std::atan2(cross, glm::dot(e0, e1));
  }
  return std::abs(turning - 2.0 * std::numbers::pi) < 1e-6;
}

bool InTriangle(const glm::dvec2& q, const glm::dvec2& a, const glm::dvec2& b,
                const glm::dvec2& c) {
  return Cross(b - a, q - a) >= 0.0 && Cross(c - b, q - b) >= 0.0 && Cross(a - c, q - c) >= 0.0;
}

// Ear clipping of a simple counter-clockwise polygon. O(n^2): lights have few vertices.
std::vector<Region> Triangulate(std::vector<glm::dvec2> poly) {
  std::vector<Region> triangles;
  while (poly.size() > 3) {
    const size_t n = poly.size();
    bool clipped = false;
    for (size_t i = 0; i < n && !clipped; ++i) {
      const glm::dvec2& a = poly[(i + n - 1) % n];
      const glm::dvec2& b = poly[i];
      const glm::dvec2& c = poly[(i + 1) % n];
      const double turn = Cross(b - a, c - b);
      if (turn == 0.0) {  // collinear: drop the vertex, no triangle
        poly.erase(poly.begin() + i);
        clipped = true;
        break;
      }
      if (turn < 0.0) continue;
      bool ear = true;
      for (size_t k = 0; k < n && ear; ++k) {
        const glm::dvec2& q = poly[k];
        if (q == a || q == b || q == c) continue;
        ear = !InTriangle(q, a, b, c);
      }
      if (!ear) continue;
      triangles.push_back(MakeRegion({a, b, c}));
      poly.erase(poly.begin() + i);
      clipped = true;
    }
    if (!clipped) break;  // not simple; what is left is dropped
  }
  if (poly.size() == 3 && TwiceSignedArea(poly) > 0.0) triangles.push_back(MakeRegion(poly));
  return triangles;
}

// The light, prepared once for many points.
struct PreparedLight {
  double area = 0.0;
  glm::dvec2 lo{0.0}, hi{0.0};
  double tolerance = 0.0;  // kTolerance times the light's extent
  std::vector<Region> regions;
};

std::optional<PreparedLight> PrepareLight(std::span<const glm::dvec2> polygon) {
  std::vector<glm::dvec2> ccw(polygon.begin(), polygon.end());
  for (const glm::dvec2& q : ccw) {
    if (!std::isfinite(q.x) || !std::isfinite(q.y)) return std::nullopt;
  }
  if (ccw.size() < 3) return std::nullopt;
  if (TwiceSignedArea(ccw) < 0.0) std::reverse(ccw.begin(), ccw.end());
  PreparedLight light;
  light.lo = light.hi = ccw[0];
  for (const glm::dvec2& q : ccw) {
    light.lo = glm::min(light.lo, q);
    light.hi = glm::max(light.hi, q);
  }
  light.tolerance = kTolerance * std::max(light.hi.x - light.lo.x, light.hi.y - light.lo.y);
  RemoveNearlyCollinear(light.tolerance, &ccw);
  if (ccw.size() < 3) return std::nullopt;
  light.area = 0.5 * TwiceSignedArea(ccw);
  if (!(light.area > 0.0)) return std::nullopt;
  if (IsConvexCcw(ccw)) {
    light.regions.push_back(MakeRegion(std::move(ccw)));
  } else {
    light.regions = Triangulate(std::move(ccw));
  }
  return light;
}

// Per-point setup: the point and the wedge from it through the light's bounding box.
struct Projector {
  glm::dvec3 p;
  double z_max;  // clip plane just short of the point
  glm::dvec2 lo, hi;

  // Half-spaces whose intersection (with 0 < z < p.z) projects into [lo, hi]: for z < p.z,
  // proj(V).x >= lo.x  <=>  (V.x - p.x) p.z >= (lo.x - p.x)(p.z - V.z), and likewise.
  double WedgeXLo(const glm::dvec3& v) const {
    return (v.x - p.x) * p.z - (lo.x - p.x) * (p.z - v.z);
  }
  double WedgeXHi(const glm::dvec3& v) const {
    return (hi.x - p.x) * (p.z - v.z) - (v.x - p.x) * p.z;
  }
  double WedgeYLo(const glm::dvec3& v) const {
    return (v.y - p.y) * p.z - (lo.y - p.y) * (p.z - v.z);
  }
  double WedgeYHi(const glm::dvec3& v) const {
    return (hi.y - p.y) * (p.z - v.z) - (v.y - p.y) * p.z;
  }

  // Conservative cull: the triangle misses the light's box if all three vertices are outside
  // the same bounding plane (all are linear, so then the whole triangle is).
  bool Misses(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) const {
    if (a.z <= 0.0 && b.z <= 0.0 && c.z <= 0.0) return true;
    if (a.z >= z_max && b.z >= z_max && c.z >= z_max) return true;
    auto all_out = [&](double (Projector::*f)(const glm::dvec3&) const) {
      return (this->*f)(a) < 0.0 && (this->*f)(b) < 0.0 && (this->*f)(c) < 0.0;
    };
    return all_out(&Projector::WedgeXLo) || all_out(&Projector::WedgeXHi) ||
           all_out(&Projector::WedgeYLo) || all_out(&Projector::WedgeYHi);
  }

  glm::dvec2 Project(const glm::dvec3& v) const {
    const double scale = p.z / (p.z - v.z);
    const glm::dvec2 q = glm::dvec2(p) + (glm::dvec2(v) - glm::dvec2(p)) * scale;
    // Inside the wedge up to rounding; the clamp keeps rounding from leaving the box.
    return glm::clamp(q, lo, hi);
  }
};

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

// A uniform grid of ~sqrt(n) x sqrt(n) cells over a region, listing the polygons whose
// (padded) bounding boxes touch each cell: finds the polygons near an edge.
class CellGrid {
 public:
  void Build(const ConvexSet& set, const glm::dvec2& lo, const glm::dvec2& hi, double pad) {
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

// Reusable buffers, one set per thread.
struct Workspace {
  std::vector<glm::dvec3> poly3, scratch3;
  std::vector<glm::dvec2> poly2, scratch2;
  std::vector<double> values;
  ConvexSet projected;  // the clipped, projected triangles
  ConvexSet pieces;     // those clipped to one region
  // Union: the polygons near each cell, the last edge that looked at each polygon, and the
  // covered parameter intervals of one edge.
  CellGrid grid;
  std::vector<uint64_t> visited;
  std::vector<std::pair<double, double>> intervals;
};

// Clips triangle abc to the part between the light and the point that projects into the
// light's box, and projects it: a convex counter-clockwise polygon in ws->poly2. Returns false
// when nothing of positive area is left.
bool ProjectTriangle(const Projector& proj, const glm::dvec3& a, const glm::dvec3& b,
                     const glm::dvec3& c, double min_area, double tolerance, Workspace* ws) {
  std::vector<glm::dvec3>& poly = ws->poly3;
  poly.assign({a, b, c});
  auto clip = [&](auto f, bool strict) {
    ClipConvex(f, strict, &poly, &ws->scratch3, &ws->values);
  };
  clip([](const glm::dvec3& v) { return v.z; }, /*strict=*/true);
  clip([&](const glm::dvec3& v) { return proj.z_max - v.z; }, false);
  clip([&](const glm::dvec3& v) { return proj.WedgeXLo(v); }, false);
  clip([&](const glm::dvec3& v) { return proj.WedgeXHi(v); }, false);
  clip([&](const glm::dvec3& v) { return proj.WedgeYLo(v); }, false);
  clip([&](const glm::dvec3& v) { return proj.WedgeYHi(v); }, false);
  if (poly.size() < 3) return false;
  ws->poly2.clear();
  for (const glm::dvec3& v : poly) ws->poly2.push_back(proj.Project(v));
  RemoveNearlyCollinear(tolerance, &ws->poly2);
  if (ws->poly2.size() < 3) return false;
  const double twice_area = TwiceSignedArea(ws->poly2);
  if (std::abs(twice_area) <= 2.0 * min_area) return false;
  if (twice_area < 0.0) std::reverse(ws->poly2.begin(), ws->poly2.end());
  return true;
}

// Clips the convex counter-clockwise ws->poly2 to a region. Returns twice the area left, 0 if
// nothing of positive area is.
double ClipToRegion(const Region& region, double min_area, double tolerance, Workspace* ws) {
  std::vector<glm::dvec2>& poly = ws->poly2;
  const double r2 = region.inner_radius * region.inner_radius;
  const bool inside = std::all_of(poly.begin(), poly.end(), [&](const glm::dvec2& q) {
    const glm::dvec2 d = q - region.inner_center;
    return glm::dot(d, d) <= r2;
  });
  if (!inside) {
    const size_t n = region.ccw.size();
    for (size_t i = 0; i < n && poly.size() >= 3; ++i) {
      const glm::dvec2 a = region.ccw[i];
      const glm::dvec2 e = region.ccw[(i + 1) % n] - a;
      ClipConvex([&](const glm::dvec2& q) { return Cross(e, q - a); }, false, &poly, &ws->scratch2,
                 &ws->values);
    }
    RemoveNearlyCollinear(tolerance, &poly);
  }
  if (poly.size() < 3) return 0.0;
  const double twice_area = TwiceSignedArea(poly);
  return twice_area > 2.0 * min_area ? twice_area : 0.0;
}

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

// Twice the area that edge k of polygon i contributes to the union, by Green's theorem:
// the cross products of the endpoints of the parts of the edge no other polygon covers.
double EdgeTerm(const ConvexSet& set, const CellGrid& grid, size_t i, uint32_t k, uint64_t edge_id,
                double tolerance, Workspace* ws) {
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
    if (t0 > reached) term += Cross(at(reached), at(t0));
    reached = std::max(reached, t1);
  }
  if (reached < 1.0) term += Cross(at(reached), b);
  return term;
}

// Area of the union of the convex polygons in `set`, which lie within [lo, hi].
double UnionArea(const ConvexSet& set, const glm::dvec2& lo, const glm::dvec2& hi, double tolerance,
                 Workspace* ws) {
  const size_t n = set.size();
  if (n == 0) return 0.0;
  if (n == 1) return set.area[0];
  ws->grid.Build(set, lo, hi, tolerance);
  ws->visited.assign(n, std::numeric_limits<uint64_t>::max());
  uint64_t edge_id = 0;
  CompensatedSum twice_area;
  for (size_t i = 0; i < n; ++i) {
    for (uint32_t k = set.start[i]; k < set.start[i + 1]; ++k, ++edge_id) {
      twice_area.Add(EdgeTerm(set, ws->grid, i, k, edge_id, tolerance, ws));
    }
  }
  return 0.5 * twice_area.Value();
}

// Clips and projects every triangle into ws->projected.
void ProjectAll(const PreparedLight& light, std::span<const glm::dvec3> tris, const Projector& proj,
                double min_area, Workspace* ws) {
  ws->projected.Clear();
  for (size_t t = 0; t + 2 < tris.size(); t += 3) {
    const glm::dvec3& a = tris[t];
    const glm::dvec3& b = tris[t + 1];
    const glm::dvec3& c = tris[t + 2];
    if (!Finite(a) || !Finite(b) || !Finite(c)) continue;
    if (proj.Misses(a, b, c)) continue;
    if (!ProjectTriangle(proj, a, b, c, min_area, light.tolerance, ws)) continue;
    ws->projected.Add(ws->poly2, TwiceSignedArea(ws->poly2));
  }
}

double HiddenFraction(const PreparedLight& light, std::span<const glm::dvec3> triangles,
                      const glm::dvec3& p, Workspace* ws) {
  if (!(p.z > 0.0) || !Finite(p)) return 0.0;
  const Projector proj{p, p.z * (1.0 - kNearPointMargin), light.lo, light.hi};
  const double min_area = kDegenerateAreaFraction * light.area;
  ProjectAll(light, triangles, proj, min_area, ws);
  const ConvexSet& projected = ws->projected;
  double hidden_area = 0.0;
  for (const Region& region : light.regions) {
    ConvexSet& pieces = ws->pieces;
    pieces.Clear();
    bool umbra = false;
    for (size_t i = 0; i < projected.size() && !umbra; ++i) {
      if (glm::any(glm::lessThan(projected.hi[i], region.lo)) ||
          glm::any(glm::greaterThan(projected.lo[i], region.hi))) {
        continue;
      }
      ws->poly2.assign(projected.vertex.begin() + projected.start[i],
                       projected.vertex.begin() + projected.start[i + 1]);
      const double twice_area = ClipToRegion(region, min_area, light.tolerance, ws);
      if (twice_area <= 0.0) continue;
      // A piece as large as its region covers all of it.
      umbra = 0.5 * twice_area >= region.area * (1.0 - 1e-12);
      pieces.Add(ws->poly2, twice_area);
    }
    hidden_area +=
        umbra ? region.area : UnionArea(pieces, region.lo, region.hi, light.tolerance, ws);
  }
  return std::clamp(hidden_area / light.area, 0.0, 1.0);
}

absl::StatusOr<std::vector<glm::dvec2>> LightPolygon(const LightSpec& light) {
  auto positive = [](double x) { return std::isfinite(x) && x > 0.0; };
  switch (light.shape) {
    case LightShape::kRect: {
      if (!positive(light.half_width) || !positive(light.half_height)) {
        return absl::InvalidArgumentError(
            absl::StrFormat("light.rect: size must be positive and finite, got half sizes %g x %g",
                            light.half_width, light.half_height));
      }
      const double w = light.half_width, h = light.half_height;
      return std::vector<glm::dvec2>{{-w, -h}, {w, -h}, {w, h}, {-w, h}};
    }
    case LightShape::kDisk: {
      if (!positive(light.radius)) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "light.disk: radius must be positive and finite, got %g", light.radius));
      }
      // Inscribed regular polygon: the reference is exact for it, and its area is short of
      // the disk's by 2.5e-5 relative, below any bake's sampling error.
      std::vector<glm::dvec2> polygon;
      polygon.reserve(kDiskSides);
      for (int k = 0; k < kDiskSides; ++k) {
        const double angle = 2.0 * std::numbers::pi * k / kDiskSides;
        polygon.emplace_back(light.radius * std::cos(angle), light.radius * std::sin(angle));
      }
      return polygon;
    }
    case LightShape::kSun:
      break;
  }
  return absl::UnimplementedError(
      "exact attenuation supports rect and disk lights only, not sun lights");
}

// All caster triangles in light space, 3 vertices each; those wholly behind the light dropped.
absl::StatusOr<std::vector<glm::dvec3>> CastersInLightSpace(const Scene& scene) {
  const LightFrame& frame = scene.light.frame;
  std::vector<glm::dvec3> triangles;
  for (const TriangleMesh& mesh : scene.meshes) {
    if (!Casts(mesh.role)) continue;
    if (mesh.indices.size() % 3 != 0) {
      return absl::InvalidArgumentError(absl::StrFormat("%s: index count %d is not a multiple of 3",
                                                        mesh.label, mesh.indices.size()));
    }
    for (size_t i = 0; i < mesh.indices.size(); i += 3) {
      glm::dvec3 v[3];
      for (int k = 0; k < 3; ++k) {
        const uint32_t index = mesh.indices[i + k];
        if (index >= mesh.positions_world.size()) {
          return absl::InvalidArgumentError(
              absl::StrFormat("%s: index %d out of range (%d vertices)", mesh.label, index,
                              mesh.positions_world.size()));
        }
        v[k] = frame.LightFromWorld(mesh.positions_world[index]);
      }
      if (v[0].z <= 0.0 && v[1].z <= 0.0 && v[2].z <= 0.0) continue;
      triangles.insert(triangles.end(), {v[0], v[1], v[2]});
    }
  }
  return triangles;
}

}  // namespace

double ExactHiddenFraction(std::span<const glm::dvec2> light_polygon,
                           std::span<const glm::dvec3> triangles, const glm::dvec3& p_light) {
  // A degenerate light has nothing to hide.
  const std::optional<PreparedLight> light = PrepareLight(light_polygon);
  if (!light.has_value()) return 0.0;
  Workspace ws;
  return HiddenFraction(*light, triangles, p_light, &ws);
}

absl::StatusOr<std::vector<double>> ExactAttenuation(const Scene& scene,
                                                     std::span<const glm::dvec3> points_world) {
  absl::StatusOr<std::vector<glm::dvec2>> polygon = LightPolygon(scene.light);
  if (!polygon.ok()) return polygon.status();
  absl::StatusOr<std::vector<glm::dvec3>> triangles = CastersInLightSpace(scene);
  if (!triangles.ok()) return triangles.status();
  const std::optional<PreparedLight> light = PrepareLight(*polygon);
  if (!light.has_value()) return absl::InternalError("light polygon is degenerate");

  std::vector<double> result(points_world.size(), std::numeric_limits<double>::quiet_NaN());
  // Points are independent: threads take them one at a time and each writes only its own
  // slot, so the output does not depend on the scheduling.
  std::atomic<size_t> next{0};
  RunOnAllCores(points_world.size(), [&] {
    Workspace ws;
    for (size_t i = next++; i < points_world.size(); i = next++) {
      const glm::dvec3 p_light = scene.light.frame.LightFromWorld(points_world[i]);
      if (!(p_light.z > 0.0) || !Finite(p_light)) continue;  // stays NaN
      result[i] = HiddenFraction(*light, *triangles, p_light, &ws);
    }
  });
  return result;
}

}  // namespace pdsm
