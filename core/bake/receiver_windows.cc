#include "core/bake/receiver_windows.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>

namespace pdsm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A receiver triangle as the PDSM sees it: the part in front of the light (perspective: z above
// a hair in front of the light plane), projected to window coordinates.
struct ProjectedTriangle {
  glm::dvec2 st[4];
  int count = 0;
  glm::dvec2 lo{kInf}, hi{-kInf};
  double z_min = kInf, z_max = -kInf;
  glm::dvec3 normal{0.0};  // plane n . p = d, light space
  double d = 0;
};

bool Project(const PdsmGeometry& g, const glm::dvec3 tri[3], double z_min_perspective,
             ProjectedTriangle* out) {
  glm::dvec3 poly[4];
  int n = 0;
  if (g.projection == Projection::kPerspective) {
    for (int k = 0; k < 3; ++k) {  // Sutherland–Hodgman against z >= z_min_perspective
      const glm::dvec3& p = tri[k];
      const glm::dvec3& q = tri[(k + 1) % 3];
      const bool p_in = p.z >= z_min_perspective, q_in = q.z >= z_min_perspective;
      if (p_in) poly[n++] = p;
      if (p_in != q_in) {
        poly[n] = p + (z_min_perspective - p.z) / (q.z - p.z) * (q - p);
        poly[n++].z = z_min_perspective;
      }
    }
  } else {
    std::copy(tri, tri + 3, poly);
    n = 3;
  }
  if (n < 3) return false;
  out->count = n;
  for (int k = 0; k < n; ++k) {
    out->st[k] = g.projection == Projection::kPerspective
                     ? glm::dvec2(poly[k].x / poly[k].z, poly[k].y / poly[k].z)
                     : glm::dvec2(poly[k].x, poly[k].y);
    out->lo = glm::min(out->lo, out->st[k]);
    out->hi = glm::max(out->hi, out->st[k]);
    out->z_min = std::min(out->z_min, poly[k].z);
    out->z_max = std::max(out->z_max, poly[k].z);
  }
  out->normal = glm::cross(tri[1] - tri[0], tri[2] - tri[0]);
  out->d = glm::dot(out->normal, tri[0]);
  return true;
}

// A pixel index from a real, saturated to the int range the tiles can use.
int PixelIndex(double x) { return static_cast<int>(std::clamp(x, -2.0, 1e9)); }

// Separating-axis test of the convex projected polygon against the square centre +- half.
bool Overlaps(const ProjectedTriangle& tri, const glm::dvec2& centre, const glm::dvec2& half) {
  if (tri.hi.x < centre.x - half.x || tri.lo.x > centre.x + half.x) return false;
  if (tri.hi.y < centre.y - half.y || tri.lo.y > centre.y + half.y) return false;
  for (int k = 0; k < tri.count; ++k) {
    const glm::dvec2 edge = tri.st[(k + 1) % tri.count] - tri.st[k];
    const glm::dvec2 axis(-edge.y, edge.x);
    if (axis == glm::dvec2(0.0)) continue;
    double p_lo = kInf, p_hi = -kInf;
    for (int v = 0; v < tri.count; ++v) {
      const double p = glm::dot(axis, tri.st[v]);
      p_lo = std::min(p_lo, p);
      p_hi = std::max(p_hi, p);
    }
    const double c = glm::dot(axis, centre);
    const double r = half.x * std::abs(axis.x) + half.y * std::abs(axis.y);
    // A margin of 1e-9 of the square's reach keeps touching edges overlapping.
    if (c + r * (1 + 1e-9) < p_lo || c - r * (1 + 1e-9) > p_hi) return false;
  }
  return true;
}

// Depth range of the triangle's plane over the square, clamped to the triangle's own range.
// Perspective: 1/z is affine in (s, t) on a plane, so its extremes are at the corners while it
// keeps one sign; orthographic: z itself is affine. Otherwise (a plane seen edge-on from the
// light, or crossing it) the triangle's whole range.
DepthWindow DepthOver(const PdsmGeometry& g, const ProjectedTriangle& tri, const glm::dvec2& centre,
                      const glm::dvec2& half) {
  DepthWindow w{kInf, -kInf};
  const double tiny = 1e-12 * glm::length(tri.normal) * (1.0 + std::abs(tri.z_max));
  for (int corner = 0; corner < 4; ++corner) {
    const glm::dvec2 st(centre.x + ((corner & 1) ? half.x : -half.x),
                        centre.y + ((corner & 2) ? half.y : -half.y));
    double z;
    if (g.projection == Projection::kPerspective) {
      const double denom = glm::dot(tri.normal, glm::dvec3(st, 1.0));
      if (!(std::abs(denom) > tiny) || !(tri.d / denom > 0)) return {tri.z_min, tri.z_max};
      z = tri.d / denom;
    } else {
      if (!(std::abs(tri.normal.z) > tiny)) return {tri.z_min, tri.z_max};
      z = (tri.d - tri.normal.x * st.x - tri.normal.y * st.y) / tri.normal.z;
    }
    w.lo = std::min(w.lo, z);
    w.hi = std::max(w.hi, z);
  }
  w.lo = std::max(w.lo, tri.z_min);
  w.hi = std::min(w.hi, tri.z_max);
  if (!(w.lo <= w.hi)) return {tri.z_min, tri.z_max};
  return w;
}

// Sorts, pads and merges one pixel's windows in place.
void MergeWindows(double abs_pad, std::vector<DepthWindow>* windows) {
  for (DepthWindow& w : *windows) {
    w.lo -= kWindowRelativePad * std::abs(w.lo) + abs_pad;
    w.hi += kWindowRelativePad * std::abs(w.hi) + abs_pad;
  }
  std::sort(windows->begin(), windows->end(), [](const DepthWindow& a, const DepthWindow& b) {
    return a.lo < b.lo || (a.lo == b.lo && a.hi < b.hi);
  });
  size_t out = 0;
  for (size_t k = 0; k < windows->size(); ++k) {
    if (out > 0 && (*windows)[k].lo <= (*windows)[out - 1].hi) {
      (*windows)[out - 1].hi = std::max((*windows)[out - 1].hi, (*windows)[k].hi);
    } else {
      (*windows)[out++] = (*windows)[k];
    }
  }
  windows->resize(out);
}

}  // namespace

TileWindows ComputeReceiverWindows(const BakePlan& plan, const TileRect& tile) {
  return ComputeReceiverWindowsAt(plan, tile, glm::dvec2(0.5), 1.0);
}

TileWindows ComputeReceiverWindowsAt(const BakePlan& plan, const TileRect& grid,
                                     const glm::dvec2& offset, double half_pixels) {
  return ComputeReceiverWindowsAt(plan, plan.receivers, grid, offset, half_pixels);
}

TileWindows ComputeReceiverWindowsAt(const BakePlan& plan, const LightSpaceMesh& mesh,
                                     const TileRect& grid, const glm::dvec2& offset,
                                     double half_pixels) {
  const PdsmGeometry& g = plan.geometry();
  const glm::dvec2 pitch(g.PixelPitchS(), g.PixelPitchT());
  const glm::dvec2 half = half_pixels * pitch;
  std::vector<std::vector<DepthWindow>> per_point(static_cast<size_t>(grid.width) * grid.height);
  // Receivers may lie nearer than any caster: clip only a hair in front of the light plane.
  const double z_min_perspective = 1e-6 * std::abs(g.z_far);
  for (size_t k = 0; k < mesh.TriangleCount(); ++k) {
    const glm::dvec3 tri[3] = {glm::dvec3(mesh.positions[mesh.indices[3 * k]]),
                               glm::dvec3(mesh.positions[mesh.indices[3 * k + 1]]),
                               glm::dvec3(mesh.positions[mesh.indices[3 * k + 2]])};
    ProjectedTriangle projected;
    if (!Project(g, tri, z_min_perspective, &projected)) continue;
    // Points whose square [centre - half, centre + half] meets the triangle's bounds. (The
    // shifts summed first: for pixel centres they are 1.5 and 0.5 exactly, as they always were.)
    const glm::dvec2 lo_shift = offset + half_pixels, hi_shift = half_pixels - offset;
    const int i_lo =
        std::max(grid.x0, PixelIndex(std::ceil((projected.lo.x - g.s_min) / pitch.x - lo_shift.x)));
    const int i_hi =
        std::min(grid.x0 + grid.width - 1,
                 PixelIndex(std::floor((projected.hi.x - g.s_min) / pitch.x + hi_shift.x)));
    const int j_lo =
        std::max(grid.y0, PixelIndex(std::ceil((projected.lo.y - g.t_min) / pitch.y - lo_shift.y)));
    const int j_hi =
        std::min(grid.y0 + grid.height - 1,
                 PixelIndex(std::floor((projected.hi.y - g.t_min) / pitch.y + hi_shift.y)));
    for (int j = j_lo; j <= j_hi; ++j) {
      for (int i = i_lo; i <= i_hi; ++i) {
        const glm::dvec2 centre(g.s_min + (i + offset.x) * pitch.x,
                                g.t_min + (j + offset.y) * pitch.y);
        if (!Overlaps(projected, centre, half)) continue;
        per_point[static_cast<size_t>(j - grid.y0) * grid.width + (i - grid.x0)].push_back(
            DepthOver(g, projected, centre, half));
      }
    }
  }
  TileWindows out;
  out.rect = grid;
  out.offsets.assign(per_point.size() + 1, 0);
  const double abs_pad = 1e-9 * std::abs(g.z_far);
  for (size_t p = 0; p < per_point.size(); ++p) {
    MergeWindows(abs_pad, &per_point[p]);
    out.windows.insert(out.windows.end(), per_point[p].begin(), per_point[p].end());
    out.offsets[p + 1] = out.windows.size();
  }
  return out;
}

}  // namespace pdsm
