#include "core/scene/node_roles.h"

#include <string>

#include "absl/strings/str_cat.h"
#include "core/scene/mesh_file.h"

namespace pdsm::internal {
namespace {

constexpr MeshRole kRoles[] = {MeshRole::kCasterAndReceiver, MeshRole::kCasterOnly,
                               MeshRole::kReceiverOnly};

// The node's own role; nullopt when its metadata has no role key.
absl::StatusOr<std::optional<MeshRole>> OwnRole(const aiNode& node) {
  if (node.mMetaData == nullptr) return std::nullopt;
  const aiMetadata& meta = *node.mMetaData;
  for (unsigned i = 0; i < meta.mNumProperties; ++i) {
    if (std::string(meta.mKeys[i].C_Str()) != kNodeRoleKey) continue;
    if (meta.mValues[i].mType != AI_AISTRING) {
      return absl::InvalidArgumentError("must be a string");
    }
    const std::string value = static_cast<const aiString*>(meta.mValues[i].mData)->C_Str();
    for (MeshRole role : kRoles) {
      if (value == MeshRoleName(role)) return role;
    }
    return absl::InvalidArgumentError(absl::StrCat(
        "must be CASTER_AND_RECEIVER, CASTER_ONLY or RECEIVER_ONLY (got \"", value, "\")"));
  }
  return std::nullopt;
}

absl::Status Visit(const aiNode& node, std::optional<MeshRole> inherited, const std::string& path,
                   const std::string& context, NodeRoles* roles) {
  absl::StatusOr<std::optional<MeshRole>> own = OwnRole(node);
  if (!own.ok()) {
    return CannotReadMesh(context, path,
                          absl::StrCat("node \"", node.mName.C_Str(), "\" extras.", kNodeRoleKey,
                                       ": ", own.status().message()));
  }
  const std::optional<MeshRole> role = own->has_value() ? *own : inherited;
  (*roles)[&node] = role;
  for (unsigned c = 0; c < node.mNumChildren; ++c) {
    if (absl::Status s = Visit(*node.mChildren[c], role, path, context, roles); !s.ok()) return s;
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<NodeRoles> ReadNodeRoles(const aiScene& scene, const std::string& path,
                                        const std::string& context) {
  NodeRoles roles;
  if (scene.mRootNode == nullptr) return roles;
  if (absl::Status s = Visit(*scene.mRootNode, std::nullopt, path, context, &roles); !s.ok()) {
    return s;
  }
  return roles;
}

bool AnyNodeRole(const NodeRoles& roles) {
  for (const auto& [node, role] : roles) {
    if (role.has_value()) return true;
  }
  return false;
}

const char* MeshRoleName(MeshRole role) {
  switch (role) {
    case MeshRole::kCasterAndReceiver:
      return "CASTER_AND_RECEIVER";
    case MeshRole::kCasterOnly:
      return "CASTER_ONLY";
    case MeshRole::kReceiverOnly:
      return "RECEIVER_ONLY";
  }
  return "?";
}

}  // namespace pdsm::internal
