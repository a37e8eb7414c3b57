// Reads a scene file (the JSON mapping of pdsm.v1.Scene), loads its meshes, and validates
// everything into a Scene. Every error names the file and the field, e.g.
//   "examples/plates/scene.json: meshes[1].transform[3]: must be finite (got NaN)".
#ifndef PDSM_CORE_SCENE_SCENE_LOADER_H_
#define PDSM_CORE_SCENE_SCENE_LOADER_H_

#include <functional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/scene/mesh_file.h"
#include "core/scene/scene.h"
#include "pdsm/v1/scene.pb.h"

namespace pdsm {

// Parses, applies `overrides` (set fields of the override replace the scene's bake fields;
// used for command-line flags), loads meshes (relative paths against the scene file's folder)
// and validates. A world file (IsWorldFile: .gltf, .glb, .fbx, .obj, .dae) is its own scene,
// with the lights it holds (core/scene/world_file.h); what it holds that is not baked, and a
// mesh file's materials baked otherwise than they say (BLEND: core/scene/mesh_file.h), go to
// `warnings` (null: logged as warnings). Errors: INVALID_ARGUMENT for bad input (malformed
// JSON, unknown field, missing or unreadable mesh, non-finite number, bad size, out-of-range
// parameter, a mesh given by assetSha256, which only the coordinator accepts, a world file
// with no light to bake), NOT_FOUND when the scene file itself does not exist.
absl::StatusOr<Scene> LoadSceneFile(const std::string& path,
                                    const pdsm::v1::BakeParams& overrides = {},
                                    std::vector<std::string>* warnings = nullptr);

// The parse and override steps of LoadSceneFile alone, with the same error messages
// (INVALID_ARGUMENT for malformed JSON or an unknown field, NOT_FOUND for a missing file). Loads
// no mesh and validates nothing else: `pdsm submit` reads the message with it, then turns its
// mesh paths (see ResolveMeshPath) into uploaded assets itself.
absl::StatusOr<pdsm::v1::Scene> ParseSceneFile(const std::string& path,
                                               const pdsm::v1::BakeParams& overrides = {},
                                               std::vector<std::string>* warnings = nullptr);

// `bake` with every default filled in, as a bake of a scene with that light (`sun`: a sun
// light) resolves it, written back with every field set: loading the same scene with the
// result as overrides gives the same settings in any build, whatever its defaults (depthBias
// stays unset where the plan derives it). What a job's GetJob reports, so that a viewer plans
// the job's PDSM from the scene file. Errors as LoadSceneFile's for bake fields, prefixed
// with `label`.
absl::StatusOr<pdsm::v1::BakeParams> EffectiveBakeParams(const pdsm::v1::BakeParams& bake, bool sun,
                                                         const std::string& label);

// The same for light `light` of `scene` (`light` for a one-light scene, else `lights[light]`):
// the scene's bake with that light's own bake fields laid over it, resolved for its shape.
// Meshes are not looked at. REQUIRES: light < max(1, lights_size()).
absl::StatusOr<pdsm::v1::BakeParams> EffectiveBakeParams(const pdsm::v1::Scene& scene,
                                                         const std::string& label, int light = 0);

// The file a scene's `meshes[i].path` names: an absolute `mesh_path` as is, a relative one
// against the folder of `scene_path` (the working directory for a bare file name), normalized
// lexically. What LoadSceneFile opens.
std::string ResolveMeshPath(const std::string& scene_path, const std::string& mesh_path);

// Returns the decoded mesh of an asset, or an error. `context` names the field for messages
// (e.g. "job 7: meshes[0].assetSha256"). The mesh must hold MeshFileData's invariants, as
// DecodeMeshAsset's result does; an error is passed on to the caller as it is.
using MeshAssetResolver = std::function<absl::StatusOr<MeshFileData>(const std::string& sha256,
                                                                     const std::string& context)>;

// The same from an already parsed message. `source_label` prefixes messages; `base_dir`
// resolves relative mesh paths (empty: mesh paths are refused, as on the server); `assets`
// loads `meshes[i].assetSha256` meshes (null: they are refused, as in scene files). A mesh
// from an asset gives the same Scene, bit for bit, as the mesh file it was encoded from.
absl::StatusOr<Scene> SceneFromProto(const pdsm::v1::Scene& message,
                                     const std::string& source_label, const std::string& base_dir,
                                     const MeshAssetResolver& assets = nullptr);

}  // namespace pdsm

#endif  // PDSM_CORE_SCENE_SCENE_LOADER_H_
