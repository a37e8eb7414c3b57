#include "worker/bake_task.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include "absl/strings/str_format.h"
#include "core/bake/receiver_windows.h"
#include "core/bake/tile_reach.h"
#include "worker/scan_convert.h"

namespace pdsm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

TileEvents EmptyTileEvents(const TileRect& tile) {
  TileEvents out;
  out.tile_index = tile.index;
  out.x0 = tile.x0;
  out.y0 = tile.y0;
  out.width = tile.width;
  out.height = tile.height;
  out.offsets.assign(out.PixelCount() + 1, 0);
  return out;
}

struct BlockScan {
  TileRect rect;
  double z_begin, z_end;  // light-space depths; z_end = +infinity: to w = 0
};

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

// Scan-converts every ray of one block through one sample's shadow map.
void ScanBlock(const BakePlan& plan, const ShadowMapView& view, const BlockScan& b,
               const glm::dvec2& sample, const TileWindows* windows, const TileRect& tile,
               std::vector<std::vector<Event>>* pixel_events, TaskStats* stats) {
  const PdsmGeometry& g = plan.geometry();
  int64_t walked = 0, segments = 0;
  for (int y = b.rect.y0; y < b.rect.y0 + b.rect.height; ++y) {
    const double t = g.PixelCenterT(y);
    for (int x = b.rect.x0; x < b.rect.x0 + b.rect.width; ++x) {
      const double s = g.PixelCenterS(x);
      const size_t p = static_cast<size_t>(y - tile.y0) * tile.width + (x - tile.x0);
      std::vector<Event>* events = &(*pixel_events)[p];
      if (windows == nullptr) {
        walked +=
            ScanConvertRay(view, RayForSample(plan, s, t, sample, b.z_begin), g.projection, events);
        ++segments;
        continue;
      }
      // Surfaces only: each depth window is one closed piece of the ray.
      for (const DepthWindow& w : windows->Pixel(p)) {
        const double lo = std::max(w.lo, b.z_begin);
        const double hi = std::min(w.hi, b.z_end);
        if (!(lo < hi)) continue;
        walked += ScanConvertRay(view, RayForSample(plan, s, t, sample, lo, hi), g.projection,
                                 events, SegmentEnd::kClose);
        ++segments;
      }
    }
  }
  stats->texels_walked += walked;
  stats->ray_segments += segments;
}

}  // namespace

ShadowMapCamera BakeCamera(const BakePlan& plan) {
  ShadowMapCamera camera;
  camera.projection = plan.geometry().projection;
  camera.lattice = plan.lattice;
  camera.z_clip_near = plan.z_clip_near;
  camera.z_clip_far = plan.z_clip_far;
  camera.depth_bias = plan.header.depth_bias;
  camera.slope_bias = plan.header.slope_bias;
  // Slope bias is scaled by the larger of a texel and a PDSM pixel: the bilinear lookup reads
  // neighbouring rays, which meet a tilted receiver up to one pixel's depth change away.
  const PdsmGeometry& g = plan.geometry();
  camera.footprint_scale =
      std::max(1.0, std::max(g.PixelPitchS(), g.PixelPitchT()) / plan.lattice.pitch_s);
  return camera;
}

void TaskStats::Add(const TaskStats& o) {
  shadow_map_seconds += o.shadow_map_seconds;
  scan_seconds += o.scan_seconds;
  shadow_maps += o.shadow_maps;
  shadow_map_texels += o.shadow_map_texels;
  triangles_submitted += o.triangles_submitted;
  events += o.events;
  texels_walked += o.texels_walked;
  ray_segments += o.ray_segments;
  tiles_skipped += o.tiles_skipped;
}

absl::StatusOr<std::unique_ptr<TaskRunner>> TaskRunner::Create(const BakePlan& plan) {
  absl::StatusOr<std::unique_ptr<ShadowMapRenderer>> renderer = ShadowMapRenderer::Create();
  if (!renderer.ok()) return renderer.status();
  return std::unique_ptr<TaskRunner>(new TaskRunner(plan, std::move(*renderer)));
}

absl::Status TaskRunner::UploadCasters(const TileReach& reach) {
  // Only the triangles that can shadow this tile, re-indexed compactly.
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
  positions.reserve(reach.triangles.size() * 3);
  indices.reserve(reach.triangles.size() * 3);
  for (uint32_t tri : reach.triangles) {
    for (int k = 0; k < 3; ++k) {
      indices.push_back(static_cast<uint32_t>(positions.size()));
      positions.push_back(plan_.casters.positions[plan_.casters.indices[3 * tri + k]]);
    }
  }
  receivers_uploaded_ = false;
  return renderer_->SetGeometry(positions, indices);
}

absl::StatusOr<TileEvents> TaskRunner::Run(const BakeTask& task, TaskStats* stats,
                                           const std::function<bool()>& cancelled) {
  const TileRect& tile = plan_.tiles.at(task.tile_index);
  TileEvents result = EmptyTileEvents(tile);
  if (task.sample_begin >= task.sample_end) return result;
  // Nothing can shadow these rays: all lit, no shadow map. Counted once per tile, at the
  // batch that starts its samples.
  if (!TileHasCasters(plan_, tile)) {
    if (task.sample_begin == 0) ++stats->tiles_skipped;
    return result;
  }
  const TileReach reach = ComputeTileReach(plan_, tile);
  if (reach.empty()) return result;
  std::optional<TileWindows> windows;
  if (plan_.header.surfaces_only) windows = ComputeReceiverWindows(plan_, tile);
  const std::vector<BlockScan> blocks = ScannedBlocks(plan_, reach, windows);
  if (blocks.empty()) return result;
  if (absl::Status s = UploadCasters(reach); !s.ok()) return s;

  const PdsmGeometry& g = plan_.geometry();
  std::vector<std::vector<Event>> pixel_events(result.PixelCount());
  std::vector<float> depth;
  ShadowMapCamera camera = BakeCamera(plan_);

  for (int k = task.sample_begin; k < task.sample_end; ++k) {
    if (cancelled && cancelled()) {
      return absl::CancelledError(absl::StrFormat("tile %d: task cancelled", tile.index));
    }
    const glm::dvec2& sample = plan_.samples.at(k);
    camera.sample = sample;
    // Only the texels the blocks' clipped segments cross.
    camera.window = ShadowMapWindow{};
    for (const BlockScan& b : blocks) {
      camera.window =
          UnionWindow(camera.window, ShadowMapWindowFor(plan_, b.rect, sample, b.z_begin, b.z_end));
    }
    const int64_t texels = int64_t{camera.window.width} * camera.window.height;
    if (texels > kMaxShadowMapTexels) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "tile %d, sample %d: its shadow map would need %dx%d texels (limit %d): "
          "lower shadowMapResolution or tileSize",
          tile.index, k, camera.window.width, camera.window.height, kMaxShadowMapTexels));
    }
    auto render_start = std::chrono::steady_clock::now();
    if (absl::Status s = renderer_->Render(camera, &depth); !s.ok()) return s;
    stats->shadow_map_seconds += SecondsSince(render_start);
    stats->shadow_maps += 1;
    stats->shadow_map_texels += texels;
    stats->triangles_submitted += static_cast<int64_t>(reach.triangles.size());

    auto scan_start = std::chrono::steady_clock::now();
    const ShadowMapView view{depth.data(), plan_.lattice, camera.window};
    for (const BlockScan& b : blocks) {
      ScanBlock(plan_, view, b, sample, windows ? &*windows : nullptr, tile, &pixel_events, stats);
    }
    stats->scan_seconds += SecondsSince(scan_start);
  }

  auto sort_start = std::chrono::steady_clock::now();
  for (size_t p = 0; p < pixel_events.size(); ++p) {
    stats->events += static_cast<int64_t>(pixel_events[p].size());
    NormalizeEvents(&pixel_events[p]);
    result.events.insert(result.events.end(), pixel_events[p].begin(), pixel_events[p].end());
    result.offsets[p + 1] = result.events.size();
    std::vector<Event>().swap(pixel_events[p]);
  }
  stats->scan_seconds += SecondsSince(sort_start);
  return result;
}

absl::StatusOr<std::vector<float>> TaskRunner::ReceiverDepth(const TileRect& tile) {
  // The light-centre view of the receivers on the PDSM's own pixel grid.
  if (!receivers_uploaded_) {
    if (absl::Status s = renderer_->SetGeometry(plan_.receivers.positions, plan_.receivers.indices);
        !s.ok()) {
      return s;
    }
    receivers_uploaded_ = true;
  }
  const PdsmGeometry& g = plan_.geometry();
  ShadowMapCamera camera;
  camera.projection = g.projection;
  camera.lattice = ShadowMapLattice{g.s_min, g.t_min, g.PixelPitchS(), g.PixelPitchT()};
  camera.window = ShadowMapWindow{tile.x0, tile.y0, tile.width, tile.height};
  // Receivers may lie nearer than any caster: clip only at the light plane.
  camera.z_clip_near =
      g.projection == Projection::kPerspective ? 1e-6 * g.z_far : plan_.z_clip_near;
  camera.z_clip_far = plan_.z_clip_far;
  std::vector<float> depth;
  if (absl::Status s = renderer_->Render(camera, &depth); !s.ok()) return s;
  return depth;
}

}  // namespace pdsm
