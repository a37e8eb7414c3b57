#include "core/scene/mesh_file.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <system_error>
#include <vector>

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/string_view.h"
#include "core/scene/material_masks.h"
#include "core/scene/node_roles.h"

namespace pdsm {
namespace internal {

absl::Status CannotReadMesh(const std::string& context, const std::string& path,
                            absl::string_view reason) {
  return absl::InvalidArgumentError(
      absl::StrCat(context, ": cannot read \"", path, "\": ", reason));
}

absl::Status CheckMeshFileExists(const std::string& path, const std::string& context) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) {
    return CannotReadMesh(context, path, "no such file");
  }
  if (ec) return CannotReadMesh(context, path, ec.message());
  if (status.type() != std::filesystem::file_type::regular) {
    return CannotReadMesh(context, path, "not a regular file");
  }
  return absl::OkStatus();
}

}  // namespace internal

namespace {

using internal::CannotReadMesh;

// Appends the triangles of one (already pre-transformed) Assimp mesh; points and lines, which
// triangulation leaves alone, cast no shadow and are skipped. `mask_index` 0: opaque; else the
// mesh's triangles are tested by masks[mask_index - 1] through its UV channel `alpha.uv_channel`.
absl::Status AppendTriangles(const aiMesh& mesh, const internal::MaterialAlpha& alpha,
                             uint16_t mask_index, MeshFileData* data) {
  const uint32_t base = static_cast<uint32_t>(data->positions.size());
  const aiVector3D* uvs = nullptr;
  if (mask_index > 0 && alpha.needs_uvs) {
    if (alpha.uv_channel >= AI_MAX_NUMBER_OF_TEXTURECOORDS ||
        mesh.mTextureCoords[alpha.uv_channel] == nullptr) {
      return absl::InvalidArgumentError(absl::StrCat(
          "mesh \"", mesh.mName.C_Str(), "\" is alpha-tested (", data->masks[mask_index - 1]->label,
          ") but has no texture coordinates ", alpha.uv_channel));
    }
    uvs = mesh.mTextureCoords[alpha.uv_channel];
  }
  for (unsigned i = 0; i < mesh.mNumVertices; ++i) {
    const aiVector3D& p = mesh.mVertices[i];
    data->positions.emplace_back(p.x, p.y, p.z);
    data->uvs.emplace_back(uvs != nullptr ? glm::vec2(uvs[i].x, uvs[i].y) : glm::vec2(0.0f));
  }
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices != 3) continue;
    for (unsigned k = 0; k < 3; ++k) data->indices.push_back(base + face.mIndices[k]);
    data->triangle_masks.push_back(mask_index);
  }
  return absl::OkStatus();
}

// Gives each distinct mask of the file's materials an index (1-based, as triangle_masks holds).
absl::StatusOr<std::vector<uint16_t>> IndexMasks(const std::vector<internal::MaterialAlpha>& alphas,
                                                 MeshFileData* data) {
  std::vector<uint16_t> index_of_material(alphas.size(), 0);
  for (size_t m = 0; m < alphas.size(); ++m) {
    if (alphas[m].mask == nullptr) continue;
    const auto same = std::find(data->masks.begin(), data->masks.end(), alphas[m].mask);
    if (same == data->masks.end()) {
      if (data->masks.size() == UINT16_MAX) {
        return absl::InvalidArgumentError(
            absl::StrCat("more than ", UINT16_MAX, " alpha-tested textures"));
      }
      data->masks.push_back(alphas[m].mask);
    }
    index_of_material[m] =
        static_cast<uint16_t>(std::find(data->masks.begin(), data->masks.end(), alphas[m].mask) -
                              data->masks.begin() + 1);
  }
  return index_of_material;
}

// PreTransformVertices flattens the node hierarchy (instances are duplicated) so one flat
// triangle list comes out; JoinIdenticalVertices undoes the per-face vertex copies some
// importers (OBJ) make, and drops vertices no face uses. FlipUVs puts every format's UV origin
// at the image's top-left (glTF's; Assimp turns all of them to OpenGL's bottom-left).
constexpr unsigned kFlattenSteps = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                   aiProcess_PreTransformVertices | aiProcess_FlipUVs;

// The flattened scene (kFlattenSteps applied) as MeshFileData, checked.
absl::StatusOr<MeshFileData> Convert(const aiScene* scene, const std::string& path,
                                     const std::string& context) {
  size_t vertex_count = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    vertex_count += scene->mMeshes[m]->mNumVertices;
  }
  if (vertex_count > std::numeric_limits<uint32_t>::max()) {
    return CannotReadMesh(context, path, absl::StrCat("too many vertices (", vertex_count, ")"));
  }

  std::vector<std::string> blend_materials, translucent_materials;
  absl::StatusOr<std::vector<internal::MaterialAlpha>> alphas =
      internal::ReadMaterialAlphas(*scene, path, &blend_materials, &translucent_materials);
  if (!alphas.ok()) return CannotReadMesh(context, path, alphas.status().message());
  MeshFileData data;
  absl::StatusOr<std::vector<uint16_t>> mask_of_material = IndexMasks(*alphas, &data);
  if (!mask_of_material.ok())
    return CannotReadMesh(context, path, mask_of_material.status().message());
  data.positions.reserve(vertex_count);
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh& mesh = *scene->mMeshes[m];
    // Assimp gives every mesh a material (a default one when the file has none).
    const unsigned material = mesh.mMaterialIndex;
    const bool known = material < alphas->size();
    const internal::MaterialAlpha opaque;
    if (absl::Status s = AppendTriangles(mesh, known ? (*alphas)[material] : opaque,
                                         known ? (*mask_of_material)[material] : 0, &data);
        !s.ok()) {
      return CannotReadMesh(context, path, s.message());
    }
  }
  // Masks no triangle uses (a material of points or lines only) are dropped with the rest.
  if (std::none_of(data.triangle_masks.begin(), data.triangle_masks.end(),
                   [](uint16_t k) { return k != 0; })) {
    data.masks.clear();
  }
  if (!data.has_masks()) {
    data.uvs.clear();
    data.triangle_masks.clear();
  }
  if (!blend_materials.empty()) {
    data.warnings.push_back(absl::StrCat(
        context, " (", path, "): material(s) ", absl::StrJoin(blend_materials, ", "),
        " use alphaMode BLEND: baked as MASK at alphaCutoff 0.5 (a shadow map stores what "
        "blocks the light, not how much of it passes)"));
  }
  if (!translucent_materials.empty()) {
    data.warnings.push_back(absl::StrCat(
        context, " (", path, "): material(s) ", absl::StrJoin(translucent_materials, ", "),
        " have an opacity below 1 and no opacity texture: baked opaque at opacity >= 0.5, "
        "casting nothing below"));
  }
  if (data.indices.empty()) return CannotReadMesh(context, path, "no triangles");
  for (const glm::dvec3& p : data.positions) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      return CannotReadMesh(context, path, "a vertex coordinate is not finite");
    }
  }
  for (const glm::vec2& uv : data.uvs) {
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) {
      return CannotReadMesh(context, path,
                            "a texture coordinate of an alpha-tested mesh is not finite");
    }
  }
  return data;
}

// Whether a node holds a mesh with polygons (what triangulation turns into triangles).
bool HoldsPolygons(const aiScene& scene, const aiNode& node) {
  for (unsigned k = 0; k < node.mNumMeshes; ++k) {
    const unsigned types = scene.mMeshes[node.mMeshes[k]]->mPrimitiveTypes;
    if ((types & (aiPrimitiveType_TRIANGLE | aiPrimitiveType_POLYGON)) != 0) return true;
  }
  return false;
}

// Visits `node` and its descendants.
template <typename Visit>
void ForEachNode(aiNode* node, const Visit& visit) {
  visit(node);
  for (unsigned c = 0; c < node->mNumChildren; ++c) ForEachNode(node->mChildren[c], visit);
}

// Deletes the meshes no node refers to and renumbers the nodes' references, keeping the order
// of the rest. Why: PreTransformVertices hands every face's index array over to the meshes it
// builds from the nodes' references and then frees the old meshes without them, so the index
// arrays of a mesh no node refers to would leak (Assimp 5.2.5; LeakSanitizer found it).
void DeleteUnreferencedMeshes(aiScene* scene) {
  std::vector<unsigned> new_index(scene->mNumMeshes, 0);
  std::vector<bool> referenced(scene->mNumMeshes, false);
  bool in_range = true;  // an importer that wrote a bad reference: leave the scene as it is
  ForEachNode(scene->mRootNode, [&](aiNode* node) {
    for (unsigned k = 0; k < node->mNumMeshes; ++k) {
      if (node->mMeshes[k] < scene->mNumMeshes) {
        referenced[node->mMeshes[k]] = true;
      } else {
        in_range = false;
      }
    }
  });
  if (!in_range) return;
  unsigned kept = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    if (!referenced[m]) {
      delete scene->mMeshes[m];
      continue;
    }
    new_index[m] = kept;
    scene->mMeshes[kept++] = scene->mMeshes[m];
  }
  for (unsigned m = kept; m < scene->mNumMeshes; ++m) scene->mMeshes[m] = nullptr;
  scene->mNumMeshes = kept;
  ForEachNode(scene->mRootNode, [&](aiNode* node) {
    for (unsigned k = 0; k < node->mNumMeshes; ++k) node->mMeshes[k] = new_index[node->mMeshes[k]];
  });
}

// The meshes of the nodes whose role is `role`, flattened. `importer` holds the file read
// without steps; the other nodes' mesh references are dropped, and the meshes then unused
// deleted (PreTransformVertices builds its meshes from the nodes' references alone), then
// LoadMeshFile's steps run. Assimp documents ReadFile(0) then ApplyPostProcessing(steps) as
// equal to ReadFile(steps), so a file without roles gives LoadMeshFile's bytes. Consumes the
// importer's scene.
absl::StatusOr<MeshFileData> FlattenNodesOfRole(Assimp::Importer& importer, const std::string& path,
                                                const std::string& context,
                                                std::optional<MeshRole> role) {
  // The importer owns the scene; editing it before the steps run is the use
  // ApplyPostProcessing exists for.
  aiScene* scene = const_cast<aiScene*>(importer.GetScene());
  absl::StatusOr<internal::NodeRoles> roles = internal::ReadNodeRoles(*scene, path, context);
  if (!roles.ok()) return roles.status();
  for (const auto& [node, node_role] : *roles) {
    if (node_role == role) continue;
    aiNode* dropped = const_cast<aiNode*>(node);
    delete[] dropped->mMeshes;
    dropped->mMeshes = nullptr;
    dropped->mNumMeshes = 0;
  }
  DeleteUnreferencedMeshes(scene);
  if (scene->mNumMeshes == 0) return CannotReadMesh(context, path, "no triangles");
  const aiScene* flat = importer.ApplyPostProcessing(kFlattenSteps);
  if (flat == nullptr) return CannotReadMesh(context, path, importer.GetErrorString());
  absl::StatusOr<MeshFileData> data = Convert(flat, path, context);
  if (data.ok()) data->node_role = role;
  return data;
}

}  // namespace

absl::StatusOr<MeshFileData> LoadMeshFile(const std::string& path, const std::string& context) {
  if (absl::Status status = internal::CheckMeshFileExists(path, context); !status.ok())
    return status;
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, kFlattenSteps);
  if (scene == nullptr) return CannotReadMesh(context, path, importer.GetErrorString());
  return Convert(scene, path, context);
}

absl::StatusOr<std::vector<MeshFileData>> LoadMeshFileByRole(const std::string& path,
                                                             const std::string& context) {
  if (absl::Status status = internal::CheckMeshFileExists(path, context); !status.ok())
    return status;
  // A first import without steps reads the roles; it serves the last role flattened, so a file
  // with k roles is imported k times (a file without roles once, as LoadMeshFile does).
  Assimp::Importer first;
  const aiScene* scene = first.ReadFile(path, 0);
  if (scene == nullptr) return CannotReadMesh(context, path, first.GetErrorString());
  absl::StatusOr<internal::NodeRoles> roles = internal::ReadNodeRoles(*scene, path, context);
  if (!roles.ok()) return roles.status();
  std::vector<std::optional<MeshRole>> present;
  if (!internal::AnyNodeRole(*roles)) {
    present.push_back(std::nullopt);
  } else {
    for (const std::optional<MeshRole> role :
         {std::optional<MeshRole>(), std::optional(MeshRole::kCasterAndReceiver),
          std::optional(MeshRole::kCasterOnly), std::optional(MeshRole::kReceiverOnly)}) {
      for (const auto& [node, node_role] : *roles) {
        if (node_role == role && HoldsPolygons(*scene, *node)) {
          present.push_back(role);
          break;
        }
      }
    }
    if (present.empty()) return CannotReadMesh(context, path, "no triangles");
  }
  std::vector<MeshFileData> parts;
  std::vector<std::string> warnings;
  for (size_t i = 0; i < present.size(); ++i) {
    Assimp::Importer again;
    const bool last = i + 1 == present.size();
    if (!last && again.ReadFile(path, 0) == nullptr) {
      return CannotReadMesh(context, path, again.GetErrorString());
    }
    absl::StatusOr<MeshFileData> part =
        FlattenNodesOfRole(last ? first : again, path, context, present[i]);
    if (!part.ok()) return part.status();
    for (std::string& w : part->warnings) {
      if (std::find(warnings.begin(), warnings.end(), w) == warnings.end()) {
        warnings.push_back(std::move(w));
      }
    }
    part->warnings.clear();
    parts.push_back(*std::move(part));
  }
  parts.front().warnings = std::move(warnings);
  return parts;
}

}  // namespace pdsm
