// Headless runs: OSMesa (llvmpipe) context, one screenshot or a benchmark table.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/view/view_app.h"
#include "gl/gl_functions.h"
#include "gl/platform/osmesa_context.h"
#include "spdlog/spdlog.h"

namespace pdsm::view {
namespace {

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values.empty() ? 0 : values[values.size() / 2];
}

// The PDSM tile pool: what streaming cost and held.
std::string TilePoolLine(const TilePoolStats& s) {
  return absl::StrFormat(
      "PDSM tiles on the GPU: %d resident (%.2f MiB of a %.2f MiB pool, limit %.2f MiB), %d "
      "empty, page table %.2f MiB; %d uploaded, %d evicted, %d compactions, %.1f ms; the last "
      "view read %d tiles, %d over the budget",
      s.resident_tiles, s.used_bytes / 1048576.0, s.capacity_bytes / 1048576.0,
      s.budget_bytes / 1048576.0, s.empty_tiles, s.page_table_bytes / 1048576.0, s.tiles_uploaded,
      s.tiles_evicted, s.compactions, 1e3 * s.upload_seconds, s.requested_tiles, s.missing_tiles);
}

// Times each mode: `frames` renders after one warm-up, shadow maps re-rendered every frame
// (what a moving object costs them) and timed apart from the camera pass.
absl::Status RunBenchmark(FrameRenderer& renderer, const ViewOptions& options,
                          const Camera& camera) {
  const std::vector<ViewMode> modes =
      options.compare.empty() ? std::vector<ViewMode>(std::begin(kAllModes), std::end(kAllModes))
                              : options.compare;
  std::printf("size %dx%d, %d frames per mode (median ms)\n", options.width, options.height,
              options.bench_frames);
  std::printf(
      "| mode | frame ms (static light) | shadow maps ms (per update) | cpu eval ms | PDSM tiles "
      "ms (per view change) |\n");
  std::printf("|---|---:|---:|---:|---:|\n");
  for (ViewMode mode : modes) {
    if (absl::Status s = renderer.Render(mode, camera, options.width, options.height); !s.ok()) {
      return s;
    }
    std::vector<double> frame, maps, cpu, tiles;
    for (int i = 0; i < options.bench_frames; ++i) {
      renderer.InvalidateShadowMaps();
      if (absl::Status s = renderer.Render(mode, camera, options.width, options.height); !s.ok()) {
        return s;
      }
      const FrameTimings& t = renderer.last_timings();
      frame.push_back(1e3 * (t.shade_seconds + t.cpu_seconds));
      maps.push_back(1e3 * t.shadow_map_seconds);
      cpu.push_back(1e3 * t.cpu_seconds);
      tiles.push_back(1e3 * t.stream_seconds);  // the feedback pass: every frame, as if moved
    }
    std::printf("| %s | %.1f | %.1f | %.1f | %.1f |\n", ModeName(mode), Median(frame), Median(maps),
                Median(cpu), Median(tiles));
  }
  std::printf("shadow-map memory: %.2f MiB (multi-sm: %zu maps)\n",
              renderer.shadow_map_bytes() / 1048576.0, renderer.multi_sm_samples().size());
  std::printf("%s\n", TilePoolLine(renderer.pdsm_pool_stats()).c_str());
  return absl::OkStatus();
}

}  // namespace

absl::Status RunHeadless(const ViewOptions& options, const ViewScene& scene) {
  absl::StatusOr<gl::OsMesaContext> context = gl::OsMesaContext::Create();
  if (!context.ok()) return context.status();
  absl::StatusOr<gl::GlFunctions> gl = gl::GlFunctions::Load(&gl::OsMesaContext::GetProcAddress);
  if (!gl.ok()) return gl.status();
  absl::Status status;
  {
    // The renderer's GL objects go before the context (this block).
    absl::StatusOr<std::unique_ptr<FrameRenderer>> renderer =
        FrameRenderer::Create(*gl, &scene, options.render);
    if (!renderer.ok()) return renderer.status();
    const Camera camera =
        options.camera ? *options.camera
                       : DefaultCamera(scene, static_cast<double>(options.width) / options.height);
    if (!options.screenshot_path.empty()) {
      status = RenderScreenshot(**renderer, options, scene, camera);
      const TilePoolStats& pool = (*renderer)->pdsm_pool_stats();
      spdlog::debug("{}", TilePoolLine(pool));
      if (status.ok() && pool.missing_tiles > 0) {
        spdlog::warn(
            "{} of the {} PDSM tiles this view reads did not fit --gpu-budget-mib {} "
            "(drawn hatched, attenuation -4)",
            pool.missing_tiles, pool.requested_tiles, options.render.gpu_budget_bytes >> 20);
      }
    }
    if (status.ok() && options.bench_frames > 0) {
      status = RunBenchmark(**renderer, options, camera);
    }
  }
  return status;
}

}  // namespace pdsm::view
