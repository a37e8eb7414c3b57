#include "core/bake/tile_groups.h"

#include <algorithm>
#include <cmath>

#include "core/bake/bake_plan.h"

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
    side = next;
  }
  return side;
}

std::vector<TileGroup> GroupTiles(const BakePlan& plan) {
  const int side = GroupSideInTiles(plan);
  std::vector<TileGroup> groups;
  groups.reserve(static_cast<size_t>((plan.tiles_y + side - 1) / side) *
                 static_cast<size_t>((plan.tiles_x + side - 1) / side));
  for (int gy = 0; gy < plan.tiles_y; gy += side) {
    for (int gx = 0; gx < plan.tiles_x; gx += side) {
      TileGroup group;
      group.index = static_cast<int>(groups.size());
      // Reserved exactly: a coordinator keeps the groups of every job it runs.
      group.tiles.reserve(static_cast<size_t>(std::min(plan.tiles_y, gy + side) - gy) *
                          static_cast<size_t>(std::min(plan.tiles_x, gx + side) - gx));
      for (int ty = gy; ty < std::min(plan.tiles_y, gy + side); ++ty) {
        for (int tx = gx; tx < std::min(plan.tiles_x, gx + side); ++tx) {
          group.tiles.push_back(ty * plan.tiles_x + tx);
        }
      }
      const TileRect& first = plan.tiles[group.tiles.front()];
      const TileRect& last = plan.tiles[group.tiles.back()];
      group.x0 = first.x0;
      group.y0 = first.y0;
      group.width = last.x0 + last.width - first.x0;
      group.height = last.y0 + last.height - first.y0;
      groups.push_back(std::move(group));
    }
  }
  return groups;
}

}  // namespace pdsm
