#include "worker/bake_task.h"

#include <chrono>
#include <cmath>
#include <limits>

#include "absl/strings/str_format.h"
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

// Slope bias is scaled by the larger of a texel and a PDSM pixel: the bilinear lookup reads
// neighbouring rays, which meet a tilted receiver up to one pixel's depth change away.
double FootprintScale(const BakePlan& plan) {
  const PdsmGeometry& g = plan.geometry();
  const double pixel = std::max(g.PixelPitchS(), g.PixelPitchT());
  return std::max(1.0, pixel / plan.lattice.pitch_s);
}

}  // namespace

void TaskStats::Add(const TaskStats& o) {
  shadow_map_seconds += o.shadow_map_seconds;
  scan_seconds += o.scan_seconds;
  shadow_maps += o.shadow_maps;
  shadow_map_texels += o.shadow_map_texels;
  events += o.events;
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
  return renderer_->SetGeometry(positions, indices);
}

absl::StatusOr<TileEvents> TaskRunner::Run(const BakeTask& task, TaskStats* stats,
                                           const std::function<bool()>& cancelled) {
  const TileRect& tile = plan_.tiles.at(task.tile_index);
  TileEvents result = EmptyTileEvents(tile);
  const TileReach reach = ComputeTileReach(plan_, tile);
  if (reach.empty()) return result;  // nothing can shadow these rays: all lit, no work
  if (absl::Status s = UploadCasters(reach); !s.ok()) return s;

  const PdsmGeometry& g = plan_.geometry();
  const size_t pixels = result.PixelCount();
  std::vector<std::vector<Event>> pixel_events(pixels);
  std::vector<float> depth;
  ShadowMapCamera camera;
  camera.projection = g.projection;
  camera.lattice = plan_.lattice;
  camera.z_clip_near = plan_.z_clip_near;
  camera.z_clip_far = plan_.z_clip_far;
  camera.depth_bias = plan_.header.depth_bias;
  camera.slope_bias = plan_.header.slope_bias;
  camera.footprint_scale = FootprintScale(plan_);

  for (int k = task.sample_begin; k < task.sample_end; ++k) {
    if (cancelled && cancelled()) {
      return absl::CancelledError(absl::StrFormat("tile %d: task cancelled", tile.index));
    }
    const glm::dvec2& sample = plan_.samples.at(k);
    camera.sample = sample;
    camera.window = ShadowMapWindowFor(plan_, tile, sample, reach.z_near);
    const int64_t texels = int64_t{camera.window.width} * camera.window.height;
    if (texels > kMaxShadowMapTexels) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "tile %d, sample %d: its shadow map would need %dx%d texels (limit %d); occluders "
          "very near the light plane spread each ray over many texels: lower "
          "shadowMapResolution or tileSize",
          tile.index, k, camera.window.width, camera.window.height, kMaxShadowMapTexels));
    }
    auto render_start = std::chrono::steady_clock::now();
    if (absl::Status s = renderer_->Render(camera, &depth); !s.ok()) return s;
    stats->shadow_map_seconds += SecondsSince(render_start);
    stats->shadow_maps += 1;
    stats->shadow_map_texels += texels;

    auto scan_start = std::chrono::steady_clock::now();
    const ShadowMapView view{depth.data(), plan_.lattice, camera.window};
    for (int j = 0; j < tile.height; ++j) {
      const double t = g.PixelCenterT(tile.y0 + j);
      for (int i = 0; i < tile.width; ++i) {
        const double s = g.PixelCenterS(tile.x0 + i);
        const RayInShadowMap ray = RayForSample(plan_, s, t, sample, reach.z_near);
        ScanConvertRay(view, ray, g.projection, &pixel_events[size_t(j) * tile.width + i]);
      }
    }
    stats->scan_seconds += SecondsSince(scan_start);
  }

  auto sort_start = std::chrono::steady_clock::now();
  for (size_t p = 0; p < pixels; ++p) {
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
  if (absl::Status s = renderer_->SetGeometry(plan_.receivers.positions, plan_.receivers.indices);
      !s.ok()) {
    return s;
  }
  const PdsmGeometry& g = plan_.geometry();
  ShadowMapCamera camera;
  camera.projection = g.projection;
  camera.lattice = ShadowMapLattice{g.s_min, g.t_min, g.PixelPitchS(), g.PixelPitchT()};
  camera.window = ShadowMapWindow{tile.x0, tile.y0, tile.width, tile.height};
  // Receivers may lie nearer than any caster: clip only at the light plane.
  camera.z_clip_near = g.projection == Projection::kPerspective ? 1e-6 * g.z_far
                                                                : plan_.z_clip_near;
  camera.z_clip_far = plan_.z_clip_far;
  std::vector<float> depth;
  if (absl::Status s = renderer_->Render(camera, &depth); !s.ok()) return s;
  return depth;
}

}  // namespace pdsm
