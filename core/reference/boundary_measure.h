// What the exact reference integrates over a part of the light plane, seen from a point: its
// area (the unweighted attenuation), its solid angle (emitter-weighted: cos θ_light / r² dA is
// the solid angle dω), or its projected solid angle on a receiver's plane (irradiance-weighted:
// cos θ_light cos θ_receiver / r² dA = cos θ_receiver dω). See light_weighting.h. Each is an
// integral over the region's boundary, a sum of one term per oriented boundary segment, so the
// union of the hidden pieces is measured from its boundary (union_area.h) whatever the measure.
// Internal to core/reference (not a public API).
//
// Frame: light space, the light plane z = 0, the point p at z = h > 0. Polygons are
// counter-clockwise in (x, y).
#ifndef PDSM_CORE_REFERENCE_BOUNDARY_MEASURE_H_
#define PDSM_CORE_REFERENCE_BOUNDARY_MEASURE_H_

#include <span>

#include <glm/glm.hpp>

namespace pdsm::internal {

class BoundaryMeasure {
 public:
  // Area: a segment's term is the signed area of the triangle (origin, s, t).
  static BoundaryMeasure Area() { return BoundaryMeasure(Kind::kArea, glm::dvec3(0.0), {}); }
  // Solid angle seen from p (p.z > 0): a segment's term is the signed solid angle of the
  // triangle (p's foot on the plane, s, t), by Van Oosterom and Strackee's formula.
  static BoundaryMeasure SolidAngle(const glm::dvec3& p) {
    return BoundaryMeasure(Kind::kSolidAngle, p, {});
  }
  // Projected solid angle ∫ cos θ dω seen from p, θ from the unit normal `normal` (light
  // space): a segment's term is Lambert's, half the angle the segment subtends times the
  // normal's component along the normal of the plane through p and the segment. It integrates
  // cos θ with its sign: the caller makes sure the region is on the normal's side of p.
  static BoundaryMeasure ProjectedSolidAngle(const glm::dvec3& p, const glm::dvec3& normal) {
    return BoundaryMeasure(Kind::kProjectedSolidAngle, p, normal);
  }

  bool is_area() const { return kind_ == Kind::kArea; }

  // The term of the oriented segment s → t. The terms of a closed counter-clockwise boundary
  // add up to the measure of the region it encloses; a segment cut in two gives the sum of
  // its halves' terms.
  double Segment(const glm::dvec2& s, const glm::dvec2& t) const;
  // The measure of a counter-clockwise polygon: the sum of its edges' terms.
  double Polygon(std::span<const glm::dvec2> ccw) const;

 private:
  enum class Kind { kArea, kSolidAngle, kProjectedSolidAngle };
  BoundaryMeasure(Kind kind, const glm::dvec3& p, const glm::dvec3& normal)
      : kind_(kind), p_(p), normal_(normal) {}

  Kind kind_;
  glm::dvec3 p_;
  glm::dvec3 normal_;
};

}  // namespace pdsm::internal

#endif  // PDSM_CORE_REFERENCE_BOUNDARY_MEASURE_H_
