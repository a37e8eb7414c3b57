// `pdsm export-image PDSM.exr (--depth Z | --surface SCENE) -o OUT.exr|png`: the PDSM as an
// ordinary image any viewer opens (client/export/attenuation_image.h): the attenuation on a
// plane at light-space depth Z, or on the scene's receivers, one pixel per PDSM pixel.
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/cli_common.h"
#include "client/commands.h"
#include "client/export/attenuation_image.h"
#include "client/view/view_scene.h"
#include "core/pdsm/pdsm_file.h"
#include "core/scene/scene_loader.h"
#include "core/util/output_path.h"

namespace pdsm {
namespace {

struct ExportFlags {
  std::string pdsm_path;
  std::optional<double> depth;
  std::string scene_path;
  std::string output_path;
  std::string light;
  bool allow_mismatch = false;
};

// "12345 of 65536 pixels (18.8%) defined".
std::string Coverage(const AttenuationImage& image) {
  size_t defined = 0;
  for (float a : image.attenuation) defined += std::isnan(a) ? 0 : 1;
  const size_t pixels = image.attenuation.size();
  return absl::StrFormat("%d of %d pixels (%.1f%%) defined", defined, pixels,
                         pixels == 0 ? 0.0 : 100.0 * defined / pixels);
}

int RunExportImage(const ExportFlags& flags) {
  if (flags.depth.has_value() == !flags.scene_path.empty()) {
    return ReportError(absl::InvalidArgumentError(
        "export-image: give either --depth Z (a plane at light-space depth Z) or --surface "
        "SCENE (the scene's receivers)"));
  }
  if (absl::Status s =
          CheckOutputPath("-o", flags.output_path, {flags.pdsm_path, flags.scene_path});
      !s.ok()) {
    return ReportError(s);
  }
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(flags.pdsm_path, flags.light);
  if (!pdsm.ok()) return ReportError(pdsm.status());

  absl::StatusOr<AttenuationImage> image;
  std::string what;
  if (flags.depth) {
    if (!std::isfinite(*flags.depth)) {
      return ReportError(absl::InvalidArgumentError(
          absl::StrCat("--depth: must be a finite light-space depth (got ", *flags.depth, ")")));
    }
    what = absl::StrFormat("attenuation on the plane at light-space depth %.9g of %s", *flags.depth,
                           flags.pdsm_path);
    image = AttenuationOnPlane(*pdsm, *flags.depth);
  } else {
    absl::StatusOr<Scene> scene = LoadSceneFile(flags.scene_path);
    if (scene.ok())
      scene = OneLight(*std::move(scene), flags.light, "pdsm export-image", "--light");
    if (!scene.ok()) return ReportError(scene.status());
    if (absl::Status s = view::CheckPdsmMatchesScene(*scene, pdsm->header, flags.pdsm_path);
        !s.ok()) {
      if (!flags.allow_mismatch) return ReportError(s);
      std::fprintf(stderr, "pdsm: warning: %s\n", std::string(s.message()).c_str());
    }
    what = absl::StrCat("attenuation on the receivers of ", flags.scene_path, " from ",
                        flags.pdsm_path);
    image = AttenuationOnReceivers(*pdsm, *scene);
  }
  if (!image.ok()) return ReportError(image.status());
  if (absl::Status s = WriteAttenuationImage(*image, what, flags.output_path); !s.ok()) {
    return ReportError(s);
  }
  std::printf("%s: %dx%d, %s (%s)\n", flags.output_path.c_str(), image->width, image->height,
              Coverage(*image).c_str(), what.c_str());
  return kExitOk;
}

}  // namespace

void RegisterExportImageCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<ExportFlags>();
  CLI::App* cmd = app.add_subcommand(
      "export-image",
      "The PDSM as an ordinary image (.exr or .png): its attenuation on the scene's receivers or "
      "on a plane, seen from the light");
  cmd->add_option("pdsm", flags->pdsm_path, "PDSM file (.exr)")->required();
  cmd->add_option("--depth", flags->depth,
                  "Light-space depth Z of the plane (world units along the light's normal)");
  cmd->add_option("--surface", flags->scene_path,
                  "Scene file (JSON) of the bake: the attenuation on its receivers");
  cmd->add_option("-o,--output", flags->output_path, "Output image: .exr (float) or .png (8-bit)")
      ->required();
  cmd->add_option("--light", flags->light, "The light of a PDSM (and scene) of several lights");
  cmd->add_flag("--allow-mismatch", flags->allow_mismatch,
                "Warn instead of failing when the PDSM was baked from another scene/light");
  cmd->callback([flags, exit_code] { *exit_code = RunExportImage(*flags); });
}

}  // namespace pdsm
