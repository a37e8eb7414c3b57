// `pdsm bake SCENE.json -o OUT.exr [overrides]`: a local single-node bake.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/bake_overrides.h"
#include "client/cli_common.h"
#include "client/commands.h"
#include "client/measure/target_error.h"
#include "client/progress_reporter.h"
#include "client/view/camera_view.h"
#include "client/view/pdsm_tile_pool.h"
#include "core/bake/receiver_coverage.h"
#include "core/pdsm/pdsm_file.h"
#include "core/scene/scene_loader.h"
#include "core/scene/sphere_faces.h"
#include "core/util/output_path.h"
#include "worker/local_bake.h"

namespace pdsm {
namespace {

struct BakeFlags {
  std::string scene_path;
  std::string output_path;
  std::string preview_path;
  bool no_preview = false;
  OverrideFlags overrides;
  int threads = 0, samples_per_task = 0;
  int64_t event_memory_mib = kDefaultEventMemoryBudget >> 20;
  std::optional<double> target_error;
  std::optional<double> target_volume;  // the band's height above the receivers
};

std::string HumanBytes(uint64_t bytes) {
  if (bytes >= (1u << 20)) return absl::StrFormat("%.1f MiB", bytes / 1048576.0);
  if (bytes >= 1024) return absl::StrFormat("%.1f KiB", bytes / 1024.0);
  return absl::StrFormat("%d B", bytes);
}

// The two pictures a bake ends with: the camera view (what a user wants to see: the scene
// with its soft shadows) and the map from the light (where every shadow hides behind its
// caster, but every PDSM pixel shows). "" both with --no-preview.
struct PreviewPaths {
  std::string camera, light;
};

PreviewPaths PreviewPathsOf(const BakeFlags& flags) {
  if (flags.no_preview) return {};
  namespace fs = std::filesystem;
  const fs::path camera = !flags.preview_path.empty()
                              ? fs::path(flags.preview_path)
                              : fs::path(flags.output_path).replace_extension(".png");
  return {camera.string(), fs::path(camera).replace_extension(".light.png").string()};
}

// LightsText of the baked lights: a sphere's faces, named "NAME@FACE", count as one light.
std::string BakedLightsText(const std::vector<BakeSummary>& lights) {
  size_t count = 0;
  std::string_view sphere;  // the sphere whose faces are being counted
  for (const BakeSummary& light : lights) {
    const std::string_view of = SphereOfFace(light.light_name);
    if (of.empty() || of != sphere) ++count;
    sphere = of;
  }
  return LightsText(count, lights.size());
}

void PrintSummary(const Scene& scene, const BakeFlags& flags,
                  const std::vector<PreviewPaths>& previews, const BakeSummary& s) {
  // What the file holds: one light's size, or how many lights (each on its own line below).
  const std::string what = s.lights.empty()
                               ? absl::StrFormat("%dx%d PDSM, %d samples", scene.bake.width,
                                                 scene.bake.height, scene.bake.samples)
                               : BakedLightsText(s.lights);
  std::fprintf(
      stderr,
      "baked \"%s\": %s, %d tiles (%d all lit), %lld tasks\n"
      "  time %.2fs; shadow maps %.2f thread-s (%lld maps, %.1f Mtexels), "
      "scan conversion %.2f thread-s, merge+compress %.3f thread-s\n"
      "  events %lld -> %lld merged -> %lld consolidated -> %lld vertices%s\n"
      "  scan: %lld ray segments (%lld meet no caster), %.1f Mtexels walked; "
      "%lld tiles skipped (no caster)\n",
      scene.name.c_str(), what.c_str(), s.tiles, s.tiles_all_lit, static_cast<long long>(s.tasks),
      s.seconds, s.tasks_stats.shadow_map_seconds,
      static_cast<long long>(s.tasks_stats.shadow_maps), s.tasks_stats.shadow_map_texels / 1e6,
      s.tasks_stats.scan_seconds, s.assembly.seconds, static_cast<long long>(s.tasks_stats.events),
      static_cast<long long>(s.assembly.merged_events),
      static_cast<long long>(s.assembly.consolidated_events),
      static_cast<long long>(s.assembly.vertices),
      s.spilled_bytes > 0 ? absl::StrCat("; ", HumanBytes(s.spilled_bytes),
                                         " of event lists went through a scratch file")
                                .c_str()
                          : "",
      static_cast<long long>(s.tasks_stats.ray_segments),
      static_cast<long long>(s.tasks_stats.segments_without_caster),
      s.tasks_stats.texels_walked / 1e6, static_cast<long long>(s.tasks_stats.tiles_skipped));
  // The limit of the design is one map per sample drawing every caster (bench/
  // pdsm-bench-limit): these two ratios say how far the bake is from it, in maps and triangles.
  // Several lights: the sum of each light's limit.
  double limit_triangles = static_cast<double>(s.casters) * scene.bake.samples;
  int samples = scene.bake.samples;
  if (!s.lights.empty()) {
    limit_triangles = 0;
    samples = 0;
    for (const BakeSummary& light : s.lights) {
      limit_triangles += static_cast<double>(light.casters) * light.samples;
      samples += light.samples;
    }
  }
  std::fprintf(
      stderr,
      "  shadow maps: %lld for %d samples in %d tile groups (%.2f per sample); "
      "%lld triangles submitted, %.2fx the %lld casters x samples%s\n",
      static_cast<long long>(s.tasks_stats.shadow_maps), samples, s.groups,
      static_cast<double>(s.tasks_stats.shadow_maps) / std::max(1, samples),
      static_cast<long long>(s.tasks_stats.triangles_submitted),
      limit_triangles > 0 ? s.tasks_stats.triangles_submitted / limit_triangles : 0.0,
      static_cast<long long>(s.casters),
      s.casters_left_out > 0
          ? absl::StrFormat(" (%d of them out of every tile's reach, left out)", s.casters_left_out)
                .c_str()
          : "");
  if (s.lights.empty() && scene.bake.adaptive() && s.tiles > 0) {
    std::fprintf(stderr,
                 "  adaptive sampling: tolerance %g, %.1f samples per tile on average "
                 "(first batch %d, max %d)\n",
                 scene.bake.adaptive_tolerance, static_cast<double>(s.tile_samples_total) / s.tiles,
                 scene.bake.adaptive_min_samples, scene.bake.samples);
  }
  if (const RefinementSummary& r = s.refinement; r.pixels > 0) {
    std::fprintf(stderr,
                 "  adaptive resolution: %lld pixels refined %dx, chosen in %.2fs; their level: "
                 "%lld tasks, %lld shadow maps (%.1f Mtexels), %lld triangles, %.2f thread-s "
                 "maps + %.2f scan, %lld vertices; spliced in %.2fs\n",
                 static_cast<long long>(r.pixels), r.factor, r.select_seconds,
                 static_cast<long long>(r.tasks), static_cast<long long>(r.tasks_stats.shadow_maps),
                 r.tasks_stats.shadow_map_texels / 1e6,
                 static_cast<long long>(r.tasks_stats.triangles_submitted),
                 r.tasks_stats.shadow_map_seconds, r.tasks_stats.scan_seconds,
                 static_cast<long long>(r.assembly.vertices), r.splice_seconds);
  } else if (r.lights > 0) {
    std::fprintf(stderr, "  adaptive resolution: no pixel needed refining\n");
  }
  for (const BakeSummary& light : s.lights) {
    std::fprintf(stderr,
                 "  light \"%s\": %dx%d, %d samples, %d tiles (%d all lit), %lld tasks, %.2fs; "
                 "%lld shadow maps, %lld vertices\n",
                 light.light_name.c_str(), light.width, light.height, light.samples, light.tiles,
                 light.tiles_all_lit, static_cast<long long>(light.tasks), light.seconds,
                 static_cast<long long>(light.tasks_stats.shadow_maps),
                 static_cast<long long>(light.assembly.vertices));
  }
  std::printf("pdsm: %s (%s%s)\n", flags.output_path.c_str(), HumanBytes(s.file_bytes).c_str(),
              s.lights.empty() ? "" : absl::StrCat(", ", BakedLightsText(s.lights)).c_str());
  for (const PreviewPaths& light : previews) {
    if (!light.camera.empty()) {
      std::printf("preview: %s (camera view, the baked soft shadows)\n", light.camera.c_str());
    }
    if (!light.light.empty()) {
      std::printf("light view: %s (the map seen from the light)\n", light.light.c_str());
    }
  }
}

// Receivers the light's frustum does not hold get no shadow from the bake (query: nan): say how
// much, and what to do, rather than bake silently. Under 0.1% is rounding at the window's edge.
void WarnAboutUncoveredReceivers(const Scene& scene, const PdsmHeader& header) {
  // A light whose reach is bounded on purpose lights only that: a spot's cone, an explicit
  // bake.frustum (a world's local lights: otherwise each of them warned that ~100% of the
  // world's ground was outside it; bench/large_world.py).
  // A sphere's face: the sphere's other faces hold the rest.
  if (scene.light.is_spot() || scene.light.is_sphere_face() || scene.bake.frustum.has_value()) {
    return;
  }
  const double outside = ReceiverAreaOutsideFrustum(scene, header.geometry);
  if (outside < 1e-3) return;
  const std::string light =
      scene.light_name.empty() ? "the light's" : absl::StrCat("light \"", scene.light_name, "\"'s");
  std::fprintf(stderr,
               "pdsm: warning: %.1f%% of the receivers' area is outside %s frustum "
               "(behind the light, or more than 85 degrees off its axis): it gets no baked "
               "shadow and `pdsm query` gives nan there; move the light back or away from the "
               "receivers, aim it at them, use a sun light for wide ground, or bound its reach "
               "with bake.frustum if that is all it should light\n",
               100 * outside, light.c_str());
}

// The camera view of light `part` of the PDSM just written, read back (`reader`: the file, or
// why it could not be opened) so that the picture shows what the file holds; `*written` says
// whether it was. Its tiles stream as in pdsm-view: a map of any size is drawn within the
// viewer's default GPU budget, the tiles past it hatched (a warning counts them). A GL that
// cannot hold even the page table leaves the PDSM complete all the same: a warning, not an
// error. Other failures are errors saying the PDSM was written.
absl::Status WriteBakeCameraView(const Scene& scene, const BakeFlags& flags,
                                 const PreviewPaths& previews, absl::StatusOr<PdsmReader>& reader,
                                 int part, bool* written) {
  *written = false;
  if (previews.camera.empty()) return absl::OkStatus();
  // A reader of its own: the tiles' cache keeps it while the other lights use `reader`. One
  // frame reads each tile once into the GPU's pool: a small cache is enough.
  constexpr int64_t kCameraViewCacheBytes = int64_t{32} << 20;
  absl::StatusOr<PdsmReader> own =
      reader.ok() ? PdsmReader::Open(reader->path()) : absl::StatusOr<PdsmReader>(reader.status());
  absl::Status s = own.status();
  view::TilePoolStats pool;
  if (s.ok()) {
    s = view::WriteCameraView(
        scene, view::PdsmTiles::FromReader(*std::move(own), part, kCameraViewCacheBytes),
        previews.camera, {}, nullptr, &pool);
  }
  if (s.ok() && pool.missing_tiles > 0) {
    std::fprintf(stderr,
                 "pdsm: warning: camera view %s: %d of the %d tiles it reads did not fit the "
                 "GPU's %.0f MiB for them (drawn hatched; a closer camera in pdsm-view reads "
                 "fewer)\n",
                 previews.camera.c_str(), pool.missing_tiles, pool.requested_tiles,
                 pool.budget_bytes / 1048576.0);
  }
  if (absl::IsResourceExhausted(s)) {
    std::fprintf(stderr, "pdsm: warning: no camera view %s: %s; the PDSM is complete\n",
                 previews.camera.c_str(), std::string(s.message()).c_str());
    return absl::OkStatus();
  }
  if (!s.ok()) {
    return absl::Status(
        s.code(), absl::StrCat(flags.output_path, " was written, but not its camera view ",
                               previews.camera, ": ", s.message(), " (--no-preview skips it)"));
  }
  *written = true;
  return absl::OkStatus();
}

// --target-error E: the knobs given on the command line stay fixed, the others are chosen.
int RunTargetErrorBake(const BakeFlags& flags, const pdsm::v1::BakeParams& overrides) {
  // The chooser's child bakes take only the knobs below: refuse the others rather than drop them.
  const std::vector<std::pair<bool, const char*>> unsupported = {
      {overrides.has_tile_size(), "--tile-size"},
      {overrides.has_adaptive_tolerance(), "--adaptive-tolerance"},
      {overrides.has_adaptive_min_samples(), "--adaptive-min-samples"},
      {overrides.surfaces_only(), "--surfaces-only"},
      // The scene file's bake.weighting is measured and kept; the flag would not reach the
      // chooser's bakes.
      {overrides.weighting() != pdsm::v1::WEIGHTING_DEFAULT, "--weighting"},
      {flags.samples_per_task != 0, "--samples-per-task"},
      {!flags.preview_path.empty(), "--preview"}};
  for (const auto& [given, flag] : unsupported) {
    if (given) {
      return ReportError(absl::InvalidArgumentError(
          absl::StrCat(flag, ": cannot be combined with --target-error")));
    }
  }
  TargetErrorOptions options;
  if (flags.target_volume) options.band_height = *flags.target_volume;
  options.scene_path = flags.scene_path;
  options.output_path = flags.output_path;
  options.target = *flags.target_error;
  options.threads = flags.threads;
  if (overrides.has_samples()) options.samples = overrides.samples();
  if (overrides.has_shadow_map_resolution()) {
    options.sm_resolution = overrides.shadow_map_resolution();
  }
  if (overrides.resolution_size() == 2) {
    options.resolution = {overrides.resolution(0), overrides.resolution(1)};
  }
  if (overrides.has_epsilon()) options.epsilon = overrides.epsilon();
  if (overrides.has_depth_bias()) options.depth_bias = overrides.depth_bias();
  options.sampling = flags.overrides.sampling;
  absl::StatusOr<TargetErrorResult> r = BakeToTargetError(options);
  if (!r.ok()) return ReportError(r.status());
  std::fprintf(stderr,
               "target-error %g: chose samples %d, resolution %dx%d, sm-resolution %d, "
               "epsilon %g, sampling %s; mean error on held-out points %.5f (receivers %.5f, "
               "band of %.4g %.5f; penumbra only %.5f on %zu points; on the fitted points "
               "%.5f, predicted %.5f): %s; bake %.2fs, %d bakes in all %.1fs\n",
               options.target, r->knobs.samples, r->knobs.width, r->knobs.height,
               r->knobs.sm_resolution, r->knobs.epsilon, r->knobs.sampling.c_str(),
               r->held_out.all.mean, r->held_out.surface.mean, r->band_height,
               r->held_out.band.mean, r->held_out.penumbra.mean, r->held_out.penumbra.count,
               r->measured.all.mean, r->predicted, r->met ? "met" : "NOT met", r->seconds, r->bakes,
               r->total_seconds);
  std::printf("pdsm: %s\n", flags.output_path.c_str());
  if (!r->met) {
    std::fprintf(stderr,
                 "pdsm: target error %g not reached after %d rebakes; %s holds the last "
                 "(costliest) bake tried\n",
                 options.target, kMaxRebakes, flags.output_path.c_str());
    return kExitFailure;
  }
  return kExitOk;
}

int RunBake(const BakeFlags& flags) {
  // Before any work: -o is a regular file or a new path, and not the scene it bakes.
  if (absl::Status s = CheckOutputPath("-o", flags.output_path, {flags.scene_path}); !s.ok()) {
    return ReportError(s);
  }
  absl::StatusOr<pdsm::v1::BakeParams> overrides = ToBakeParams(flags.overrides);
  if (!overrides.ok()) return ReportError(overrides.status());
  if (flags.target_volume && !flags.target_error) {
    return ReportError(absl::InvalidArgumentError(
        "--target-volume: says where --target-error is measured; give --target-error too"));
  }
  if (flags.target_error) return RunTargetErrorBake(flags, *overrides);
  std::vector<std::string> warnings;  // a world file's lights that are not baked
  absl::StatusOr<Scene> scene = LoadSceneFile(flags.scene_path, *overrides, &warnings);
  if (!scene.ok()) return ReportError(scene.status());
  for (const std::string& w : warnings) std::fprintf(stderr, "pdsm: warning: %s\n", w.c_str());

  LocalBakeOptions options;
  options.output_path = flags.output_path;
  const PreviewPaths previews = PreviewPathsOf(flags);
  options.preview_path = previews.light;
  OutputPaths outputs = {{"-o", flags.output_path},
                         {"--preview", previews.camera},
                         {"--preview (its .light.png)", previews.light}};
  if (scene->LightCount() > 1) {
    outputs.resize(1);  // the pictures are each light's
    for (size_t i = 0; i < scene->LightCount(); ++i) {
      const std::string name = LightOf(*scene, i).name;
      outputs.push_back(
          {absl::StrCat("--preview (light ", name, ")"), LightPreviewPath(previews.camera, name)});
      outputs.push_back({absl::StrCat("--preview (light ", name, ", its .light.png)"),
                         LightPreviewPath(previews.light, name)});
    }
  }
  if (absl::Status s = CheckOutputPaths(outputs, {flags.scene_path}); !s.ok()) {
    return ReportError(s);
  }
  options.threads = flags.threads;
  options.samples_per_task = flags.samples_per_task;
  options.event_memory_budget_bytes = flags.event_memory_mib << 20;
  ProgressReporter progress("bake " + scene->name);
  options.on_progress = [&progress](const BakeProgress& p) {
    progress.Update(p.tasks_done, p.tasks_total, p.seconds);
  };
  absl::StatusOr<BakeSummary> summary = RunLocalBake(*scene, options);
  progress.Finish();
  if (!summary.ok()) return ReportError(summary.status());
  // A scene of several lights: the pictures of each light, its name before the extension
  // (OUT.sun.png, OUT.light.sun.png). One picture shading every light is pdsm-view's to come.
  // The file is opened once (its framing scanned once) for every light's warning and picture.
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(flags.output_path);
  std::vector<PreviewPaths> written;
  for (size_t i = 0; i < scene->LightCount(); ++i) {
    Scene one_light;  // a scene of several lights: light i's (ForLight copies the meshes)
    if (scene->LightCount() > 1) one_light = ForLight(*scene, i);
    const Scene& light = scene->LightCount() > 1 ? one_light : *scene;
    PreviewPaths paths = previews;
    if (scene->LightCount() > 1) {
      paths = {LightPreviewPath(previews.camera, light.light_name),
               LightPreviewPath(previews.light, light.light_name)};
    }
    // The file's parts are the scene's lights in order.
    if (reader.ok() && static_cast<size_t>(reader->light_count()) == scene->LightCount()) {
      WarnAboutUncoveredReceivers(light, reader->headers()[i]);
    }
    bool camera_written = false;
    if (absl::Status s =
            WriteBakeCameraView(light, flags, paths, reader, static_cast<int>(i), &camera_written);
        !s.ok()) {
      return ReportError(s);
    }
    if (!camera_written) paths.camera.clear();
    written.push_back(paths);
  }
  PrintSummary(*scene, flags, written, *summary);
  return kExitOk;
}

}  // namespace

void RegisterBakeCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<BakeFlags>();
  CLI::App* cmd = app.add_subcommand("bake", "Bake a PDSM locally (no server needed)");
  cmd->add_option("scene", flags->scene_path,
                  "Scene file (JSON), or a world file (.gltf .glb .fbx .obj .dae) with its lights")
      ->required();
  cmd->add_option("-o,--output", flags->output_path, "Output PDSM (.exr)")->required();
  AddOverrideFlags(cmd, &flags->overrides);
  cmd->add_option("--threads", flags->threads, "Worker threads (default: one per core)")
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--samples-per-task", flags->samples_per_task,
                  "Light samples per task (default: all); does not change the result")
      ->check(CLI::Range(1, 1 << 20));
  cmd->add_option("--event-memory-mib", flags->event_memory_mib,
                  "Event lists kept in memory before they move to a scratch file beside OUT "
                  "(default 8); memory stays flat in the samples, the result does not change")
      ->check(CLI::Range(1, 1 << 20));
  cmd->add_option("--preview", flags->preview_path,
                  "Camera view PNG (default: OUT with .png); the map from the light goes beside "
                  "it, with .light.png");
  cmd->add_flag("--no-preview", flags->no_preview, "Write neither picture");
  cmd->add_option("--target-error", flags->target_error,
                  "Choose the knobs not given to reach this mean attenuation error, on the "
                  "receivers and in the band above them, at least cost (pilot bakes against "
                  "the reference; writes no preview)")
      ->check(CLI::Range(1e-6, 1.0));
  cmd->add_option("--target-volume", flags->target_volume,
                  "With --target-error: the height of the band above the receivers where it is "
                  "measured, world units (default: half the depth range between the casters "
                  "and the farthest receiver)")
      ->check(CLI::PositiveNumber);
  cmd->callback([flags, exit_code] { *exit_code = RunBake(*flags); });
}

}  // namespace pdsm
