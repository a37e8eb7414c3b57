// Reads a triangle mesh from a file with Assimp (PLY, OBJ, glTF, FBX, ... anything Assimp
// imports). All meshes of the file are flattened into one, with their node transforms applied;
// polygons are triangulated; points and lines are dropped.
//
// Alpha-tested materials (core/scene/alpha_mask.h; docs/scene_format.md, "Alpha-tested
// casters") keep their triangles' UVs and a mask:
//   glTF alphaMode MASK: the base-colour texture's alpha (255 where the image has none) times
//     the base-colour factor's alpha, against alphaCutoff; with no texture the factor alone
//     decides (opaque, or casting nothing);
//   glTF alphaMode BLEND: the same at cutoff 0.5, named in a warning (a deep shadow map stores
//     visibility, not partial transmittance);
//   other formats (OBJ/MTL map_d, FBX): an opacity texture (its alpha, or its gray when it has
//     no alpha) times the opacity factor, at cutoff 0.5; an opacity factor below 1 without a
//     texture is the same rule, named in a warning.
// Textures are PNG, embedded (glb, data URI) or files next to the model; sampled with
// GL_LINEAR and the texture's wrap modes (filters and KHR_texture_transform are not read).
#ifndef PDSM_CORE_SCENE_MESH_FILE_H_
#define PDSM_CORE_SCENE_MESH_FILE_H_

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "core/scene/alpha_mask.h"
#include "core/scene/scene.h"

namespace pdsm {

struct MeshFileData {
  std::vector<glm::dvec3> positions;  // model space (the file's units), finite
  std::vector<uint32_t> indices;      // 3 per triangle, each < positions.size()
  // Alpha-tested triangles: `masks` empty when every triangle is opaque, and then `uvs` and
  // `triangle_masks` are empty too. Otherwise uvs has one entry per vertex (finite) and
  // triangle_masks one per triangle: 0 opaque, k in [1, masks.size()] tested by masks[k - 1].
  std::vector<glm::vec2> uvs;
  std::vector<uint16_t> triangle_masks;
  std::vector<std::shared_ptr<const AlphaMask>> masks;  // each Valid(), at most 65535
  // What the file holds that is baked otherwise than it says (BLEND materials), one line per
  // kind, each naming the file.
  std::vector<std::string> warnings;
  // LoadMeshFileByRole: the role its nodes' extras give these triangles (core/scene/
  // node_roles.h); nullopt: no node says, the scene entry's role applies. Not encoded in mesh
  // assets: `pdsm submit` sends it as the entry's role.
  std::optional<MeshRole> node_role;

  bool has_masks() const { return !masks.empty(); }
};

// Loads `path` (opened as given: the caller resolves relative paths). `context` prefixes every
// error message and names where the path came from, e.g. "scene.json: meshes[0].path".
// Errors: INVALID_ARGUMENT "<context>: cannot read \"<path>\": <reason>" when the file is
// missing, unreadable, has no triangles or a non-finite coordinate, or an alpha-tested material
// whose texture cannot be read (not PNG, missing, over kMaxAlphaMaskSide) or whose mesh has
// no texture coordinates.
// Thread-safe: each call uses its own importer.
absl::StatusOr<MeshFileData> LoadMeshFile(const std::string& path, const std::string& context);

// The file as the bake reads a scene's mesh entry: split by the roles its nodes' extras set
// (core/scene/node_roles.h). A file no node of which has a role gives one element, node_role
// nullopt, the same bytes as LoadMeshFile. Otherwise one element per role some node holding
// polygons has, in the order: no role (the entry's), CASTER_AND_RECEIVER, CASTER_ONLY,
// RECEIVER_ONLY; each is what LoadMeshFile gives for the file with only those nodes' meshes
// (the file is imported once per element). Warnings are deduplicated into the first element.
// Errors: LoadMeshFile's, and ReadNodeRoles' for a node whose role is not a role name.
absl::StatusOr<std::vector<MeshFileData>> LoadMeshFileByRole(const std::string& path,
                                                             const std::string& context);

namespace internal {
// The mesh readers' (this one, core/scene/lightmap_parts.h) error: INVALID_ARGUMENT
// "<context>: cannot read \"<path>\": <reason>".
absl::Status CannotReadMesh(const std::string& context, const std::string& path,
                            absl::string_view reason);
// OK when `path` is a regular file; else CannotReadMesh saying what it is (Assimp reports a
// missing file as a generic open failure).
absl::Status CheckMeshFileExists(const std::string& path, const std::string& context);
}  // namespace internal

}  // namespace pdsm

#endif  // PDSM_CORE_SCENE_MESH_FILE_H_
