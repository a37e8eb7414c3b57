#include "core/scene/scene_builder.h"

#include <utility>

#include "absl/strings/str_cat.h"
#include "core/scene/scene_bake.h"
#include "core/scene/scene_light.h"

namespace pdsm::internal {

SceneBuilder::SceneBuilder(std::string source, std::string base_dir,
                           std::set<std::string> overridden, const MeshAssetResolver* assets)
    : checks_(std::move(source), std::move(overridden)),
      sources_{std::move(base_dir), assets != nullptr && *assets ? assets : nullptr} {}

absl::StatusOr<Scene> SceneBuilder::Build(const pdsm::v1::Scene& message) const {
  Scene scene;
  if (message.name().size() > kMaxSceneNameBytes) {
    return checks_.Error("name", absl::StrCat("at most ", kMaxSceneNameBytes, " bytes (got ",
                                              message.name().size(), ")"));
  }
  scene.name = message.name();
  scene.source_path = checks_.source();
  // Light and bake first: they are cheap, and a typo there should not wait for a mesh load.
  absl::StatusOr<LightSpec> light = BuildLight(checks_, message.light());
  if (!light.ok()) return light.status();
  scene.light = *light;
  absl::StatusOr<BakeSettings> bake = BuildBake(checks_, message.bake(), light->shape);
  if (!bake.ok()) return bake.status();
  scene.bake = *bake;
  scene.meshes.reserve(message.meshes_size());
  for (int i = 0; i < message.meshes_size(); ++i) {
    absl::StatusOr<TriangleMesh> mesh = BuildMesh(checks_, sources_, i, message.meshes(i));
    if (!mesh.ok()) return mesh.status();
    scene.meshes.push_back(*std::move(mesh));
  }
  return scene;
}

}  // namespace pdsm::internal
