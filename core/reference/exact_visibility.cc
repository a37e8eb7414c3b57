#include "core/reference/exact_visibility.h"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
// Boost 1.74's envelope and rescale code trips GCC 12's -Wmaybe-uninitialized (false alarms).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/geometry.hpp>
#include <iostream>
#include <boost/geometry/geometries/multi_polygon.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/polygon.hpp>
#pragma GCC diagnostic pop
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"

#ifndef UNION_SLACK
#define UNION_SLACK kUnionAreaSlack
#endif
namespace pdsm {
namespace {

namespace bg = boost::geometry;
using BgPoint = bg::model::d2::point_xy<double>;
// Counter-clockwise and closed: the orientation the clipping below produces.
using BgPolygon = bg::model::polygon<BgPoint, /*ClockWise=*/false, /*Closed=*/true>;
using BgMultiPolygon = bg::model::multi_polygon<BgPolygon>;

// Geometry closer to the point than this (relative to p.z) is dropped: its projection runs
// off to infinity and only matters for triangles through p itself, which hide nothing.
constexpr double kNearPointMargin = 1e-9;
// The disk light's stand-in. Relative area error 1 - sin(2π/n)/(2π/n) = 2.51e-5 for n = 512.
constexpr int kDiskSides = 512;
// Projected pieces below this share of the light are degenerate (edge-on triangles, slivers
// from clipping) and are dropped: Boost.Geometry's overlay is at its least reliable there.
constexpr double kDegenerateAreaFraction = 1e-14;
// A union whose area is outside [max(a, b), a + b] widened by this share of the light is
// treated as a failed operation (Boost.Geometry can return garbage without throwing).
constexpr double kUnionAreaSlack = 1e-9;
// Size of the nudge, relative to the light's extent, applied to an operand that made a boolean
// operation fail. Moves the hidden area by at most perimeter * nudge: far below 1e-9.
constexpr double kNudgeFraction = 1e-10;

// Vertices this close (relative to the light's extent) to a neighbour or to the line through
// their neighbours are dropped: far above rounding noise, far below any meaningful detail.
constexpr double kCleanTolerance = 1e-11;

std::shared_ptr<spdlog::logger> Logger() {
  static const std::shared_ptr<spdlog::logger> logger = [] {
    std::shared_ptr<spdlog::logger> existing = spdlog::get("reference");
    return existing != nullptr ? existing : spdlog::stderr_color_mt("reference");
  }();
  return logger;
}

// How often Boost.Geometry had to be worked around: failed attempts, operations that
// succeeded on a retry, and operands left out after every retry failed. skipped_area bounds
// the error those cause, in units of the light's area.
struct BooleanStats {
  int64_t failures = 0;
  int64_t recovered = 0;
  int64_t skipped = 0;
  double skipped_area = 0.0;

  void Add(const BooleanStats& o) {
    failures += o.failures;
    recovered += o.recovered;
    skipped += o.skipped;
    skipped_area += o.skipped_area;
  }
};

bool Finite(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

double Cross(const glm::dvec2& a, const glm::dvec2& b) { return a.x * b.y - a.y * b.x; }

// Twice the signed area (counter-clockwise positive), relative to the first vertex to keep
// the products small.
double TwiceSignedArea(const std::vector<glm::dvec2>& poly) {
  double sum = 0.0;
  for (size_t i = 1; i + 1 < poly.size(); ++i) {
    sum += Cross(poly[i] - poly[0], poly[i + 1] - poly[0]);
  }
  return sum;
}

// The light, prepared once for many points.
struct PreparedLight {
  std::vector<glm::dvec2> ccw;  // counter-clockwise, no repeated closing vertex
  double area = 0.0;
  glm::dvec2 box_lo{0.0}, box_hi{0.0};
  double extent = 0.0;  // largest bounding-box side
  double clean_tolerance = 0.0;  // for RemoveNearlyCollinear
  // Convex lights are intersected by plain clipping; anything within inner_radius of
  // inner_center is inside the light and needs no clipping at all.
  bool convex = false;
  glm::dvec2 inner_center{0.0};
  double inner_radius = 0.0;
  BgPolygon bg;  // for non-convex lights
};

// Removes repeated vertices (consecutive and the wrap-around) closer than `tolerance`.
void RemoveDuplicates(double tolerance, std::vector<glm::dvec2>* poly) {
  const double tol2 = tolerance * tolerance;
  auto same = [tol2](const glm::dvec2& a, const glm::dvec2& b) {
    const glm::dvec2 d = a - b;
    return glm::dot(d, d) <= tol2;
  };
  size_t out = 0;
  for (size_t i = 0; i < poly->size(); ++i) {
    if (out > 0 && same((*poly)[out - 1], (*poly)[i])) continue;
    (*poly)[out++] = (*poly)[i];
  }
  while (out > 1 && same((*poly)[out - 1], (*poly)[0])) --out;
  poly->resize(out);
}

// Removes vertices within `tolerance` of their predecessor or of the line through their
// neighbours (collinear points and spikes). Boost.Geometry keeps or drops such points
// depending on rounding, and then fails to merge a T-junction whose middle vertex is 1e-17
// off the other polygon's edge; without them, shared boundaries are bit-identical.
// Moves the boundary by at most `tolerance`.
void RemoveNearlyCollinear(double tolerance, std::vector<glm::dvec2>* ring) {
  auto close = [tolerance](const glm::dvec2& a, const glm::dvec2& b) {
    return glm::length(b - a) <= tolerance;
  };
  // b is within tolerance of the line through a and c (or a ~ c, so a-b-c is a spike).
  auto redundant = [&](const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
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

// RemoveNearlyCollinear on every ring; rings and polygons left degenerate are dropped.
void CleanShape(double tolerance, BgMultiPolygon* shape) {
  std::vector<glm::dvec2> ring;
  auto clean_ring = [&](auto& bg_ring) {
    ring.clear();
    // Boost rings are closed: the last point repeats the first.
    for (size_t i = 0; i + 1 < bg_ring.size(); ++i) ring.emplace_back(bg_ring[i].x(), bg_ring[i].y());
    RemoveNearlyCollinear(tolerance, &ring);
    bg_ring.clear();
    if (ring.empty()) return false;
    for (const glm::dvec2& q : ring) bg_ring.emplace_back(q.x, q.y);
    bg_ring.emplace_back(ring.front().x, ring.front().y);
    return true;
  };
  BgMultiPolygon cleaned;
  for (BgPolygon& poly : *shape) {
    if (!clean_ring(poly.outer())) continue;
    auto& inners = poly.inners();
    inners.erase(std::remove_if(inners.begin(), inners.end(),
                                [&](auto& inner) { return !clean_ring(inner); }),
                 inners.end());
    cleaned.push_back(std::move(poly));
  }
  *shape = std::move(cleaned);
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

BgPolygon ToBg(const std::vector<glm::dvec2>& ccw) {
  BgPolygon poly;
  poly.outer().reserve(ccw.size() + 1);
  for (const glm::dvec2& q : ccw) poly.outer().emplace_back(q.x, q.y);
  poly.outer().emplace_back(ccw.front().x, ccw.front().y);
  return poly;
}

std::optional<PreparedLight> PrepareLight(std::span<const glm::dvec2> polygon) {
  PreparedLight light;
  light.ccw.assign(polygon.begin(), polygon.end());
  for (const glm::dvec2& q : light.ccw) {
    if (!std::isfinite(q.x) || !std::isfinite(q.y)) return std::nullopt;
  }
  RemoveDuplicates(0.0, &light.ccw);
  if (light.ccw.size() < 3) return std::nullopt;
  double twice_area = TwiceSignedArea(light.ccw);
  if (twice_area < 0.0) {
    std::reverse(light.ccw.begin(), light.ccw.end());
    twice_area = -twice_area;
  }
  if (!(twice_area > 0.0)) return std::nullopt;
  light.area = 0.5 * twice_area;
  light.box_lo = light.box_hi = light.ccw[0];
  for (const glm::dvec2& q : light.ccw) {
    light.box_lo = glm::min(light.box_lo, q);
    light.box_hi = glm::max(light.box_hi, q);
  }
  light.extent = std::max(light.box_hi.x - light.box_lo.x, light.box_hi.y - light.box_lo.y);
  light.clean_tolerance = kCleanTolerance * light.extent;
  light.convex = IsConvexCcw(light.ccw);
  if (light.convex) {
    glm::dvec2 sum(0.0);
    for (const glm::dvec2& q : light.ccw) sum += q;
    light.inner_center = sum / static_cast<double>(light.ccw.size());
    double radius = std::numeric_limits<double>::infinity();
    const size_t n = light.ccw.size();
    for (size_t i = 0; i < n; ++i) {
      const glm::dvec2 a = light.ccw[i];
      const glm::dvec2 e = light.ccw[(i + 1) % n] - a;
      radius = std::min(radius, Cross(e, light.inner_center - a) / glm::length(e));
    }
    // Shrunk a little so that rounding in the distance test can never wrongly skip a clip.
    light.inner_radius = std::max(0.0, radius * (1.0 - 1e-9));
  }
  light.bg = ToBg(light.ccw);
  bg::correct(light.bg);
  return light;
}

template <typename Vec>
bool LexLess(const Vec& a, const Vec& b) {
  for (int i = 0; i < Vec::length(); ++i) {
    if (a[i] != b[i]) return a[i] < b[i];
  }
  return false;
}

// Where segment ab crosses {f = 0}. Interpolated from the lexicographically smaller end, so
// an edge shared by two mesh triangles is cut at bit-identical points in both and their
// projections still share the edge exactly (Boost.Geometry merges exact shared edges well,
// nearly-shared ones badly).
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

// Reusable buffers, one set per thread.
struct Workspace {
  std::vector<glm::dvec3> poly3, scratch3;
  std::vector<glm::dvec2> poly2, scratch2;
  std::vector<double> values;
};

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
  // the same bounding plane (all linear, so the whole triangle is).
  bool Misses(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) const {
    if (a.z <= 0.0 && b.z <= 0.0 && c.z <= 0.0) return true;
    if (a.z >= z_max && b.z >= z_max && c.z >= z_max) return true;
    auto all_out = [&](auto f) { return f(a) < 0.0 && f(b) < 0.0 && f(c) < 0.0; };
    return all_out([&](const glm::dvec3& v) { return WedgeXLo(v); }) ||
           all_out([&](const glm::dvec3& v) { return WedgeXHi(v); }) ||
           all_out([&](const glm::dvec3& v) { return WedgeYLo(v); }) ||
           all_out([&](const glm::dvec3& v) { return WedgeYHi(v); });
  }

  glm::dvec2 Project(const glm::dvec3& v) const {
    const double scale = p.z / (p.z - v.z);
    const glm::dvec2 q = glm::dvec2(p) + (glm::dvec2(v) - glm::dvec2(p)) * scale;
    // Inside the wedge up to rounding; the clamp keeps rounding from leaving the box.
    return glm::clamp(q, lo, hi);
  }
};

// Clips triangle abc to the part between the light and the point that projects into the
// light's box, and projects it: a convex polygon, counter-clockwise, in ws->poly2. Returns
// false when nothing of positive area is left.
bool ProjectTriangle(const Projector& proj, const glm::dvec3& a, const glm::dvec3& b,
                     const glm::dvec3& c, double min_area, double clean_tolerance,
                     Workspace* ws) {
  std::vector<glm::dvec3>& poly = ws->poly3;
  poly.assign({a, b, c});
  ClipConvex([](const glm::dvec3& v) { return v.z; }, /*strict=*/true, &poly, &ws->scratch3,
             &ws->values);
  ClipConvex([&](const glm::dvec3& v) { return proj.z_max - v.z; }, false, &poly, &ws->scratch3,
             &ws->values);
  ClipConvex([&](const glm::dvec3& v) { return proj.WedgeXLo(v); }, false, &poly, &ws->scratch3,
             &ws->values);
  ClipConvex([&](const glm::dvec3& v) { return proj.WedgeXHi(v); }, false, &poly, &ws->scratch3,
             &ws->values);
  ClipConvex([&](const glm::dvec3& v) { return proj.WedgeYLo(v); }, false, &poly, &ws->scratch3,
             &ws->values);
  ClipConvex([&](const glm::dvec3& v) { return proj.WedgeYHi(v); }, false, &poly, &ws->scratch3,
             &ws->values);
  if (poly.size() < 3) return false;
  ws->poly2.clear();
  for (const glm::dvec3& v : poly) ws->poly2.push_back(proj.Project(v));
  RemoveNearlyCollinear(clean_tolerance, &ws->poly2);
  if (ws->poly2.size() < 3) return false;
  const double twice_area = TwiceSignedArea(ws->poly2);
  if (std::abs(twice_area) <= 2.0 * min_area) return false;
  if (twice_area < 0.0) std::reverse(ws->poly2.begin(), ws->poly2.end());
  return true;
}

// Clips the convex ccw polygon ws->poly2 to a convex light. Returns false if nothing is left.
bool ClipToConvexLight(const PreparedLight& light, double min_area, Workspace* ws) {
  std::vector<glm::dvec2>& poly = ws->poly2;
  const double r2 = light.inner_radius * light.inner_radius;
  const bool inside = std::all_of(poly.begin(), poly.end(), [&](const glm::dvec2& q) {
    const glm::dvec2 d = q - light.inner_center;
    return glm::dot(d, d) <= r2;
  });
  if (inside) return true;
  const size_t n = light.ccw.size();
  for (size_t i = 0; i < n && poly.size() >= 3; ++i) {
    const glm::dvec2 a = light.ccw[i];
    const glm::dvec2 e = light.ccw[(i + 1) % n] - a;
    ClipConvex([&](const glm::dvec2& q) { return Cross(e, q - a); }, false, &poly, &ws->scratch2,
               &ws->values);
  }
  RemoveNearlyCollinear(light.clean_tolerance, &poly);
  return poly.size() >= 3 && TwiceSignedArea(poly) > 2.0 * min_area;
}

void Nudge(double dx, double dy, BgMultiPolygon* shape) {
  auto move_ring = [&](auto& ring) {
    for (BgPoint& q : ring) q = BgPoint(q.x() + dx, q.y() + dy);
  };
  for (BgPolygon& poly : *shape) {
    move_ring(poly.outer());
    for (auto& inner : poly.inners()) move_ring(inner);
  }
}

// Runs a Boost.Geometry boolean operation `op` (which returns the result's area, or nullopt
// when that area is implausible). Boost.Geometry can throw (overlay_invalid_input_exception
// and friends) or return garbage on nearly-degenerate turns; both are retried with the
// operands swapped (the turn traversal depends on the order), then with `b` nudged by a tiny
// amount. Returns nullopt if every attempt failed.
template <typename Op>
std::optional<double> TryBoolean(const Op& op, double nudge, const BgMultiPolygon& a,
                                 const BgMultiPolygon& b, BgMultiPolygon* out,
                                 BooleanStats* stats) {
  constexpr int kAttempts = 4;
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    out->clear();
    std::optional<double> area;
    try {
      if (attempt == 0) {
        area = op(a, b, out);
      } else if (attempt == 1) {
        area = op(b, a, out);
      } else {
        // An irrational-ish direction, unlikely to line the moved edges up with others.
        BgMultiPolygon moved = b;
        const double step = nudge * (attempt - 1);
        Nudge(step * 0.8191520442889918, step * 0.5735764363510461, &moved);
        area = op(a, moved, out);
      }
    } catch (const std::exception&) {
      area.reset();
    }
    if (area.has_value()) {
      if (attempt > 0) ++stats->recovered;
      return area;
    }
    ++stats->failures;
  }
  out->clear();
  return std::nullopt;
}

struct Piece {
  BgMultiPolygon shape;
  double area = 0.0;
  uint64_t morton = 0;  // of the centre, for locality of the union tree
};

uint64_t SpreadBits(uint32_t x) {
  uint64_t v = x;
  v = (v | (v << 16)) & 0x0000FFFF0000FFFFULL;
  v = (v | (v << 8)) & 0x00FF00FF00FF00FFULL;
  v = (v | (v << 4)) & 0x0F0F0F0F0F0F0F0FULL;
  v = (v | (v << 2)) & 0x3333333333333333ULL;
  v = (v | (v << 1)) & 0x5555555555555555ULL;
  return v;
}

uint64_t MortonCode(const PreparedLight& light, const std::vector<glm::dvec2>& poly) {
  glm::dvec2 lo = poly[0], hi = poly[0];
  for (const glm::dvec2& q : poly) {
    lo = glm::min(lo, q);
    hi = glm::max(hi, q);
  }
  const glm::dvec2 t = (0.5 * (lo + hi) - light.box_lo) / std::max(light.extent, 1e-300);
  auto quantize = [](double u) { return static_cast<uint32_t>(std::clamp(u, 0.0, 1.0) * 65535.0); };
  return SpreadBits(quantize(t.x)) | (SpreadBits(quantize(t.y)) << 1);
}

// The projected, light-clipped pieces of all triangles, in Morton order.
std::vector<Piece> CollectPieces(const PreparedLight& light, std::span<const glm::dvec3> tris,
                                 const glm::dvec3& p, BooleanStats* stats) {
  const Projector proj{p, p.z * (1.0 - kNearPointMargin), light.box_lo, light.box_hi};
  const double min_area = kDegenerateAreaFraction * light.area;
  const double nudge = kNudgeFraction * light.extent;
  Workspace ws;
  std::vector<Piece> pieces;
  for (size_t t = 0; t + 2 < tris.size(); t += 3) {
    const glm::dvec3& a = tris[t];
    const glm::dvec3& b = tris[t + 1];
    const glm::dvec3& c = tris[t + 2];
    if (!Finite(a) || !Finite(b) || !Finite(c)) continue;
    if (proj.Misses(a, b, c)) continue;
    if (!ProjectTriangle(proj, a, b, c, min_area, light.clean_tolerance, &ws)) continue;
    Piece piece;
    piece.morton = MortonCode(light, ws.poly2);
    if (light.convex) {
      if (!ClipToConvexLight(light, min_area, &ws)) continue;
      piece.area = 0.5 * TwiceSignedArea(ws.poly2);
      piece.shape.push_back(ToBg(ws.poly2));
    } else {
      BgMultiPolygon projected{ToBg(ws.poly2)};
      const BgMultiPolygon light_shape{light.bg};
      auto intersect = [&](const BgMultiPolygon& x, const BgMultiPolygon& y,
                           BgMultiPolygon* out) -> std::optional<double> {
        bg::intersection(x, y, *out);
        const double area = bg::area(*out);
        const double slack = kUnionAreaSlack * light.area;
        if (!(area >= -slack && area <= std::min(bg::area(x), bg::area(y)) + slack)) {
          return std::nullopt;
        }
        return area;
      };
      std::optional<double> area =
          TryBoolean(intersect, nudge, light_shape, projected, &piece.shape, stats);
      if (!area.has_value()) {
        ++stats->skipped;
        stats->skipped_area += bg::area(projected) / light.area;
        continue;
      }
      CleanShape(light.clean_tolerance, &piece.shape);
      piece.area = bg::area(piece.shape);
      if (piece.area <= min_area) continue;
    }
    pieces.push_back(std::move(piece));
  }
  // Neighbours first: unions of nearby pieces merge into compact shapes, which keeps the
  // intermediate results of the union tree small.
  std::stable_sort(pieces.begin(), pieces.end(),
                   [](const Piece& x, const Piece& y) { return x.morton < y.morton; });
  return pieces;
}

// Union of two pieces. On persistent failure keeps the larger one and records the other.
Piece UnionOf(const PreparedLight& light, Piece a, Piece b, BooleanStats* stats) {
  const double slack = UNION_SLACK * light.area;
  auto unite = [&](const BgMultiPolygon& x, const BgMultiPolygon& y,
                   BgMultiPolygon* out) -> std::optional<double> {
    bg::union_(x, y, *out);
    const double area = bg::area(*out);
#ifdef PDSM_EXACT_DEBUG2
    std::string reason;
    fprintf(stderr, "union %.15g + %.15g -> %.15g  valid x=%d y=%d out=%d\n", bg::area(x), bg::area(y), area, (int)bg::is_valid(x), (int)bg::is_valid(y), (int)bg::is_valid(*out, reason));
    if (!reason.empty() && reason != "Geometry is valid") fprintf(stderr, "  %s\n", reason.c_str());
    if (!bg::is_valid(*out)) { std::cerr.precision(17); std::cerr << bg::wkt(x) << "\n" << bg::wkt(y) << "\n" << bg::wkt(*out) << "\n"; }
#endif
    // The union can be neither smaller than either operand nor larger than both together.
    if (!(area >= std::max(a.area, b.area) - slack && area <= a.area + b.area + slack)) {
      return std::nullopt;
    }
    return area;
  };
  Piece result;
  result.morton = a.morton;
  const std::optional<double> area =
      TryBoolean(unite, kNudgeFraction * light.extent, a.shape, b.shape, &result.shape, stats);
  if (area.has_value()) {
    CleanShape(light.clean_tolerance, &result.shape);
    result.area = bg::area(result.shape);
    return result;
  }
  ++stats->skipped;
  stats->skipped_area += std::min(a.area, b.area) / light.area;
  return a.area >= b.area ? std::move(a) : std::move(b);
}

double HiddenFraction(const PreparedLight& light, std::span<const glm::dvec3> triangles,
                      const glm::dvec3& p, BooleanStats* stats) {
  if (!(p.z > 0.0) || !Finite(p)) return 0.0;
  std::vector<Piece> pieces = CollectPieces(light, triangles, p, stats);
  const double full = light.area * (1.0 - 1e-12);
  // Every piece lies inside the light: one that is as large as the light is the umbra.
  for (const Piece& piece : pieces) {
    if (piece.area >= full) return 1.0;
  }
  // Balanced pairwise union: O(log n) levels instead of n ever-growing unions.
  while (pieces.size() > 1) {
    std::vector<Piece> next;
    next.reserve((pieces.size() + 1) / 2);
    for (size_t i = 0; i + 1 < pieces.size(); i += 2) {
      next.push_back(UnionOf(light, std::move(pieces[i]), std::move(pieces[i + 1]), stats));
      if (next.back().area >= full) return 1.0;
    }
    if (pieces.size() % 2 == 1) next.push_back(std::move(pieces.back()));
    pieces = std::move(next);
  }
  if (pieces.empty()) return 0.0;
  return std::clamp(pieces[0].area / light.area, 0.0, 1.0);
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
  BooleanStats stats;
  return HiddenFraction(*light, triangles, p_light, &stats);
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
  // Points are independent: threads take them one at a time, each writing its own slot, so
  // the output does not depend on the scheduling.
  const size_t thread_count = std::clamp<size_t>(std::thread::hardware_concurrency(), 1,
                                                 std::max<size_t>(points_world.size(), 1));
  std::vector<BooleanStats> stats(thread_count);
  std::atomic<size_t> next{0};
  auto work = [&](size_t thread_index) {
    for (size_t i = next++; i < points_world.size(); i = next++) {
      const glm::dvec3 p_light = scene.light.frame.LightFromWorld(points_world[i]);
      if (!(p_light.z > 0.0) || !Finite(p_light)) continue;  // stays NaN
      result[i] = HiddenFraction(*light, *triangles, p_light, &stats[thread_index]);
    }
  };
  std::vector<std::thread> threads;
  for (size_t t = 1; t < thread_count; ++t) threads.emplace_back(work, t);
  work(0);
  for (std::thread& thread : threads) thread.join();

  BooleanStats total;
  for (const BooleanStats& s : stats) total.Add(s);
  if (total.skipped > 0) {
    Logger()->warn(
        "exact reference: {} Boost.Geometry operations failed after every retry; operands "
        "left out, total {:.3g} of the light area over {} points",
        total.skipped, total.skipped_area, points_world.size());
  } else if (total.failures > 0) {
    Logger()->info("exact reference: {} Boost.Geometry operations needed a retry ({} recovered)",
                   total.failures, total.recovered);
  }
  return result;
}

}  // namespace pdsm
