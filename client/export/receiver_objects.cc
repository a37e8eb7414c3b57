#include "client/export/receiver_objects.h"

#include <cctype>
#include <filesystem>
#include <set>

#include "absl/strings/str_cat.h"
#include "core/scene/lightmap_parts.h"
#include "core/scene/scene_loader.h"

namespace pdsm {
namespace {

// `base` made of [A-Za-z0-9_.-] (at most 64 bytes), unique among `used`.
std::string UniqueName(const std::string& base, std::set<std::string>* used) {
  std::string clean;
  for (char c : base.substr(0, 64)) {
    clean +=
        std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-' ? c : '_';
  }
  if (clean.empty() || clean == "." || clean == "..") clean = "object";
  std::string out = clean;
  for (int k = 2; !used->insert(out).second; ++k) out = absl::StrCat(clean, "-", k);
  return out;
}

bool EntryReceives(pdsm::v1::Role role) { return role != pdsm::v1::CASTER_ONLY; }

}  // namespace

absl::StatusOr<ReceiverObjects> LoadReceiverObjects(const std::string& scene_path) {
  absl::StatusOr<pdsm::v1::Scene> scene = ParseSceneFile(scene_path);
  if (!scene.ok()) return scene.status();
  ReceiverObjects out;
  out.scene_name = scene->name();
  std::set<std::string> used;
  for (int i = 0; i < scene->meshes_size(); ++i) {
    const pdsm::v1::Mesh& mesh = scene->meshes(i);
    const std::string field = absl::StrCat("meshes[", i, "]");
    if (!mesh.has_path()) {
      if (!EntryReceives(mesh.role())) continue;
      out.without_uvs.push_back(absl::StrCat(field, " (inline: no UVs)"));
      continue;
    }
    absl::StatusOr<std::vector<LightmapPart>> parts = LoadSceneMeshParts(scene_path, i, mesh);
    if (!parts.ok()) return parts.status();
    const std::string stem = std::filesystem::path(mesh.path()).stem().string();
    for (LightmapPart& part : *parts) {
      // A node's own role (its extras, core/scene/node_roles.h) before the entry's.
      if (part.node_role.has_value() ? !Receives(*part.node_role) : !EntryReceives(mesh.role())) {
        continue;
      }
      const std::string source =
          absl::StrCat(field, " (", mesh.path(), "), node \"", part.node, "\"");
      if (part.uv_set < 0) {
        out.without_uvs.push_back(source);
        continue;
      }
      ReceiverObject object;
      object.name = UniqueName(part.node.empty() ? stem : part.node, &used);
      object.source = source;
      object.mesh_entry = i;
      object.uv_set = part.uv_set;
      object.indices = std::move(part.indices);
      object.uvs = std::move(part.uvs);
      object.positions_world = std::move(part.positions);
      out.objects.push_back(std::move(object));
    }
  }
  return out;
}

}  // namespace pdsm
