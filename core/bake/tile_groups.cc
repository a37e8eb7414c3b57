#include "core/bake/tile_groups.h"

#include <algorithm>
#include <cmath>

#include "core/bake/bake_plan.h"
#include "core/bake/face_samples.h"

namespace pdsm {
namespace {

// A group's shadow-map window for the widest sample, in texels: its own extent plus how far
// its rays' segments run in that map (|a| w per unit of s for perspective lights, from
// w = 1 / z_first to 0; |a| (z_far - z_first) for the sun), plus two texels of snapping.
double GroupWindowTexels(const BakePlan& plan, int side_tiles) {
  const PdsmGeometry& g = plan.geometry();
  double a_max = 0, b_max = 0;
  for (const glm::dvec2& s : plan.samples) {
    a_max = std::max(a_max, std::abs(s.x));
    b_max = std::max(b_max, std::abs(s.y));
  }
  a_max *= FaceSampleStretch(plan);
  b_max *= FaceSampleStretch(plan);
  const double z_first = std::max({plan.z_scan_floor, plan.z_clip_near, 1e-300});
  const double reach = g.projection == Projection::kPerspective
                           ? 1.0 / z_first
                           : std::max(0.0, g.z_far - std::min(z_first, g.z_far));
  const double side = static_cast<double>(side_tiles) * plan.header.tile_size;
  const double x = (side * g.PixelPitchS() + a_max * reach) / plan.lattice.pitch_s + 2;
  const double y = (side * g.PixelPitchT() + b_max * reach) / plan.lattice.pitch_t + 2;
  return x * y;
}

}  // namespace

int GroupSideInTiles(const BakePlan& plan) {
  const int most = std::max(plan.tiles_x, plan.tiles_y);
  if (plan.tile_group_size > 0) return std::min(plan.tile_group_size, std::max(1, most));
  const int64_t tile_pixels = int64_t{plan.header.tile_size} * plan.header.tile_size;
  int side = 1;
  while (side < most) {
    const int next = 2 * side;
    if (int64_t{next} * next * tile_pixels > kMaxGroupPixels) break;
    if (GroupWindowTexels(plan, next) > static_cast<double>(kShadowMapTexelBudget)) break;
    // A sphere face's group uses the sphere's outline seen from its centre direction: keep
    // its rays within kMaxFaceGroupTangent of that direction (core/bake/face_samples.h).
    const double span = next * plan.header.tile_size *
                        std::max(plan.geometry().PixelPitchS(), plan.geometry().PixelPitchT());
    if (IsSphereFacePlan(plan) && span > kMaxFaceGroupTangent) break;
    side = next;
  }
  return side;
}

}  // namespace pdsm
