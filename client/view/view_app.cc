#include "client/view/view_app.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "client/cli_common.h"
#include "client/view/image_io.h"
#include "client/view/job_follower.h"
#include "client/view/pdsm_source.h"
#include "client/view/shadowmask_textures.h"
#include "client/view/text_overlay.h"
#include "core/bake/bake_plan.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_lights.h"
#include "core/scene/scene_loader.h"
#include "spdlog/spdlog.h"

namespace pdsm::view {
namespace {

absl::StatusOr<DynamicObject> MakeDynamicObject(const DynamicObjectSpec& spec, size_t i) {
  DynamicObject object;
  if (spec.sphere) {
    object.mesh = MakeUnitSphere();
    const glm::dvec4& s = *spec.sphere;
    object.world_from_object = glm::dmat4(s.w);
    object.world_from_object[3] = glm::dvec4(s.x, s.y, s.z, 1.0);
    return object;
  }
  absl::StatusOr<DrawMesh> mesh = LoadObjectMesh(spec.mesh_path, absl::StrCat("--object[", i, "]"));
  if (!mesh.ok()) return mesh.status();
  object.mesh = *std::move(mesh);
  object.world_from_object = spec.world_from_object;
  return object;
}

// --job shown while it runs: plans the scene with the job's settings (the coordinator's
// planner: same scene, same settings, same plan) and, headless with --partial, takes the tiles
// finished now; a window starts with every tile pending and follows the job (RunWindow).
absl::Status StartFromPlan(const ViewOptions& options, const pdsm::v1::Job& job, ViewScene* view) {
  absl::StatusOr<BakePlan> plan = PlanBake(view->scene);
  if (!plan.ok()) return plan.status();
  if (absl::Status s = CheckPlanMatchesJob(*plan, job, options.light, options.scene_path);
      !s.ok()) {
    return s;
  }
  view->plan = std::make_shared<const BakePlan>(*std::move(plan));
  PartialPdsm partial = EmptyPartialPdsm(*view->plan);
  if (options.headless) {
    absl::StatusOr<std::unique_ptr<JobFollower>> follower =
        JobFollower::Create(options.service, options.job_id, options.light, view->plan.get());
    if (!follower.ok()) return follower.status();
    absl::StatusOr<JobSnapshot> snapshot = (*follower)->Poll();
    if (!snapshot.ok()) return snapshot.status();
    if (snapshot->pdsm) partial = *std::move(snapshot->pdsm);
    std::fprintf(stderr, "pdsm-view: job %s %s: %d/%d tiles\n", options.job_id.c_str(),
                 pdsm::v1::JobState_Name(snapshot->job.state()).c_str(), snapshot->job.tiles_done(),
                 snapshot->job.tiles_total());
  }
  view->pdsm = PdsmTiles::FromImage(std::move(partial.image), std::move(partial.pending));
  return absl::OkStatus();
}

// Prepares the scene's meshes, the shadowmask textures and the dynamic objects.
absl::StatusOr<ViewScene> FinishViewScene(const ViewOptions& options, ViewScene view);

// Without --light, a scene and file of several lights are shaded with every light at once (pdsm
// mode only: the comparison modes render one light's shadow maps). Each part of the file gets
// its own reader and a share of --cache-mib; each is checked against its light in the scene.
absl::Status LoadEveryLight(const ViewOptions& options, const Scene& scene, ViewScene* view) {
  const bool pdsm_only =
      options.mode == ViewMode::kPdsm &&
      std::all_of(options.compare.begin(), options.compare.end(),
                  [](ViewMode m) { return m == ViewMode::kPdsm; }) &&
      (options.bench_frames == 0 || !options.compare.empty());  // --bench: every mode, else
  if (!pdsm_only) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--mode, --compare, --bench: the modes but pdsm shade one light; name it with --light (",
        options.scene_path, " has ", scene.LightCount(),
        " lights; without --light pdsm mode shades with all of them)"));
  }
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(options.pdsm_path);
  if (!reader.ok()) return reader.status();
  const std::vector<PdsmHeader> headers = reader->headers();
  const std::vector<PdsmLightParts> lights = LightsOfParts(headers);
  // The scene counts a sphere's faces as the file does: one part each.
  if (headers.size() != scene.LightCount()) {
    return absl::InvalidArgumentError(absl::StrCat("--pdsm ", options.pdsm_path, ": holds ",
                                                   headers.size(), " lights and faces, ",
                                                   options.scene_path, " ", scene.LightCount()));
  }
  const int64_t cache_share = std::max<int64_t>(
      options.cache_bytes / static_cast<int64_t>(headers.size()), int64_t{1} << 20);
  for (const PdsmLightParts& light : lights) {
    for (const int part : light.parts) {
      absl::StatusOr<Scene> one = OneLight(scene, headers[part].light_name, "pdsm-view", "--light");
      if (!one.ok()) return one.status();
      if (absl::Status s = CheckPdsmMatchesScene(*one, headers[part], options.pdsm_path); !s.ok()) {
        if (!options.allow_mismatch) return s;
        spdlog::warn("{}", std::string(s.message()));
      }
      if (view->every_light.empty()) view->scene = *std::move(one);
      absl::StatusOr<PdsmReader> own =
          view->every_light.empty() ? std::move(reader) : PdsmReader::Open(options.pdsm_path);
      if (!own.ok()) return own.status();
      view->every_light.push_back(
          {PdsmTiles::FromReader(*std::move(own), part, cache_share), light.parts.back() + 1});
    }
  }
  view->pdsm = view->every_light.front().tiles;
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<ViewScene> LoadViewScene(const ViewOptions& options) {
  ViewScene view;
  pdsm::v1::Job job;
  if (!options.job_id.empty()) {
    // The job's own settings first: a submit may have overridden any of the file's.
    absl::StatusOr<pdsm::v1::Job> fetched = FetchJob(options.service, options.job_id);
    if (!fetched.ok()) return fetched.status();
    job = *std::move(fetched);
  }
  absl::StatusOr<Scene> scene = options.job_id.empty()
                                    ? LoadSceneFile(options.scene_path)
                                    : LoadJobScene(options.scene_path, job, options.light);
  if (!scene.ok()) return scene.status();
  if (options.job_id.empty() && options.light.empty() && scene->LightCount() > 1) {
    if (absl::Status s = LoadEveryLight(options, *scene, &view); !s.ok()) return s;
    return FinishViewScene(options, std::move(view));
  }
  scene = OneLight(*std::move(scene), options.light, "pdsm-view", "--light");
  if (!scene.ok()) return scene.status();
  view.scene = *std::move(scene);
  // A sphere light, named or a scene's only light, is shaded with one face (OneLight): its part.
  const std::string light =
      view.scene.light.is_sphere_face() ? view.scene.light_name : options.light;
  if (!options.job_id.empty() && (!options.headless || options.partial)) {
    // Shown while it runs: the geometry from the local plan, tiles as they finish.
    if (absl::Status s = StartFromPlan(options, job, &view); !s.ok()) return s;
  } else {
    absl::StatusOr<std::shared_ptr<PdsmTiles>> pdsm =
        options.job_id.empty()
            ? PdsmTiles::OpenFile(options.pdsm_path, light, options.cache_bytes)
            : FetchJobPdsm(options.service, options.job_id, light, options.cache_bytes);
    if (!pdsm.ok()) return pdsm.status();
    view.pdsm = *std::move(pdsm);
  }
  const std::string pdsm_name =
      options.job_id.empty() ? options.pdsm_path : absl::StrCat("job ", options.job_id);
  if (absl::Status s = CheckPdsmMatchesScene(view.scene, view.pdsm->header(), pdsm_name); !s.ok()) {
    if (!options.allow_mismatch) return s;
    spdlog::warn("{}", std::string(s.message()));
  }
  return FinishViewScene(options, std::move(view));
}

namespace {

absl::StatusOr<ViewScene> FinishViewScene(const ViewOptions& options, ViewScene view) {
  PrepareViewScene(&view);
  if (!options.shadowmask_dir.empty()) {
    std::vector<std::string> missing;
    absl::StatusOr<std::vector<ShadowmaskedMesh>> textured = LoadShadowmaskTextures(
        options.scene_path, options.shadowmask_dir, view.scene.light_name, view.frame(), &missing);
    if (!textured.ok()) return textured.status();
    view.shadowmasked = *std::move(textured);
    for (const std::string& m : missing) {
      spdlog::warn("{}: no shadowmask texture in {}: --mode shadowmask shades it with the PDSM", m,
                   options.shadowmask_dir);
    }
  }
  for (size_t i = 0; i < options.objects.size(); ++i) {
    absl::StatusOr<DynamicObject> object = MakeDynamicObject(options.objects[i], i);
    if (!object.ok()) return object.status();
    view.dynamic_objects.push_back(*std::move(object));
  }
  return view;
}

}  // namespace

namespace {

std::vector<std::string> LegendLines(const ViewScene& scene, const FrameRenderer& renderer) {
  const PdsmHeader& h = scene.pdsm->header();
  std::vector<std::string> lines = {
      absl::StrCat("SCENE ", scene.scene.name),
      absl::StrFormat("PDSM %dX%d, %d SAMPLES", h.geometry.width, h.geometry.height, h.samples)};
  switch (h.light_shape) {
    case LightShape::kRect:
      lines.push_back(absl::StrFormat("RECT LIGHT %.3g X %.3g", 2 * h.light_half_width,
                                      2 * h.light_half_height));
      break;
    case LightShape::kDisk:
      lines.push_back(absl::StrFormat("DISK LIGHT, RADIUS %.3g", h.light_radius));
      break;
    case LightShape::kSun:
      lines.push_back(absl::StrFormat("SUN, %.3g DEG ACROSS",
                                      2 * std::atan(h.tan_half_angle) * 180 / std::numbers::pi));
      break;
  }
  if (!scene.dynamic_objects.empty()) {
    lines.push_back(absl::StrCat("+ ", scene.dynamic_objects.size(), " DYNAMIC OBJECT",
                                 scene.dynamic_objects.size() > 1 ? "S" : ""));
    lines.push_back(
        renderer.dynamic_sm_samples().empty()
            ? "(RECEIVE ONLY IN PDSM)"
            : absl::StrCat("(THEIR SHADOW: ", renderer.dynamic_sm_samples().size(), " MAPS)"));
  }
  return lines;
}

// The tiles of --compare, each labelled with its mode, in rows; spare cells of the last row get
// the legend (the scene and its bake) instead of staying black.
RgbImage CompareImage(std::vector<RgbImage> tiles, const std::vector<ViewMode>& modes, int columns,
                      const std::vector<std::string>& legend) {
  const int scale = LabelScale(tiles.front().height);
  for (size_t i = 0; i < tiles.size(); ++i) {
    DrawLabel(&tiles[i], 3 * scale, 3 * scale, absl::AsciiStrToUpper(ModeName(modes[i])), scale);
  }
  const int n = static_cast<int>(tiles.size());
  columns = std::clamp(columns, 1, n);
  const int spare = (columns - n % columns) % columns;
  if (spare > 0) {
    RgbImage cell = tiles.front();
    for (size_t p = 0; p < cell.rgb.size(); p += 3) {
      cell.rgb[p] = 28, cell.rgb[p + 1] = 31, cell.rgb[p + 2] = 36;  // the viewer's background
    }
    RgbImage with_legend = cell;
    DrawText(&with_legend, 6 * scale, 6 * scale, legend, scale);
    tiles.push_back(with_legend);
    for (int i = 1; i < spare; ++i) tiles.push_back(cell);
  }
  return Composite(tiles, columns, 4);
}

}  // namespace

int CompareColumns(int tiles) {
  if (tiles <= 4) return std::max(tiles, 1);
  // 3 or 4: fewer would make tall images.
  const int spare4 = (4 - tiles % 4) % 4, spare3 = (3 - tiles % 3) % 3;
  return spare3 < spare4 ? 3 : 4;
}

absl::Status RenderScreenshot(FrameRenderer& renderer, const ViewOptions& options,
                              const ViewScene& scene, const Camera& camera) {
  const std::vector<ViewMode> modes =
      options.compare.empty() ? std::vector<ViewMode>{options.mode} : options.compare;
  std::vector<RgbImage> tiles;
  std::vector<std::string> names;
  FloatImage attenuation;
  for (ViewMode mode : modes) {
    if (absl::Status s = renderer.Render(mode, camera, options.width, options.height); !s.ok()) {
      return s;
    }
    absl::StatusOr<Frame> frame = renderer.ReadFrame();
    if (!frame.ok()) return frame.status();
    tiles.push_back({frame->width, frame->height, std::move(frame->rgb)});
    attenuation = {frame->width, frame->height, std::move(frame->attenuation)};
    names.push_back(ModeName(mode));
  }
  const int columns =
      options.compare_columns > 0 ? options.compare_columns : CompareColumns(modes.size());
  const RgbImage image = options.compare.empty() ? tiles.front()
                                                 : CompareImage(std::move(tiles), modes, columns,
                                                                LegendLines(scene, renderer));
  if (absl::Status s = WritePng(options.screenshot_path, image); !s.ok()) return s;
  if (!options.compare.empty()) {
    std::printf("compare (left to right, top to bottom, %d per row, labelled): %s\n", columns,
                absl::StrJoin(names, ",").c_str());
  }
  std::printf("wrote %s (%dx%d)\n", options.screenshot_path.c_str(), image.width, image.height);
  if (!options.attenuation_path.empty()) {  // one mode: ParseViewOptions refuses --compare
    if (absl::Status s = WritePfm(options.attenuation_path, attenuation); !s.ok()) return s;
  }
  return absl::OkStatus();
}

}  // namespace pdsm::view
