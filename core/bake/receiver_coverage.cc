#include "core/bake/receiver_coverage.h"

#include <algorithm>
#include <vector>

#include <glm/glm.hpp>

namespace pdsm {
namespace {

// A half-space dot(normal, p) + offset >= 0 in light space.
struct Plane {
  glm::dvec3 normal;
  double offset;
  double Distance(const glm::dvec3& p) const { return glm::dot(normal, p) + offset; }
};

// The frustum as half-spaces: a perspective window s_min <= x/z <= s_max is x - s_min z >= 0
// and s_max z - x >= 0 for z > 0, so every side is a plane through the light's centre.
std::vector<Plane> FrustumPlanes(const PdsmGeometry& g) {
  std::vector<Plane> planes;
  if (g.projection == Projection::kPerspective) {
    planes = {{{1, 0, -g.s_min}, 0},
              {{-1, 0, g.s_max}, 0},
              {{0, 1, -g.t_min}, 0},
              {{0, -1, g.t_max}, 0},
              {{0, 0, 1}, 0}};  // in front of the light
  } else {
    planes = {
        {{1, 0, 0}, -g.s_min}, {{-1, 0, 0}, g.s_max}, {{0, 1, 0}, -g.t_min}, {{0, -1, 0}, g.t_max}};
  }
  if (g.z_valid_min > 0) planes.push_back({{0, 0, 1}, -g.z_valid_min});
  return planes;
}

// Sutherland-Hodgman: the part of the convex polygon on the plane's inner side.
std::vector<glm::dvec3> Clip(const std::vector<glm::dvec3>& polygon, const Plane& plane) {
  std::vector<glm::dvec3> out;
  for (size_t k = 0; k < polygon.size(); ++k) {
    const glm::dvec3& p = polygon[k];
    const glm::dvec3& q = polygon[(k + 1) % polygon.size()];
    const double dp = plane.Distance(p), dq = plane.Distance(q);
    if (dp >= 0) out.push_back(p);
    if ((dp >= 0) != (dq >= 0)) out.push_back(p + (dp / (dp - dq)) * (q - p));
  }
  return out;
}

double Area(const std::vector<glm::dvec3>& polygon) {
  glm::dvec3 twice(0.0);
  for (size_t k = 1; k + 1 < polygon.size(); ++k) {
    twice += glm::cross(polygon[k] - polygon[0], polygon[k + 1] - polygon[0]);
  }
  return 0.5 * glm::length(twice);
}

}  // namespace

double ReceiverAreaOutsideFrustum(const Scene& scene, const PdsmGeometry& geometry) {
  const std::vector<Plane> planes = FrustumPlanes(geometry);
  double total = 0, inside = 0;
  for (const TriangleMesh& mesh : scene.meshes) {
    if (!Receives(mesh.role)) continue;
    for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
      // Light space: relative to the light's centre, so far-away worlds keep their precision.
      std::vector<glm::dvec3> polygon;
      for (size_t k = 0; k < 3; ++k) {
        polygon.push_back(geometry.frame.LightFromWorld(mesh.positions_world[mesh.indices[i + k]]));
      }
      total += Area(polygon);
      for (const Plane& plane : planes) {
        if (polygon.empty()) break;
        polygon = Clip(polygon, plane);
      }
      if (polygon.size() >= 3) inside += Area(polygon);
    }
  }
  if (!(total > 0)) return 0;
  return std::clamp(1.0 - inside / total, 0.0, 1.0);
}

}  // namespace pdsm
