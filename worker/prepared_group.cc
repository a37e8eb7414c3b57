#include "worker/prepared_group.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/bake/scan_windows.h"
#include "core/bake/tile_reach.h"

namespace pdsm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The blocks of rays to scan, each with its depth range: from the block's z_begin to the
// ray's natural end, or (surfaces only) to the deepest window of its pixels. A block whose
// windows all lie nearer than z_begin is all lit where it is defined: not scanned.
std::vector<BlockScan> ScannedBlocks(const BakePlan& plan, const TileReach& reach,
                                     const std::optional<TileWindows>& windows) {
  const PdsmGeometry& g = plan.geometry();
  const double natural_end = g.projection == Projection::kPerspective ? kInf : g.z_far;
  std::vector<BlockScan> out;
  for (const RayBlock& block : reach.blocks) {
    BlockScan scan{block.rect, block.z_begin, natural_end};
    if (windows) {
      double shallowest = kInf, deepest = -kInf;
      for (int y = block.rect.y0; y < block.rect.y0 + block.rect.height; ++y) {
        for (int x = block.rect.x0; x < block.rect.x0 + block.rect.width; ++x) {
          const size_t p = static_cast<size_t>(y - windows->rect.y0) * windows->rect.width +
                           (x - windows->rect.x0);
          for (const DepthWindow& w : windows->Pixel(p)) {
            if (!(w.hi > block.z_begin)) continue;  // lit: nothing shadows it
            shallowest = std::min(shallowest, w.lo);
            deepest = std::max(deepest, w.hi);
          }
        }
      }
      if (!(deepest > block.z_begin)) continue;
      scan.z_begin = std::max(block.z_begin, shallowest);
      scan.z_end = std::min(natural_end, deepest);
      if (!(scan.z_end > scan.z_begin)) continue;
    }
    out.push_back(scan);
  }
  return out;
}

// The union of the tiles' triangles (each list ascending: in the casters' cluster order).
std::vector<uint32_t> UnionOfTriangles(const std::vector<std::vector<uint32_t>>& lists) {
  std::vector<uint32_t> all;
  for (const std::vector<uint32_t>& list : lists) all.insert(all.end(), list.begin(), list.end());
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  return all;
}

// The runs of `triangles` (ascending) within each plan cluster, with their boxes.
std::vector<UploadedCluster> ClusterRuns(const BakePlan& plan,
                                         const std::vector<uint32_t>& triangles) {
  std::vector<UploadedCluster> runs;
  size_t i = 0;
  for (const CasterCluster& c : plan.caster_clusters) {
    const uint32_t end = c.first_triangle + c.triangle_count;
    UploadedCluster run{{static_cast<uint32_t>(i), 0, c.mask}, glm::dvec3(kInf), glm::dvec3(-kInf)};
    for (; i < triangles.size() && triangles[i] < end; ++i) {
      for (int v = 0; v < 3; ++v) {
        const glm::dvec3 p(plan.casters.positions[plan.casters.indices[3 * triangles[i] + v]]);
        run.lo = glm::min(run.lo, p);
        run.hi = glm::max(run.hi, p);
      }
      ++run.range.triangle_count;
    }
    if (run.range.triangle_count > 0) runs.push_back(run);
  }
  return runs;
}

}  // namespace

PreparedGroup PrepareGroup(const BakePlan& plan, int group_index, const std::vector<int>& tiles) {
  PreparedGroup group;
  group.group_index = group_index;
  group.tiles = tiles;
  std::vector<std::vector<uint32_t>> triangles;
  for (int t : tiles) {
    PreparedTile prepared;
    prepared.rect = plan.tile(t);
    TileReach reach = ComputeTileReach(plan, prepared.rect);
    prepared.has_casters = !reach.triangles.empty();
    if (!reach.empty()) {
      prepared.windows = ScanWindows(plan, prepared.rect);
      prepared.blocks = ScannedBlocks(plan, reach, prepared.windows);
      if (!prepared.blocks.empty()) triangles.push_back(std::move(reach.triangles));
    }
    group.prepared.push_back(std::move(prepared));
  }
  group.triangles = UnionOfTriangles(triangles);
  group.clusters = ClusterRuns(plan, group.triangles);
  return group;
}

ShadowMapWindow GroupWindow(const BakePlan& plan, const PreparedGroup& group,
                            const glm::dvec2& sample) {
  ShadowMapWindow window;
  for (const PreparedTile& tile : group.prepared) {
    for (const BlockScan& b : tile.blocks) {
      window = UnionWindow(window, ShadowMapWindowFor(plan, b.rect, sample, b.z_begin, b.z_end));
    }
  }
  return window;
}

std::vector<DrawRange> VisibleClusters(const BakePlan& plan, const PreparedGroup& group,
                                       const glm::dvec2& sample, const ShadowMapWindow& window) {
  const bool sun = plan.geometry().projection == Projection::kOrthographic;
  const ShadowMapLattice& lattice = plan.lattice;
  std::vector<DrawRange> visible;
  for (const UploadedCluster& c : group.clusters) {
    // Only the part of the box the shadow map draws.
    double z_lo, z_hi;
    if (!DrawnDepths(plan, c.lo.z, c.hi.z, &z_lo, &z_hi)) continue;
    // The projection ((x - a) / z or x - a z) is monotone in x and in z on the box: its
    // extremes are at the corners.
    double s_lo = kInf, s_hi = -kInf, t_lo = kInf, t_hi = -kInf;
    for (int k = 0; k < 8; ++k) {
      const double x = (k & 1) ? c.hi.x : c.lo.x, y = (k & 2) ? c.hi.y : c.lo.y;
      const double z = (k & 4) ? z_hi : z_lo;
      const double s = sun ? x - sample.x * z : (x - sample.x) / z;
      const double t = sun ? y - sample.y * z : (y - sample.y) / z;
      s_lo = std::min(s_lo, s), s_hi = std::max(s_hi, s);
      t_lo = std::min(t_lo, t), t_hi = std::max(t_hi, t);
    }
    // One texel of margin each side: rounding never drops a cluster that reaches a texel.
    if (lattice.TexelS(s_hi) + 1 < window.x0 ||
        lattice.TexelS(s_lo) - 1 >= window.x0 + window.width ||
        lattice.TexelT(t_hi) + 1 < window.y0 ||
        lattice.TexelT(t_lo) - 1 >= window.y0 + window.height) {
      continue;
    }
    visible.push_back(c.range);
  }
  return visible;
}

}  // namespace pdsm
