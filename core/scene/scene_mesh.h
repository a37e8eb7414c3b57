// One mesh of a scene message, loaded (inline, from a file or from an uploaded asset),
// transformed to world space and validated into a TriangleMesh. Internal to core/scene (not a
// public API); see scene_loader.h for that.
#ifndef PDSM_CORE_SCENE_SCENE_MESH_H_
#define PDSM_CORE_SCENE_SCENE_MESH_H_

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "core/scene/field_checker.h"
#include "core/scene/scene.h"
#include "core/scene/scene_loader.h"
#include "pdsm/v1/scene.pb.h"

namespace pdsm::internal {

// Where BuildMesh may read mesh data from, besides the message itself.
struct MeshSources {
  std::string base_dir;                       // resolves relative paths; empty: files refused
  const MeshAssetResolver* assets = nullptr;  // loads assetSha256 meshes; null: assets refused
  // Gets what a mesh file holds that is baked otherwise than it says (mesh_file.h); null:
  // logged as warnings.
  std::vector<std::string>* warnings = nullptr;
};

// `path` as is when absolute, else against `base_dir`, normalized lexically.
std::string ResolveAgainst(const std::string& base_dir, const std::string& path);

// Model positions moved to world space by a mesh entry's `transform` (row-major, 0 or 16
// numbers): checked (finite, last row 0 0 0 1, invertible 3x3) and applied in double in one
// fixed order of operations, so that every caller (BuildMesh, lightmap_parts.h) gets the same
// bits. Errors (from `checks`, naming `field`): a malformed transform, or one that moves a
// vertex out of the finite range.
absl::StatusOr<std::vector<glm::dvec3>> PlaceInWorld(const FieldChecker& checks,
                                                     absl::string_view field,
                                                     const RepeatedDoubles& transform,
                                                     const std::vector<glm::dvec3>& model);

// meshes[index] of a scene: one TriangleMesh, or for a file whose nodes set roles
// (core/scene/node_roles.h) one per role in LoadMeshFileByRole's order, each with its role
// (the entry's for nodes that set none) and `entry` = index. World positions are computed in double
// in a fixed order of operations, so every build gives the same bits. Errors (from `checks`, fields
// under "meshes[index]."): an unknown role, no source, a malformed transform (not 0 or 16 finite
// numbers, a projective last row, a singular 3x3 part), a transform that moves a vertex out of
// the finite range, bad inline data, a source `sources` refuses, and the errors of
// LoadMeshFile and of the asset resolver as they are.
absl::StatusOr<std::vector<TriangleMesh>> BuildMesh(const FieldChecker& checks,
                                                    const MeshSources& sources, int index,
                                                    const pdsm::v1::Mesh& mesh);

}  // namespace pdsm::internal

#endif  // PDSM_CORE_SCENE_SCENE_MESH_H_
