// The area of a union of convex polygons, from its boundary: by Green's theorem,
// area = 1/2 ∮ (x dy - y dx), where the boundary is every polygon edge minus the parts covered
// by another polygon. Internal to core/reference (not a public API).
//
// Why not Boost.Geometry's union_: Boost 1.74 (Debian 12) fails on exactly the input the exact
// reference sees most, meshes whose projected edges meet at T-junctions that are collinear only
// up to rounding. It returns invalid multipolygons (pieces that share an edge left unmerged),
// and later unions of those return areas off by tens of percent without throwing
// (boostorg/geometry #838, #1068, #1229; the rescaling overlay was replaced in 1.80+).
// The boundary integral has no topology to get wrong: a rounding error in deciding whether a
// point of an edge is covered moves the area by at most (error x edge length), and the one
// discontinuous decision, coincident edges, is made by a test that gives the same answer from
// both sides.
#ifndef PDSM_CORE_REFERENCE_UNION_AREA_H_
#define PDSM_CORE_REFERENCE_UNION_AREA_H_

#include <cstdint>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "core/reference/boundary_measure.h"
#include "core/reference/cell_grid.h"
#include "core/reference/convex_set.h"

namespace pdsm::internal {

// Buffers UnionArea reuses between calls, one per thread: the polygons near each cell, the
// last edge that looked at each polygon, and the covered parameter intervals of one edge.
struct UnionScratch {
  CellGrid grid;
  std::vector<uint64_t> visited;
  std::vector<std::pair<double, double>> intervals;
};

// Area of the union of the convex polygons in `set`, which lie within [lo, hi]. Edges of two
// polygons that lie on one line within `tolerance` (a length) count as coincident: a boundary
// shared by two polygons drops out, and of several coincident edges running the same way one
// survives. Each such decision moves the area by at most `tolerance` times an edge length.
// `scratch` holds no state between calls.
double UnionArea(const ConvexSet& set, const glm::dvec2& lo, const glm::dvec2& hi, double tolerance,
                 UnionScratch* scratch);

// The same union measured by `measure` (boundary_measure.h: area, solid angle or projected
// solid angle from a point), from the same boundary segments: the coincidence decisions are
// UnionArea's, so the union is the same one, whatever the measure.
double UnionMeasure(const ConvexSet& set, const glm::dvec2& lo, const glm::dvec2& hi,
                    double tolerance, const BoundaryMeasure& measure, UnionScratch* scratch);

}  // namespace pdsm::internal

#endif  // PDSM_CORE_REFERENCE_UNION_AREA_H_
