#include "client/view/view_options.h"

#include <algorithm>
#include <cmath>

#include <CLI/CLI.hpp>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "core/util/output_path.h"
#include "core/util/version.h"

namespace pdsm::view {
namespace {

absl::StatusOr<std::vector<double>> ParseNumbers(const std::string& text, size_t count,
                                                 const std::string& flag) {
  absl::StatusOr<std::vector<double>> numbers = ParseFlagNumbers(text, flag);
  if (!numbers.ok()) return numbers.status();
  if (numbers->size() != count) {
    return absl::InvalidArgumentError(absl::StrCat(
        flag, ": expected ", count, " comma-separated numbers, got ", numbers->size()));
  }
  return numbers;
}

absl::StatusOr<std::vector<DynamicObjectSpec>> ParseObjects(
    const std::vector<std::string>& spheres, const std::vector<std::string>& meshes,
    const std::vector<std::string>& transforms) {
  std::vector<DynamicObjectSpec> objects;
  for (size_t i = 0; i < spheres.size(); ++i) {
    const std::string flag = absl::StrCat("--sphere[", i, "]");
    absl::StatusOr<std::vector<double>> n = ParseNumbers(spheres[i], 4, flag);
    if (!n.ok()) return n.status();
    if (!((*n)[3] > 0)) return absl::InvalidArgumentError(flag + ": radius must be > 0");
    DynamicObjectSpec spec;
    spec.sphere = glm::dvec4((*n)[0], (*n)[1], (*n)[2], (*n)[3]);
    objects.push_back(spec);
  }
  if (transforms.size() > meshes.size()) {
    return absl::InvalidArgumentError("--object-transform: more transforms than --object meshes");
  }
  for (size_t i = 0; i < meshes.size(); ++i) {
    DynamicObjectSpec spec;
    spec.mesh_path = meshes[i];
    if (i < transforms.size()) {
      absl::StatusOr<std::vector<double>> n =
          ParseNumbers(transforms[i], 16, absl::StrCat("--object-transform[", i, "]"));
      if (!n.ok()) return n.status();
      // Row-major, column vectors, as the scene file's `transform`.
      for (int row = 0; row < 4; ++row) {
        for (int col = 0; col < 4; ++col) spec.world_from_object[col][row] = (*n)[row * 4 + col];
      }
      // Normals need the inverse; a flat or affine-broken transform has none.
      const double det = glm::determinant(glm::dmat3(spec.world_from_object));
      if (!(std::abs(det) > 1e-12) || spec.world_from_object[0][3] != 0 ||
          spec.world_from_object[1][3] != 0 || spec.world_from_object[2][3] != 0 ||
          spec.world_from_object[3][3] != 1) {
        return absl::InvalidArgumentError(absl::StrCat(
            "--object-transform[", i, "]: must be affine (last row 0,0,0,1) and invertible"));
      }
    }
    objects.push_back(spec);
  }
  return objects;
}

}  // namespace

absl::StatusOr<ViewOptions> ParseViewOptions(int argc, char** argv) {
  ViewOptions o;
  std::string size = "1280x720", mode = "pdsm", compare, camera, combine = "product";
  bool no_dynamic_shadows = false;
  std::vector<std::string> spheres, meshes, transforms;
  bool no_bilinear = false;
  CLI::App app{"pdsm-view: look at a penumbra deep shadow map on the GPU (docs/viewer.md)",
               "pdsm-view"};
  app.add_option("scene", o.scene_path, "Scene file (JSON) the PDSM was baked from")->required();
  app.add_option("--pdsm", o.pdsm_path, "PDSM file (.exr)");
  AddServiceFlags(&app, &o.service, /*required=*/false);
  app.add_option("--job", o.job_id, "Job id on --server: fetch its PDSM (waits until done)");
  app.add_flag("--headless", o.headless, "Render with OSMesa, no window (needs --screenshot)");
  app.add_option("--size", size, "Image size WxH")->default_val(size);
  app.add_option("--screenshot", o.screenshot_path, "Write the image (PNG) and exit");
  app.add_option("--save-attenuation", o.attenuation_path,
                 "Also write the attenuation per pixel (PFM float32; -1 outside the PDSM, "
                 "-2 background)");
  app.add_option("--mode", mode, "pdsm | cpu | hard | pcf | pcss | vsm | multi-sm | shadowmask")
      ->default_val(mode);
  app.add_option("--shadowmask", o.shadowmask_dir,
                 "Folder of `pdsm shadowmask` textures: --mode shadowmask draws them on their "
                 "receivers (key 8)");
  app.add_option("--compare", compare, "Comma-separated modes tiled side by side");
  app.add_option("--compare-columns", o.compare_columns, "Tiles per row in --compare");
  app.add_option("--camera", camera,
                 "EX,EY,EZ,TX,TY,TZ[,FOV_DEG] (world); default frames the scene");
  app.add_flag("--no-bilinear", no_bilinear, "PDSM: nearest pixel instead of 4-pixel blend");
  app.add_option("--sm-size", o.render.sm_size, "hard/pcf/pcss/vsm map size (default: bake's)");
  app.add_option("--sm-count", o.render.sm_count, "multi-sm maps (default: bake's samples)");
  app.add_option("--multi-sm-size", o.render.multi_sm_size,
                 "multi-sm map size (default: bake's, at most 1024)");
  app.add_option("--filter-radius", o.render.filter_radius, "pcf/vsm kernel half-width, texels")
      ->default_val(o.render.filter_radius);
  app.add_option("--sphere", spheres, "Dynamic sphere X,Y,Z,R (world), repeatable");
  app.add_option("--object", meshes, "Dynamic mesh file, repeatable");
  app.add_option("--object-transform", transforms,
                 "16 numbers, row-major world_from_object of the matching --object");
  app.add_flag("--no-dynamic-shadows", no_dynamic_shadows,
               "pdsm/cpu: the dynamic objects receive the baked shadow but cast none");
  app.add_option("--dynamic-sm-count", o.render.dynamic_sm_count,
                 "pdsm/cpu: shadow maps of the dynamic objects (light samples)")
      ->default_val(o.render.dynamic_sm_count);
  app.add_option("--dynamic-sm-size", o.render.dynamic_sm_size,
                 "pdsm/cpu: texels per side of those maps")
      ->default_val(o.render.dynamic_sm_size);
  app.add_option("--dynamic-combine", combine,
                 "product | max: how baked and dynamic attenuation combine (docs/viewer.md)")
      ->default_val(combine);
  app.add_option("--frames", o.frames,
                 "Window: render N frames (with --job: after the final PDSM arrived), write "
                 "--screenshot, exit");
  app.add_option("--bench", o.bench_frames,
                 "Headless: time N frames of each mode (--compare or all)");
  int64_t gpu_budget_mib = o.render.gpu_budget_bytes >> 20, cache_mib = o.cache_bytes >> 20;
  app.add_option("--gpu-budget-mib", gpu_budget_mib,
                 "pdsm/shadowmask: GPU memory for the PDSM's resident tiles (tiles past it are "
                 "drawn hatched)")
      ->default_val(gpu_budget_mib);
  app.add_option("--cache-mib", cache_mib, "The PDSM's tiles kept in memory once read")
      ->default_val(cache_mib);
  app.add_flag("--partial", o.partial,
               "--job, headless: render the tiles finished so far instead of waiting");
  app.add_option("--light", o.light,
                 "The light to shade with, of a scene and PDSM of several (shading with every "
                 "light at once is still to come)");
  app.add_flag("--allow-mismatch", o.allow_mismatch,
               "Warn instead of failing when the PDSM was baked from another scene/light");
  app.add_flag("-v,--verbose", o.verbose, "Debug logging");
  app.set_version_flag("--version", VersionLine("pdsm-view"));
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return absl::CancelledError(app.help());
  } catch (const CLI::CallForVersion& e) {
    return absl::CancelledError(VersionLine("pdsm-view") + "\n");
  } catch (const CLI::ParseError& e) {
    return absl::InvalidArgumentError(e.what());
  }
  if (gpu_budget_mib < 1 || gpu_budget_mib > (int64_t{1} << 20) || cache_mib < 1 ||
      cache_mib > (int64_t{1} << 20)) {
    return absl::InvalidArgumentError("--gpu-budget-mib and --cache-mib in 1..1048576");
  }
  o.render.gpu_budget_bytes = gpu_budget_mib << 20;
  o.cache_bytes = cache_mib << 20;
  o.render.bilinear = !no_bilinear;
  o.render.dynamic_shadows = !no_dynamic_shadows;
  if (combine == "max") {
    o.render.dynamic_combine = DynamicCombine::kMax;
  } else if (combine == "product") {
    o.render.dynamic_combine = DynamicCombine::kProduct;
  } else {
    return absl::InvalidArgumentError(
        absl::StrCat("--dynamic-combine: expected max or product, got \"", combine, "\""));
  }
  if (o.render.dynamic_sm_count < 1 || o.render.dynamic_sm_count > 1024 ||
      o.render.dynamic_sm_size < 16 || o.render.dynamic_sm_size > 8192) {
    return absl::InvalidArgumentError(
        "--dynamic-sm-count in 1..1024, --dynamic-sm-size in 16..8192");
  }
  const std::vector<std::string> wh = absl::StrSplit(size, 'x');
  if (wh.size() != 2 || !absl::SimpleAtoi(wh[0], &o.width) || !absl::SimpleAtoi(wh[1], &o.height) ||
      o.width < 1 || o.height < 1 || o.width > 16384 || o.height > 16384) {
    return absl::InvalidArgumentError(
        absl::StrCat("--size: expected WxH (1..16384), got \"", size, "\""));
  }
  absl::StatusOr<std::vector<ViewMode>> modes = ParseModeList(mode, "--mode");
  if (!modes.ok()) return modes.status();
  if (modes->size() != 1) return absl::InvalidArgumentError("--mode: give one mode");
  o.mode = modes->front();
  if (!compare.empty()) {
    absl::StatusOr<std::vector<ViewMode>> list = ParseModeList(compare, "--compare");
    if (!list.ok()) return list.status();
    o.compare = *list;
  }
  if (!camera.empty()) {
    absl::StatusOr<Camera> c = ParseCamera(camera, "--camera");
    if (!c.ok()) return c.status();
    o.camera = *c;
  }
  absl::StatusOr<std::vector<DynamicObjectSpec>> objects =
      ParseObjects(spheres, meshes, transforms);
  if (!objects.ok()) return objects.status();
  o.objects = *objects;
  const bool shows_shadowmask =
      o.mode == ViewMode::kShadowmask ||
      std::find(o.compare.begin(), o.compare.end(), ViewMode::kShadowmask) != o.compare.end();
  if (shows_shadowmask && o.shadowmask_dir.empty()) {
    return absl::InvalidArgumentError(
        "--mode shadowmask needs --shadowmask DIR (the folder pdsm shadowmask wrote)");
  }
  if (o.pdsm_path.empty() == o.job_id.empty()) {
    return absl::InvalidArgumentError("give either --pdsm PDSM.exr or --server ADDR --job JOB");
  }
  if (!o.job_id.empty() && o.service.server.empty()) {
    return absl::InvalidArgumentError("--job needs --server ADDR (or $PDSM_SERVER)");
  }
  if (o.partial && (o.job_id.empty() || !o.headless)) {
    return absl::InvalidArgumentError(
        "--partial needs --headless and --job (a window always shows tiles as they finish)");
  }
  if (!o.headless && (!o.compare.empty() || o.bench_frames > 0 || !o.attenuation_path.empty())) {
    return absl::InvalidArgumentError("--compare, --bench and --save-attenuation need --headless");
  }
  if (!o.compare.empty() && !o.attenuation_path.empty()) {
    return absl::InvalidArgumentError("--save-attenuation: needs one mode, not --compare");
  }
  if (o.headless && o.screenshot_path.empty() && o.bench_frames == 0) {
    return absl::InvalidArgumentError("--headless needs --screenshot OUT.png (or --bench N)");
  }
  if (o.render.sm_size < 0 || o.render.sm_size > 16384 || o.render.multi_sm_size < 0 ||
      o.render.multi_sm_size > 16384 || o.render.sm_count < 0 || o.render.sm_count > 65536 ||
      o.render.filter_radius < 0 || o.render.filter_radius > 16 || o.frames < 0 ||
      o.bench_frames < 0) {
    return absl::InvalidArgumentError(
        "--sm-size/--multi-sm-size in 0..16384, --sm-count in 0..65536, --filter-radius in "
        "0..16, --frames and --bench >= 0");
  }
  // Outputs: regular files or new paths, never one of the viewer's inputs.
  std::vector<std::string> inputs = {o.scene_path, o.pdsm_path, o.service.token_file,
                                     o.service.tls_ca};
  for (const DynamicObjectSpec& object : o.objects) inputs.push_back(object.mesh_path);
  if (absl::Status s = CheckOutputPaths(
          {{"--screenshot", o.screenshot_path}, {"--save-attenuation", o.attenuation_path}},
          inputs);
      !s.ok()) {
    return s;
  }
  return o;
}

}  // namespace pdsm::view
