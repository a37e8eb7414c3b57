#include "core/bake/level_groups.h"

#include <algorithm>
#include <limits>
#include <optional>
#include <vector>

#include "core/bake/refined_pixels.h"

namespace pdsm {
namespace {

// A box in window coordinates (s, t).
struct WindowBox {
  double s0 = std::numeric_limits<double>::infinity(), t0 = s0;
  double s1 = -std::numeric_limits<double>::infinity(), t1 = s1;
  bool empty() const { return !(s0 < s1 && t0 < t1); }
  bool Overlaps(const WindowBox& o) const {
    return s0 <= o.s1 && o.s0 <= s1 && t0 <= o.t1 && o.t0 <= t1;
  }
};

// Each cluster's box as the light's centre sees it.
std::vector<WindowBox> ClusterBoxes(const BakePlan& plan) {
  const bool sun = plan.geometry().projection == Projection::kOrthographic;
  std::vector<WindowBox> boxes;
  boxes.reserve(plan.caster_clusters.size());
  for (const CasterCluster& c : plan.caster_clusters) {
    WindowBox b;
    const double z_lo = std::max(c.lo.z, plan.z_clip_near), z_hi = std::max(c.hi.z, z_lo);
    for (int k = 0; k < 8; ++k) {
      const double x = (k & 1) ? c.hi.x : c.lo.x, y = (k & 2) ? c.hi.y : c.lo.y;
      const double z = (k & 4) ? z_hi : z_lo;
      const double s = sun ? x : x / z, t = sun ? y : y / z;
      b.s0 = std::min(b.s0, s), b.s1 = std::max(b.s1, s);
      b.t0 = std::min(b.t0, t), b.t1 = std::max(b.t1, t);
    }
    boxes.push_back(b);
  }
  return boxes;
}

}  // namespace

int LevelGroupSide(const BakePlan& level) {
  const PdsmGeometry& g = level.geometry();
  std::vector<std::optional<TileRect>> bounds(level.tile_count());
  for (int t = 0; t < level.tile_count(); ++t) {
    if (level.tile_has_casters[t]) bounds[t] = level.refined->LevelRayBounds(level.tile(t));
  }
  const std::vector<WindowBox> clusters = ClusterBoxes(level);
  const double texel_area = level.lattice.pitch_s * level.lattice.pitch_t;
  // Estimated seconds per sample of the groups of `side` tiles.
  const auto cost = [&](int side) {
    double seconds = 0;
    for (int gy = 0; gy < level.tiles_y; gy += side) {
      for (int gx = 0; gx < level.tiles_x; gx += side) {
        int x0 = g.width, y0 = g.height, x1 = 0, y1 = 0;
        for (int ty = gy; ty < std::min(level.tiles_y, gy + side); ++ty) {
          for (int tx = gx; tx < std::min(level.tiles_x, gx + side); ++tx) {
            const std::optional<TileRect>& b = bounds[static_cast<size_t>(ty) * level.tiles_x + tx];
            if (!b) continue;
            x0 = std::min(x0, b->x0), y0 = std::min(y0, b->y0);
            x1 = std::max(x1, b->x0 + b->width), y1 = std::max(y1, b->y0 + b->height);
          }
        }
        if (x0 >= x1 || y0 >= y1) continue;
        const WindowBox rays{g.s_min + x0 * g.PixelPitchS(), g.t_min + y0 * g.PixelPitchT(),
                             g.s_min + x1 * g.PixelPitchS(), g.t_min + y1 * g.PixelPitchT()};
        double triangles = 0;
        for (size_t c = 0; c < clusters.size(); ++c) {
          if (clusters[c].Overlaps(rays)) triangles += level.caster_clusters[c].triangle_count;
        }
        const double texels = (rays.s1 - rays.s0) * (rays.t1 - rays.t0) / texel_area;
        seconds += kMapSecondsPerTriangle * triangles + kMapSecondsPerTexel * texels;
      }
    }
    return seconds;
  };
  int best = 1;
  double best_cost = cost(1);
  for (int side = 2; side <= level.group_side; side *= 2) {
    const double c = cost(side);
    if (c <= best_cost) best = side, best_cost = c;
  }
  return best;
}

}  // namespace pdsm
