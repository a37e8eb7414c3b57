#include "worker/bake_task.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include "absl/strings/str_format.h"
#include "core/bake/face_samples.h"
#include "core/bake/receiver_windows.h"
#include "core/bake/tile_reach.h"
#include "core/pipeline/unreached_tile.h"
#include "worker/scan_convert.h"

namespace pdsm {
namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Depths of the shadow maps a task holds at once (16 MiB): a chunk of samples is rendered,
// then scanned; a map larger than this is a chunk of its own.
constexpr int64_t kScanMapTexels = int64_t{1} << 22;

// A rendered shadow map of the task's current chunk of samples.
struct ChunkMap {
  glm::dvec2 sample;
  int32_t key = 1;  // its events' key: 1, or SampleEventKey of its sample (sample-keyed bakes)
  std::vector<float> depth;
  std::vector<uint32_t> occupancy;  // BuildOccupancySums(depth): skips rays that meet no caster
  ShadowMapWindow window;
};

// Which block of the tile each pixel's ray belongs to (-1: none, the ray is all lit), so that
// the tile is scanned pixel by pixel in row-major order and its lists written in place.
std::vector<int> BlockOfPixel(const PreparedTile& tile) {
  std::vector<int> block_of(static_cast<size_t>(tile.rect.width) * tile.rect.height, -1);
  for (size_t b = 0; b < tile.blocks.size(); ++b) {
    const TileRect& r = tile.blocks[b].rect;
    for (int y = r.y0; y < r.y0 + r.height; ++y) {
      for (int x = r.x0; x < r.x0 + r.width; ++x) {
        block_of[static_cast<size_t>(y - tile.rect.y0) * tile.rect.width + (x - tile.rect.x0)] =
            static_cast<int>(b);
      }
    }
  }
  return block_of;
}

// The tile's event lists for the chunk's samples: each pixel's ray scan-converted through
// every map of the chunk in turn, its events normalized where they were appended. Pixel-major,
// so each pixel's events are sorted while in cache and no list is kept per pixel.
TileEvents ScanTile(const BakePlan& plan, const PreparedTile& tile,
                    const std::vector<ChunkMap>& maps, size_t map_count, TaskStats* stats) {
  const PdsmGeometry& g = plan.geometry();
  const TileRect& rect = tile.rect;
  const std::vector<int> block_of = BlockOfPixel(tile);
  const TileWindows* windows = tile.windows ? &*tile.windows : nullptr;
  const EventKeying keying = KeyingOf(plan.header);
  TileEvents out = NoShadowEvents(rect);
  std::vector<ShadowMapView> views;
  for (size_t m = 0; m < map_count; ++m) {
    views.push_back(ShadowMapView{maps[m].depth.data(), plan.lattice, maps[m].window,
                                  maps[m].occupancy.data()});
  }
  int64_t walked = 0, segments = 0, without_caster = 0;
  for (int y = rect.y0; y < rect.y0 + rect.height; ++y) {
    const double t = g.PixelCenterT(y);
    for (int x = rect.x0; x < rect.x0 + rect.width; ++x) {
      const size_t p = static_cast<size_t>(y - rect.y0) * rect.width + (x - rect.x0);
      const size_t first = out.events.size();
      if (const int b = block_of[p]; b >= 0) {
        const BlockScan& block = tile.blocks[b];
        const double s = g.PixelCenterS(x);
        for (size_t m = 0; m < map_count; ++m) {
          const glm::dvec2& sample = maps[m].sample;
          if (windows == nullptr) {
            const int64_t n =
                ScanConvertRay(views[m], RayForSample(plan, s, t, sample, block.z_begin),
                               g.projection, &out.events, SegmentEnd::kOpen, maps[m].key);
            walked += n;
            without_caster += n == 0 ? 1 : 0;
            ++segments;
            continue;
          }
          // Surfaces only: each depth window is one closed piece of the ray.
          for (const DepthWindow& w : windows->Pixel(p)) {
            const double lo = std::max(w.lo, block.z_begin);
            const double hi = std::min(w.hi, block.z_end);
            if (!(lo < hi)) continue;
            const int64_t n =
                ScanConvertRay(views[m], RayForSample(plan, s, t, sample, lo, hi), g.projection,
                               &out.events, SegmentEnd::kClose, maps[m].key);
            walked += n;
            without_caster += n == 0 ? 1 : 0;
            ++segments;
          }
        }
        stats->events += static_cast<int64_t>(out.events.size() - first);
        NormalizeEventsFrom(&out.events, first, keying);
      }
      out.offsets[p + 1] = out.events.size();
    }
  }
  stats->texels_walked += walked;
  stats->ray_segments += segments;
  stats->segments_without_caster += without_caster;
  return out;
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
  segments_without_caster += o.segments_without_caster;
  tiles_skipped += o.tiles_skipped;
}

absl::StatusOr<std::unique_ptr<TaskRunner>> TaskRunner::Create() {
  absl::StatusOr<std::unique_ptr<ShadowMapRenderer>> renderer = ShadowMapRenderer::Create();
  if (!renderer.ok()) return renderer.status();
  return std::unique_ptr<TaskRunner>(new TaskRunner(std::move(*renderer)));
}

absl::StatusOr<std::unique_ptr<TaskRunner>> TaskRunner::Create(const BakePlan& plan,
                                                               GroupCache* groups) {
  absl::StatusOr<std::unique_ptr<TaskRunner>> runner = Create();
  if (runner.ok()) (*runner)->SetPlan(plan, groups);
  return runner;
}

void TaskRunner::SetPlan(const BakePlan& plan, GroupCache* groups) {
  plan_ = &plan;
  own_groups_ = groups == nullptr ? std::make_unique<GroupCache>(plan, 1) : nullptr;
  groups_ = groups != nullptr ? groups : own_groups_.get();
  group_.reset();
  receivers_uploaded_ = false;
  masks_set_ = false;
}

void TaskRunner::LeaveThread() { renderer_->LeaveThread(); }

absl::Status TaskRunner::Prepare(const BakeTask& task) {
  if (plan_ == nullptr) return absl::FailedPreconditionError("the task runner has no plan");
  if (!receivers_uploaded_ && group_ && group_->group_index == task.group_index &&
      group_->tiles == task.tiles) {
    return absl::OkStatus();
  }
  if (task.group_index < 0 || task.group_index >= plan_->group_count()) {
    return absl::InvalidArgumentError(absl::StrFormat("tile group %d: the plan has %d groups",
                                                      task.group_index, plan_->group_count()));
  }
  const std::vector<int> of_group = plan_->group(task.group_index).tiles;
  for (int t : task.tiles) {
    if (!std::binary_search(of_group.begin(), of_group.end(), t)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("tile %d is not in tile group %d", t, task.group_index));
    }
  }
  if (!masks_set_) {  // the plan's alpha masks, once per plan (on the runner's thread: GL)
    if (absl::Status s = renderer_->SetMasks(plan_->masks); !s.ok()) return s;
    masks_set_ = true;
  }
  group_ = groups_->Get(task.group_index, task.tiles);
  // The casters any tile of the group can meet, in cluster order, re-indexed compactly with
  // their vertices still shared: llvmpipe shades a vertex once for the triangles around it
  // (its vertex cache), which is most of a shadow map's cost on a fine mesh.
  constexpr uint32_t kUnused = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> remap(plan_->casters.positions.size(), kUnused);
  std::vector<glm::vec3> positions;
  std::vector<glm::vec2> uvs;  // alpha-tested plans only
  std::vector<uint32_t> indices;
  const bool with_uvs = !plan_->casters.uvs.empty();
  indices.reserve(group_->triangles.size() * 3);
  for (uint32_t tri : group_->triangles) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = plan_->casters.indices[3 * tri + k];
      if (remap[v] == kUnused) {
        remap[v] = static_cast<uint32_t>(positions.size());
        positions.push_back(plan_->casters.positions[v]);
        if (with_uvs) uvs.push_back(plan_->casters.uvs[v]);
      }
      indices.push_back(remap[v]);
    }
  }
  receivers_uploaded_ = false;
  absl::Status uploaded = renderer_->SetGeometry(positions, indices, uvs);
  if (!uploaded.ok()) group_.reset();  // the renderer's geometry is unknown
  return uploaded;
}

absl::StatusOr<std::vector<TileEvents>> TaskRunner::Run(const BakeTask& task, TaskStats* stats,
                                                        const std::function<bool()>& cancelled) {
  if (absl::Status s = Prepare(task); !s.ok()) return s;
  std::vector<TileEvents> results;
  const PreparedGroup& group = *group_;
  for (const PreparedTile& tile : group.prepared) {
    results.push_back(NoShadowEvents(tile.rect));
    // Counted once per tile, at the batch that starts its samples.
    if (!tile.has_casters && task.sample_begin == 0) ++stats->tiles_skipped;
  }
  if (task.sample_begin >= task.sample_end || group.empty()) return results;

  // The batch's samples in chunks whose maps fit kScanMapTexels together (one map at least):
  // each chunk's maps are rendered, then every ray is scanned through all of them at once.
  ShadowMapCamera camera = BakeCamera(*plan_);
  // A sphere face's group sees the sphere's outline from its own direction.
  std::vector<glm::dvec2> face_samples;
  if (IsSphereFacePlan(*plan_)) face_samples = FaceGroupSamples(*plan_, task.group_index);
  const std::vector<glm::dvec2>& samples = face_samples.empty() ? plan_->samples : face_samples;
  std::vector<ChunkMap> maps;
  bool first_chunk = true;
  for (int k = task.sample_begin; k < task.sample_end;) {
    size_t map_count = 0;
    int64_t chunk_texels = 0;
    for (; k < task.sample_end; ++k) {
      const glm::dvec2& sample = samples.at(k);
      const ShadowMapWindow window = GroupWindow(*plan_, group, sample);
      const int64_t texels = int64_t{window.width} * window.height;
      if (texels > kMaxShadowMapTexels) {
        return absl::ResourceExhaustedError(absl::StrFormat(
            "tile group %d, sample %d: its shadow map would need %dx%d texels (limit %d): "
            "lower shadowMapResolution or tileSize",
            task.group_index, k, window.width, window.height, kMaxShadowMapTexels));
      }
      if (map_count > 0 && chunk_texels + texels > kScanMapTexels) break;
      if (cancelled && cancelled()) {
        return absl::CancelledError(
            absl::StrFormat("tile group %d: task cancelled", task.group_index));
      }
      if (maps.size() <= map_count) maps.emplace_back();
      ChunkMap& map = maps[map_count];
      map.sample = sample;
      map.key = KeyingOf(plan_->header) == EventKeying::kSampleKeys ? SampleEventKey(k) : 1;
      map.window = window;
      camera.sample = sample;
      camera.window = window;
      const std::vector<DrawRange> visible = VisibleClusters(*plan_, group, sample, window);
      auto render_start = std::chrono::steady_clock::now();
      if (absl::Status s = renderer_->Render(camera, visible, &map.depth); !s.ok()) return s;
      stats->shadow_map_seconds += SecondsSince(render_start);
      BuildOccupancySums(map.depth.data(), window.width, window.height, &map.occupancy);
      stats->shadow_maps += 1;
      stats->shadow_map_texels += texels;
      for (const DrawRange& r : visible) stats->triangles_submitted += r.triangle_count;
      chunk_texels += texels;
      ++map_count;
    }

    auto scan_start = std::chrono::steady_clock::now();
    for (size_t i = 0; i < group.prepared.size(); ++i) {
      const PreparedTile& tile = group.prepared[i];
      if (tile.blocks.empty()) continue;  // all lit: its offsets stay zero
      TileEvents chunk = ScanTile(*plan_, tile, maps, map_count, stats);
      if (first_chunk) {
        results[i] = std::move(chunk);
      } else {
        const TileEvents parts[2] = {std::move(results[i]), std::move(chunk)};
        results[i] = MergeTileEvents(parts, KeyingOf(plan_->header));
      }
    }
    stats->scan_seconds += SecondsSince(scan_start);
    first_chunk = false;
  }
  return results;
}

absl::StatusOr<std::vector<float>> TaskRunner::ReceiverDepth(const TileRect& tile) {
  if (plan_ == nullptr) return absl::FailedPreconditionError("the task runner has no plan");
  // The light-centre view of the receivers on the PDSM's own pixel grid.
  if (!receivers_uploaded_) {
    group_.reset();  // its casters are no longer uploaded
    if (absl::Status s =
            renderer_->SetGeometry(plan_->receivers.positions, plan_->receivers.indices);
        !s.ok()) {
      return s;
    }
    receivers_uploaded_ = true;
  }
  const PdsmGeometry& g = plan_->geometry();
  ShadowMapCamera camera;
  camera.projection = g.projection;
  camera.lattice = ShadowMapLattice{g.s_min, g.t_min, g.PixelPitchS(), g.PixelPitchT()};
  camera.window = ShadowMapWindow{tile.x0, tile.y0, tile.width, tile.height};
  // Receivers may lie nearer than any caster: clip only at the light plane, for the sun too
  // (its frame puts the whole scene at z > 0). The casters' clip plane here cut off the ground
  // nearest a low sun from the preview, though the PDSM holds it.
  camera.z_clip_near = g.projection == Projection::kPerspective ? 1e-6 * g.z_far : 0.0;
  camera.z_clip_far = plan_->z_clip_far;
  std::vector<float> depth;
  if (absl::Status s = renderer_->Render(camera, &depth); !s.ok()) return s;
  return depth;
}

}  // namespace pdsm
