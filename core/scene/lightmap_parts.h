// The receiving objects of a mesh file as an engine sees them: one part per node that holds
// meshes, with the UV set its lightmap (a shadowmask texture, client/export/shadowmask.h) is
// laid out in. The bake itself flattens a file into one mesh (core/scene/mesh_file.h); a
// texture per object needs the objects.
#ifndef PDSM_CORE_SCENE_LIGHTMAP_PARTS_H_
#define PDSM_CORE_SCENE_LIGHTMAP_PARTS_H_

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "core/scene/scene.h"
#include "pdsm/v1/scene.pb.h"

namespace pdsm {

struct LightmapPart {
  std::string node;  // the node's name in the file ("" when it has none)
  // The role the node's extras (or an ancestor's) set (core/scene/node_roles.h); nullopt: the
  // scene entry's role.
  std::optional<MeshRole> node_role;
  // The UV set the texture is laid out in: 1 (glTF TEXCOORD_1) when every mesh of the node
  // has a second set, else 0 when every one has a first; -1 when not (then `uvs` is empty).
  int uv_set = -1;
  // The file's model space (the node's transform and its ancestors' applied, in double): the
  // same space a scene's `meshes[i].transform` moves the whole file from.
  std::vector<glm::dvec3> positions;
  std::vector<uint32_t> indices;  // 3 per triangle
  std::vector<glm::vec2> uvs;     // one per vertex; v = 0 at the image's top row (glTF's)
};

// The parts of `path`, one per node holding triangles, in depth-first node order (a node's
// meshes, e.g. a glTF mesh's primitives, are one part). Points and lines are dropped.
// `context` prefixes errors, as LoadMeshFile's: INVALID_ARGUMENT "<context>: cannot read
// \"<path>\": <reason>" for a missing or unreadable file, no triangles, a non-finite
// position or UV, or a node whose extras.role is not a role name. Thread-safe: each call uses its
// own importer.
absl::StatusOr<std::vector<LightmapPart>> LoadLightmapParts(const std::string& path,
                                                            const std::string& context);

// The parts of the file a scene's mesh entry names (`mesh` is meshes[index] of the scene file
// at `scene_path`, with a `path`), moved to world space by the entry's transform exactly as
// the bake moves its triangles (core/scene/scene_mesh.h, PlaceInWorld: the same checks, the
// same bits); `positions` are then world points. Errors: LoadLightmapParts' with the context
// "<scene_path>: meshes[index].path", and a bad transform naming "meshes[index].transform".
absl::StatusOr<std::vector<LightmapPart>> LoadSceneMeshParts(const std::string& scene_path,
                                                             int index, const pdsm::v1::Mesh& mesh);

}  // namespace pdsm

#endif  // PDSM_CORE_SCENE_LIGHTMAP_PARTS_H_
