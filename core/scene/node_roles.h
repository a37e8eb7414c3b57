// Roles set per node in a mesh file (issue #16 item 1): an artist marks a node of a glTF (or
// any format whose node metadata Assimp reads: FBX user properties) as a caster or a receiver
// with a string in its extras, `"extras": {"role": "RECEIVER_ONLY"}`, the values being the scene
// JSON's `meshes[i].role` (CASTER_AND_RECEIVER, CASTER_ONLY, RECEIVER_ONLY). A node without one
// takes its parent's; a node neither it nor an ancestor marks has the role of the scene entry
// that names the file (docs/scene_format.md, "Roles per node"). Internal to core/scene.
#ifndef PDSM_CORE_SCENE_NODE_ROLES_H_
#define PDSM_CORE_SCENE_NODE_ROLES_H_

#include <optional>
#include <string>
#include <unordered_map>

#include <assimp/scene.h>

#include "absl/status/statusor.h"
#include "core/scene/scene.h"

namespace pdsm::internal {

// The node extras key that holds a role.
inline constexpr char kNodeRoleKey[] = "role";

// Every node of the scene (pointers into it: valid while it lives) to its role; nullopt for a
// node with no role of its own or inherited. Errors: INVALID_ARGUMENT "<context>: cannot read
// \"<path>\": node \"<name>\" extras.role: ..." for a value that is not a string or not one of
// the three role names.
using NodeRoles = std::unordered_map<const aiNode*, std::optional<MeshRole>>;
absl::StatusOr<NodeRoles> ReadNodeRoles(const aiScene& scene, const std::string& path,
                                        const std::string& context);

// Whether any node of the map has a role.
bool AnyNodeRole(const NodeRoles& roles);

// "CASTER_AND_RECEIVER", "CASTER_ONLY", "RECEIVER_ONLY": the names the scene JSON uses.
const char* MeshRoleName(MeshRole role);

}  // namespace pdsm::internal

#endif  // PDSM_CORE_SCENE_NODE_ROLES_H_
