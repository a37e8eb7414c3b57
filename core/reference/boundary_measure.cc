#include "core/reference/boundary_measure.h"

#include <cmath>

namespace pdsm::internal {
namespace {

double Cross2(const glm::dvec2& a, const glm::dvec2& b) { return a.x * b.y - a.y * b.x; }

}  // namespace

double BoundaryMeasure::Segment(const glm::dvec2& s, const glm::dvec2& t) const {
  switch (kind_) {
    case Kind::kArea:
      // Half the cross product: exact scaling, so sums are those of the cross products halved.
      return 0.5 * Cross2(s, t);
    case Kind::kSolidAngle: {
      // tan(Ω/2) = c·(a×b) / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|) for the triangle of
      // directions a, b, c from p; here c = (0, 0, -h) to the foot, a = (u, -h), b = (v, -h).
      // Every term carries one factor h, divided out; the denominator stays positive, so the
      // sign is the orientation's and atan2 keeps full precision for small triangles.
      const double h = p_.z;
      const glm::dvec2 u = s - glm::dvec2(p_), v = t - glm::dvec2(p_);
      const double la = std::sqrt(glm::dot(u, u) + h * h);
      const double lb = std::sqrt(glm::dot(v, v) + h * h);
      return 2.0 * std::atan2(Cross2(u, v), la * lb + glm::dot(u, v) + h * h + h * (la + lb));
    }
    case Kind::kProjectedSolidAngle: {
      const glm::dvec3 a = glm::dvec3(s, 0.0) - p_, b = glm::dvec3(t, 0.0) - p_;
      const glm::dvec3 c = glm::cross(a, b);
      const double length = glm::length(c);
      if (length == 0.0) return 0.0;
      const double angle = std::atan2(length, glm::dot(a, b));
      // The light is below p (z < p.z): a counter-clockwise (x, y) boundary turns clockwise
      // seen from p, hence the minus sign.
      return -0.5 * angle * glm::dot(normal_, c) / length;
    }
  }
  return 0.0;
}

double BoundaryMeasure::Polygon(std::span<const glm::dvec2> ccw) const {
  double sum = 0.0;
  for (size_t k = 0; k < ccw.size(); ++k) sum += Segment(ccw[k], ccw[(k + 1) % ccw.size()]);
  return sum;
}

}  // namespace pdsm::internal
