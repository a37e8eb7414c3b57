// The objects of a scene that receive baked shadows and can carry a texture of them: every node
// of every mesh file a scene's receiving meshes name, in world space, with its lightmap UVs
// (core/scene/lightmap_parts.h). What `pdsm shadowmask` writes a texture for and what
// `pdsm-view --mode shadowmask` puts those textures back on, named the same way by both.
#ifndef PDSM_CLIENT_EXPORT_RECEIVER_OBJECTS_H_
#define PDSM_CLIENT_EXPORT_RECEIVER_OBJECTS_H_

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"

namespace pdsm {

struct ReceiverObject {
  // Unique in the scene, [A-Za-z0-9_.-]+: the node's name (other characters made '_'), the
  // mesh file's stem for a node with none; repeats get "-2", "-3", ... in scene order.
  std::string name;
  std::string source;  // "meshes[0] (world.gltf), node \"ground\"", for messages
  int mesh_entry = 0;  // the scene's meshes[] entry it comes from
  int uv_set = 0;      // the UV set `uvs` is (LightmapPart::uv_set)
  std::vector<glm::dvec3> positions_world;
  std::vector<uint32_t> indices;  // 3 per triangle
  std::vector<glm::vec2> uvs;     // one per vertex, v = 0 at the image's top row
};

struct ReceiverObjects {
  std::string scene_name;               // the scene's `name`
  std::vector<ReceiverObject> objects;  // scene order: meshes[i], then the file's node order
  // Receiving meshes or nodes without UVs, which get no texture: one line each.
  std::vector<std::string> without_uvs;
};

// The receiver objects of the scene file (or world file) at `scene_path`: for each mesh entry,
// its file's parts that receive (by the role the node's extras set, core/scene/node_roles.h,
// else the entry's role), moved by the entry's transform as the bake moves them
// (LoadSceneMeshParts, core/scene/lightmap_parts.h). Inline meshes have no UVs. Errors: those
// of ParseSceneFile and of LoadSceneMeshParts, naming the file and the field.
absl::StatusOr<ReceiverObjects> LoadReceiverObjects(const std::string& scene_path);

}  // namespace pdsm

#endif  // PDSM_CLIENT_EXPORT_RECEIVER_OBJECTS_H_
