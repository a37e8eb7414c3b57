#include "client/view/shadowmask_textures.h"

#include <algorithm>
#include <filesystem>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "client/export/receiver_objects.h"
#include "client/export/shadowmask.h"

namespace pdsm::view {
namespace {

// The object's triangles in light space, unindexed, with flat normals and their UVs.
void PlaceInLightSpace(const ReceiverObject& object, const LightFrame& frame,
                       ShadowmaskedMesh* out) {
  out->mesh.label = object.name;
  out->mesh_entry = object.mesh_entry;
  const size_t corners = object.indices.size();
  out->mesh.positions.reserve(corners);
  out->mesh.normals.reserve(corners);
  out->uvs.reserve(corners);
  for (size_t t = 0; t + 2 < corners; t += 3) {
    glm::dvec3 p[3];
    for (int k = 0; k < 3; ++k) {
      p[k] = frame.LightFromWorld(object.positions_world[object.indices[t + k]]);
    }
    glm::dvec3 normal = glm::cross(p[1] - p[0], p[2] - p[0]);
    const double length = glm::length(normal);
    normal = length > 0 ? normal / length : glm::dvec3(0, 0, 1);
    for (int k = 0; k < 3; ++k) {
      out->mesh.positions.push_back(glm::vec3(p[k]));
      out->mesh.normals.push_back(glm::vec3(normal));
      out->uvs.push_back(object.uvs[object.indices[t + k]]);
    }
  }
}

}  // namespace

std::string ShadowmaskLightName(const std::string& light_name) {
  return light_name.substr(0, light_name.find('@'));
}

absl::StatusOr<std::vector<ShadowmaskedMesh>> LoadShadowmaskTextures(
    const std::string& scene_path, const std::string& dir, const std::string& light_name,
    const LightFrame& frame, std::vector<std::string>* missing) {
  absl::StatusOr<ReceiverObjects> objects = LoadReceiverObjects(scene_path);
  if (!objects.ok()) return objects.status();
  const std::string wanted = ShadowmaskLightName(light_name);
  std::vector<ShadowmaskedMesh> meshes;
  for (const ReceiverObject& object : objects->objects) {
    std::vector<std::string> seen;  // the lights of the object's files, for the error
    bool found = false;
    for (int group = 0;; ++group) {
      const std::string path =
          (std::filesystem::path(dir) / (ShadowmaskFileStem(object.name, group) + ".exr")).string();
      std::error_code ec;
      if (!std::filesystem::exists(path, ec)) break;
      absl::StatusOr<ShadowmaskImage> image = ReadShadowmaskExr(path);
      if (!image.ok()) return image.status();
      const size_t channels = image->lights.size();
      auto it = std::find(image->lights.begin(), image->lights.end(), wanted);
      // A texture of a single unnamed light serves a scene of one unnamed light.
      if (it == image->lights.end() && wanted.empty() && channels == 1) it = image->lights.begin();
      if (it == image->lights.end()) {
        seen.insert(seen.end(), image->lights.begin(), image->lights.end());
        continue;
      }
      const size_t channel = static_cast<size_t>(it - image->lights.begin());
      ShadowmaskedMesh mesh;
      PlaceInLightSpace(object, frame, &mesh);
      mesh.width = image->width;
      mesh.height = image->height;
      mesh.attenuation.resize(static_cast<size_t>(image->width) * image->height);
      for (size_t t = 0; t < mesh.attenuation.size(); ++t) {
        const float v = image->values[t * channels + channel];
        mesh.attenuation[t] = image->visibility ? 1.0f - v : v;
      }
      meshes.push_back(std::move(mesh));
      found = true;
      break;
    }
    if (!found && !seen.empty()) {
      return absl::InvalidArgumentError(absl::StrCat(
          dir, ": the textures of ", object.source, " hold the lights ", absl::StrJoin(seen, ", "),
          ", not \"", wanted, "\" (pdsm-view --light chooses the light)"));
    }
    if (!found) missing->push_back(object.source);
  }
  if (meshes.empty()) {
    return absl::NotFoundError(absl::StrCat(
        dir, ": no shadowmask texture of this scene's receivers (",
        ShadowmaskFileStem(objects->objects.empty() ? "OBJECT" : objects->objects[0].name, 0),
        ".exr ...; written by pdsm shadowmask)"));
  }
  return meshes;
}

}  // namespace pdsm::view
