#include "core/bake/face_samples.h"

#include <algorithm>
#include <cmath>

namespace pdsm {

std::vector<glm::dvec2> FaceGroupSamples(const BakePlan& plan, int group_index) {
  const PdsmGeometry& g = plan.geometry();
  const TileGroup group = plan.group(group_index);
  // The group's centre direction, light space.
  const double s = g.s_min + (group.x0 + 0.5 * group.width) * g.PixelPitchS();
  const double t = g.t_min + (group.y0 + 0.5 * group.height) * g.PixelPitchT();
  const glm::dvec3 w = glm::normalize(glm::dvec3(s, t, 1.0));
  // The disk facing w, its axes the light's x and y turned with it (w = z gives them back).
  const glm::dvec3 e1 = glm::normalize(glm::dvec3(1, 0, 0) - w.x * w);
  const glm::dvec3 e2 = glm::cross(w, e1);
  std::vector<glm::dvec2> samples;
  samples.reserve(plan.samples.size());
  for (const glm::dvec2& ab : plan.samples) {
    const glm::dvec3 q = ab.x * e1 + ab.y * e2;
    const glm::dvec3 on_plane = q - (q.z / w.z) * w;  // along w onto z = 0
    samples.emplace_back(on_plane.x, on_plane.y);
  }
  return samples;
}

double FaceSampleStretch(const BakePlan& plan) {
  if (!IsSphereFacePlan(plan)) return 1.0;
  const PdsmGeometry& g = plan.geometry();
  const double s = std::max(std::abs(g.s_min), std::abs(g.s_max));
  const double t = std::max(std::abs(g.t_min), std::abs(g.t_max));
  return std::sqrt(1.0 + s * s + t * t);
}

}  // namespace pdsm
