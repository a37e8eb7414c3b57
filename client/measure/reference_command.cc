// `pdsm reference SCENE.json --points PTS.csv [--samples N] [--method exact|embree|auto]
// [--weighting unweighted|emitter|irradiance --normal X,Y,Z]`: the ground-truth attenuation at
// world points, printed exactly like `pdsm query` ("x,y,z,attenuation", nan behind the light), so
// the two outputs compare line by line. The weightings (core/reference/light_weighting.h) measure
// how far pdsm's definition sits from a renderer's shadow ratio.
#include <cstdio>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "client/cli_common.h"
#include "client/commands.h"
#include "client/points_csv.h"
#include "core/reference/reference_attenuation.h"
#include "core/scene/scene_loader.h"

namespace pdsm {
namespace {

struct ReferenceFlags {
  std::string scene_path;
  std::string points_path;
  std::string method = "auto";
  int samples = kDefaultReferenceSamples;
  uint64_t seed = 1;
  std::string weighting;  // empty: the scene's bake.weighting (what its bake stores)
  std::vector<double> normal;
};

int RunReference(const ReferenceFlags& flags) {
  absl::StatusOr<ReferenceMethod> method = ParseReferenceMethod(flags.method, "--method");
  if (!method.ok()) return ReportError(method.status());
  absl::StatusOr<LightWeighting> weighting =
      flags.weighting.empty() ? LightWeighting::kUnweighted
                              : ParseLightWeighting(flags.weighting, "--weighting");
  if (!weighting.ok()) return ReportError(weighting.status());
  const bool irradiance = *weighting == LightWeighting::kIrradiance;
  if (irradiance != !flags.normal.empty()) {
    return ReportError(absl::InvalidArgumentError(
        "--normal: given exactly when --weighting is irradiance (the receiver's normal, world "
        "space, facing the light)"));
  }
  absl::StatusOr<Scene> scene = LoadSceneFile(flags.scene_path);
  if (scene.ok()) scene = OneLight(*std::move(scene), "", "pdsm reference");
  if (!scene.ok()) return ReportError(scene.status());
  // By default the definition the scene bakes, so that `pdsm query` and this compare line by
  // line.
  WeightingSpec spec{flags.weighting.empty() ? scene->bake.weighting : *weighting, glm::dvec3(0.0)};
  if (!flags.normal.empty())
    spec.normal_world = {flags.normal[0], flags.normal[1], flags.normal[2]};
  absl::StatusOr<std::vector<QueryPoint>> points = ReadPointsCsv(flags.points_path);
  if (!points.ok()) return ReportError(points.status());
  const ReferenceMethod resolved = ResolveReferenceMethod(*method, *scene);
  if (resolved == ReferenceMethod::kExact && scene->light.shape == LightShape::kSun) {
    return ReportError(absl::InvalidArgumentError(
        absl::StrFormat("--method exact: %s has a sun light; the exact method "
                        "needs a planar light "
                        "(use --method embree)",
                        flags.scene_path)));
  }
  std::vector<glm::dvec3> world;
  world.reserve(points->size());
  for (const QueryPoint& p : *points) world.push_back(p.world);
  absl::StatusOr<std::vector<double>> attenuation = ReferenceAttenuation(
      *scene, world, ReferenceOptions{resolved, flags.samples, flags.seed, spec});
  if (!attenuation.ok()) return ReportError(attenuation.status());
  if (resolved == ReferenceMethod::kEmbree) {
    std::fprintf(stderr, "reference: embree, %d samples per point (std. dev. <= %.4f)\n",
                 flags.samples, EmbreeErrorBound(flags.samples));
  } else {
    std::fprintf(stderr, "reference: exact polygon projection\n");
  }
  if (spec.kind != LightWeighting::kUnweighted) {
    std::fprintf(stderr, "reference: %s-weighted\n", LightWeightingName(spec.kind));
  }
  for (size_t i = 0; i < points->size(); ++i) PrintAttenuationLine((*points)[i], (*attenuation)[i]);
  return kExitOk;
}

}  // namespace

void RegisterReferenceCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<ReferenceFlags>();
  CLI::App* cmd = app.add_subcommand(
      "reference", "Ground-truth attenuation at world points (exact or ray-traced)");
  cmd->add_option("scene", flags->scene_path, "Scene file (JSON)")->required();
  cmd->add_option("--points", flags->points_path,
                  "Points file: one x,y,z per line (a header row x,y,z allowed; - reads stdin)")
      ->required();
  cmd->add_option("--method", flags->method,
                  "exact (rect/disk lights), embree (any light), auto: exact "
                  "for rect lights")
      ->capture_default_str();
  cmd->add_option("--samples", flags->samples, "Embree: light samples per point")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  cmd->add_option("--seed", flags->seed, "Embree: sample seed")->capture_default_str();
  cmd->add_option(
      "--weighting", flags->weighting,
      "unweighted (the share of the light's area hidden), emitter (of its solid angle), "
      "irradiance (a renderer's shadow ratio on a surface of --normal); default: the "
      "scene's bake.weighting, what its bake stores");
  cmd->add_option("--normal", flags->normal,
                  "irradiance: the receiver's normal X,Y,Z (world space, facing the light)")
      ->delimiter(',')
      ->expected(3);
  cmd->callback([flags, exit_code] { *exit_code = RunReference(*flags); });
}

}  // namespace pdsm
