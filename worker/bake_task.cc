#include "worker/bake_task.h"

#include <algorithm>
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

absl::StatusOr<std::unique_ptr<TaskRunner>> TaskRunner::Create(const BakePlan& plan,
                                                               GroupCache* groups) {
  absl::StatusOr<std::unique_ptr<ShadowMapRenderer>> renderer = ShadowMapRenderer::Create();
  if (!renderer.ok()) return renderer.status();
  return std::unique_ptr<TaskRunner>(new TaskRunner(plan, std::move(*renderer), groups));
}

absl::Status TaskRunner::Prepare(const BakeTask& task) {
  if (!receivers_uploaded_ && group_ && group_->group_index == task.group_index &&
      group_->tiles == task.tiles) {
    return absl::OkStatus();
  }
  if (task.group_index < 0 || task.group_index >= static_cast<int>(plan_.groups.size())) {
    return absl::InvalidArgumentError(absl::StrFormat("tile group %d: the plan has %d groups",
                                                      task.group_index, plan_.groups.size()));
  }
  const std::vector<int>& of_group = plan_.groups[task.group_index].tiles;
  for (int t : task.tiles) {
    if (!std::binary_search(of_group.begin(), of_group.end(), t)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("tile %d is not in tile group %d", t, task.group_index));
    }
  }
  group_ = groups_->Get(task.group_index, task.tiles);
  // The casters any tile of the group can meet, in cluster order, re-indexed compactly with
  // their vertices still shared: llvmpipe shades a vertex once for the triangles around it
  // (its vertex cache), which is most of a shadow map's cost on a fine mesh.
  constexpr uint32_t kUnused = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> remap(plan_.casters.positions.size(), kUnused);
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
  indices.reserve(group_->triangles.size() * 3);
  for (uint32_t tri : group_->triangles) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = plan_.casters.indices[3 * tri + k];
      if (remap[v] == kUnused) {
        remap[v] = static_cast<uint32_t>(positions.size());
        positions.push_back(plan_.casters.positions[v]);
      }
      indices.push_back(remap[v]);
    }
  }
  receivers_uploaded_ = false;
  absl::Status uploaded = renderer_->SetGeometry(positions, indices);
  if (!uploaded.ok()) group_.reset();  // the renderer's geometry is unknown
  return uploaded;
}

absl::StatusOr<std::vector<TileEvents>> TaskRunner::Run(const BakeTask& task, TaskStats* stats,
                                                        const std::function<bool()>& cancelled) {
  if (absl::Status s = Prepare(task); !s.ok()) return s;
  std::vector<TileEvents> results;
  std::vector<std::vector<std::vector<Event>>> pixel_events;  // per tile, per pixel
  const PreparedGroup& group = *group_;
  for (const PreparedTile& tile : group.prepared) {
    results.push_back(EmptyTileEvents(tile.rect));
    pixel_events.emplace_back(tile.blocks.empty() ? 0 : results.back().PixelCount());
    // Counted once per tile, at the batch that starts its samples.
    if (!tile.has_casters && task.sample_begin == 0) ++stats->tiles_skipped;
  }
  if (task.sample_begin >= task.sample_end || group.empty()) return results;

  std::vector<float> depth;
  ShadowMapCamera camera = BakeCamera(plan_);
  for (int k = task.sample_begin; k < task.sample_end; ++k) {
    if (cancelled && cancelled()) {
      return absl::CancelledError(
          absl::StrFormat("tile group %d: task cancelled", task.group_index));
    }
    const glm::dvec2& sample = plan_.samples.at(k);
    camera.sample = sample;
    camera.window = GroupWindow(plan_, group, sample);
    const int64_t texels = int64_t{camera.window.width} * camera.window.height;
    if (texels > kMaxShadowMapTexels) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "tile group %d, sample %d: its shadow map would need %dx%d texels (limit %d): "
          "lower shadowMapResolution or tileSize",
          task.group_index, k, camera.window.width, camera.window.height, kMaxShadowMapTexels));
    }
    const std::vector<DrawRange> visible = VisibleClusters(plan_, group, sample, camera.window);
    auto render_start = std::chrono::steady_clock::now();
    if (absl::Status s = renderer_->Render(camera, visible, &depth); !s.ok()) return s;
    stats->shadow_map_seconds += SecondsSince(render_start);
    stats->shadow_maps += 1;
    stats->shadow_map_texels += texels;
    for (const DrawRange& r : visible) stats->triangles_submitted += r.triangle_count;

    auto scan_start = std::chrono::steady_clock::now();
    const ShadowMapView view{depth.data(), plan_.lattice, camera.window};
    for (size_t i = 0; i < group.prepared.size(); ++i) {
      const PreparedTile& tile = group.prepared[i];
      for (const BlockScan& b : tile.blocks) {
        ScanBlock(plan_, view, b, sample, tile.windows ? &*tile.windows : nullptr, tile.rect,
                  &pixel_events[i], stats);
      }
    }
    stats->scan_seconds += SecondsSince(scan_start);
  }

  auto sort_start = std::chrono::steady_clock::now();
  for (size_t i = 0; i < results.size(); ++i) {
    TileEvents& result = results[i];
    for (size_t p = 0; p < pixel_events[i].size(); ++p) {
      std::vector<Event>& events = pixel_events[i][p];
      stats->events += static_cast<int64_t>(events.size());
      NormalizeEvents(&events);
      result.events.insert(result.events.end(), events.begin(), events.end());
      result.offsets[p + 1] = result.events.size();
      std::vector<Event>().swap(events);
    }
    // A tile without blocks keeps its all-zero offsets.
  }
  stats->scan_seconds += SecondsSince(sort_start);
  return results;
}

absl::StatusOr<std::vector<float>> TaskRunner::ReceiverDepth(const TileRect& tile) {
  // The light-centre view of the receivers on the PDSM's own pixel grid.
  if (!receivers_uploaded_) {
    group_.reset();  // its casters are no longer uploaded
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
  // Receivers may lie nearer than any caster: clip only at the light plane, for the sun too
  // (its frame puts the whole scene at z > 0). The casters' clip plane here cut off the ground
  // nearest a low sun from the preview, though the PDSM holds it.
  camera.z_clip_near = g.projection == Projection::kPerspective ? 1e-6 * g.z_far : 0.0;
  camera.z_clip_far = plan_.z_clip_far;
  std::vector<float> depth;
  if (absl::Status s = renderer_->Render(camera, &depth); !s.ok()) return s;
  return depth;
}

}  // namespace pdsm
