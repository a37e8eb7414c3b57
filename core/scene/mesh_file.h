// Reads a triangle mesh from a file with Assimp (PLY, OBJ, glTF, FBX, ... anything Assimp
// imports). All meshes of the file are flattened into one, with their node transforms applied;
// polygons are triangulated; points and lines are dropped.
#ifndef PDSM_CORE_SCENE_MESH_FILE_H_
#define PDSM_CORE_SCENE_MESH_FILE_H_

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"

namespace pdsm {

struct MeshFileData {
  std::vector<glm::dvec3> positions;  // model space (the file's units), finite
  std::vector<uint32_t> indices;      // 3 per triangle, each < positions.size()
};

// Loads `path` (opened as given: the caller resolves relative paths). `context` prefixes every
// error message and names where the path came from, e.g. "scene.json: meshes[0].path".
// Errors: INVALID_ARGUMENT "<context>: cannot read \"<path>\": <reason>" when the file is
// missing, unreadable, has no triangles or a non-finite coordinate.
// Thread-safe: each call uses its own importer.
absl::StatusOr<MeshFileData> LoadMeshFile(const std::string& path, const std::string& context);

}  // namespace pdsm

#endif  // PDSM_CORE_SCENE_MESH_FILE_H_
