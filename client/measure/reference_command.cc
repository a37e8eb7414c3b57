// `pdsm reference SCENE.json --points PTS.csv [--samples N] [--method exact|embree|auto]`: the
// ground-truth attenuation at world points, printed exactly like `pdsm query` ("x,y,z,attenuation",
// nan behind the light), so the two outputs compare line by line.
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
};

int RunReference(const ReferenceFlags& flags) {
  absl::StatusOr<ReferenceMethod> method = ParseReferenceMethod(flags.method, "--method");
  if (!method.ok()) return ReportError(method.status());
  absl::StatusOr<Scene> scene = LoadSceneFile(flags.scene_path);
  if (scene.ok()) scene = OneLight(*std::move(scene), "", "pdsm reference");
  if (!scene.ok()) return ReportError(scene.status());
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
  absl::StatusOr<std::vector<double>> attenuation =
      ReferenceAttenuation(*scene, world, ReferenceOptions{resolved, flags.samples, flags.seed});
  if (!attenuation.ok()) return ReportError(attenuation.status());
  if (resolved == ReferenceMethod::kEmbree) {
    std::fprintf(stderr, "reference: embree, %d samples per point (std. dev. <= %.4f)\n",
                 flags.samples, EmbreeErrorBound(flags.samples));
  } else {
    std::fprintf(stderr, "reference: exact polygon projection\n");
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
  cmd->callback([flags, exit_code] { *exit_code = RunReference(*flags); });
}

}  // namespace pdsm
