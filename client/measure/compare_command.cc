// `pdsm compare PDSM.exr --scene SCENE -o ERROR.png [--light NAME] [--method M] [--step K]
// [--max-error E]`: where a bake's error lives (client/measure/error_map.h): |PDSM − reference|
// on the scene's receivers, seen from the light as `pdsm export-image --surface` shows them,
// as a picture with a colour scale and as mean / P95 / P99 / max over all pixels and over the
// penumbra.
#include <cstdio>
#include <filesystem>
#include <string>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/cli_common.h"
#include "client/commands.h"
#include "client/measure/error_map.h"
#include "client/view/view_scene.h"
#include "core/pdsm/pdsm_file.h"
#include "core/scene/scene_loader.h"
#include "core/util/output_path.h"

namespace pdsm {
namespace {

struct CompareFlags {
  std::string pdsm_path;
  std::string scene_path;
  std::string output_path;
  std::string light;
  std::string method = "auto";
  int samples = kDefaultReferenceSamples;
  int step = 1;
  double max_error = kDefaultErrorMapScale;
  bool allow_mismatch = false;
};

int RunCompare(const CompareFlags& flags) {
  absl::StatusOr<ReferenceMethod> method = ParseReferenceMethod(flags.method, "--method");
  if (!method.ok()) return ReportError(method.status());
  if (absl::Status s =
          CheckOutputPath("-o", flags.output_path, {flags.pdsm_path, flags.scene_path});
      !s.ok()) {
    return ReportError(s);
  }
  if (absl::AsciiStrToLower(std::filesystem::path(flags.output_path).extension().string()) !=
      ".png") {
    return ReportError(absl::InvalidArgumentError(
        absl::StrCat("-o ", flags.output_path, ": the error map is a .png image")));
  }
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(flags.pdsm_path, flags.light);
  if (!pdsm.ok()) return ReportError(pdsm.status());
  absl::StatusOr<Scene> scene = LoadSceneFile(flags.scene_path);
  if (scene.ok()) scene = OneLight(*std::move(scene), flags.light, "pdsm compare", "--light");
  if (!scene.ok()) return ReportError(scene.status());
  if (absl::Status s = view::CheckPdsmMatchesScene(*scene, pdsm->header, flags.pdsm_path);
      !s.ok()) {
    if (!flags.allow_mismatch) return ReportError(s);
    std::fprintf(stderr, "pdsm: warning: %s\n", std::string(s.message()).c_str());
  }
  absl::StatusOr<ErrorMap> map = MeasureErrorMap(
      *pdsm, *scene, ReferenceOptions{*method, flags.samples, 1, {pdsm->header.weighting}},
      flags.step);
  if (!map.ok()) return ReportError(map.status());
  const ErrorMapSummary summary = SummarizeErrorMap(*map);
  const std::string title = ErrorMapTitle(*map);
  if (absl::Status s = WriteErrorMapPng(*map, summary, flags.max_error, title, flags.output_path);
      !s.ok()) {
    return ReportError(s);
  }
  std::printf("%s: %dx%d, %s\n", flags.output_path.c_str(), map->width, map->height, title.c_str());
  std::printf("all       %s\n", FormatErrorStats(summary.all).c_str());
  std::printf("penumbra  %s\n", FormatErrorStats(summary.penumbra).c_str());
  return kExitOk;
}

}  // namespace

void RegisterCompareCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<CompareFlags>();
  CLI::App* cmd = app.add_subcommand(
      "compare",
      "Where the error lives: |PDSM - reference| on the scene's receivers as a PNG with a "
      "colour scale, and its mean, P95, P99 and max");
  cmd->add_option("pdsm", flags->pdsm_path, "PDSM file (.exr)")->required();
  cmd->add_option("--scene", flags->scene_path, "Scene file of the bake (JSON or a world file)")
      ->required();
  cmd->add_option("-o,--output", flags->output_path, "Error map (.png)")->required();
  cmd->add_option("--light", flags->light, "The light of a PDSM (and scene) of several lights");
  cmd->add_option("--method", flags->method,
                  "Reference: exact (rect/disk lights), embree (any light), auto: exact for rect "
                  "lights")
      ->capture_default_str();
  cmd->add_option("--samples", flags->samples, "Embree reference: light samples per point")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  cmd->add_option("--step", flags->step,
                  "Compare every STEP-th PDSM pixel in each direction (the reference's cost "
                  "falls by STEP^2)")
      ->check(CLI::Range(1, 1 << 16))
      ->capture_default_str();
  cmd->add_option("--max-error", flags->max_error,
                  "The error at the top of the colour scale (fixed, so that maps compare)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--allow-mismatch", flags->allow_mismatch,
                "Warn instead of failing when the PDSM was baked from another scene/light");
  cmd->callback([flags, exit_code] { *exit_code = RunCompare(*flags); });
}

}  // namespace pdsm
