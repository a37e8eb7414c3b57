// Validates one pdsm.v1.Scene message into a Scene: the light, the bake settings and the
// meshes. Internal to core/scene (not a public API): LoadSceneFile and SceneFromProto
// (scene_loader.h) are the entry points.
#ifndef PDSM_CORE_SCENE_SCENE_BUILDER_H_
#define PDSM_CORE_SCENE_SCENE_BUILDER_H_

#include <set>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/scene/field_checker.h"
#include "core/scene/scene.h"
#include "core/scene/scene_loader.h"
#include "core/scene/scene_mesh.h"
#include "pdsm/v1/scene.pb.h"

namespace pdsm::internal {

// Every error is INVALID_ARGUMENT "SOURCE: FIELD: what (got VALUE)", FIELD spelled with the
// JSON names the user wrote (field_checker.h), except the mesh loaders' own (scene_mesh.h).
class SceneBuilder {
 public:
  // `source` prefixes messages and becomes Scene::source_path. `base_dir` resolves relative
  // mesh paths (empty: mesh files refused). `overridden` names the bake fields the overrides
  // replaced, for messages. `assets` loads assetSha256 meshes (null or empty: assets refused);
  // it must outlive the builder. `warnings` gets the mesh files' warnings (null: logged).
  SceneBuilder(std::string source, std::string base_dir, std::set<std::string> overridden,
               const MeshAssetResolver* assets = nullptr,
               std::vector<std::string>* warnings = nullptr);

  // The light and bake settings first (cheap: a typo there does not wait for a mesh load),
  // then the meshes in order. Stops at the first error.
  absl::StatusOr<Scene> Build(const pdsm::v1::Scene& message) const;

 private:
  // `light` or every entry of `lights`, each with its bake settings (the scene's `bake` with
  // the light's own fields in place of those it sets). Errors name "lights[i].field".
  absl::StatusOr<std::vector<SceneLight>> BuildLights(const pdsm::v1::Scene& message) const;

  FieldChecker checks_;
  MeshSources sources_;
};

}  // namespace pdsm::internal

#endif  // PDSM_CORE_SCENE_SCENE_BUILDER_H_
