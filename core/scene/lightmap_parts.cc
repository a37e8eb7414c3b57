#include "core/scene/lightmap_parts.h"

#include <cmath>
#include <limits>

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include "absl/strings/str_cat.h"
#include "core/scene/field_checker.h"
#include "core/scene/mesh_file.h"
#include "core/scene/node_roles.h"
#include "core/scene/scene_loader.h"
#include "core/scene/scene_mesh.h"

namespace pdsm {
namespace {

using internal::CannotReadMesh;

// Row-major 4x4 in double (Assimp's aiMatrix4x4 is float, row-major, column vectors).
struct Affine {
  double m[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};

  glm::dvec3 Apply(const aiVector3D& p) const {
    const double x = p.x, y = p.y, z = p.z;
    return {m[0][0] * x + m[0][1] * y + m[0][2] * z + m[0][3],
            m[1][0] * x + m[1][1] * y + m[1][2] * z + m[1][3],
            m[2][0] * x + m[2][1] * y + m[2][2] * z + m[2][3]};
  }
};

// parent * local, in double: a deep hierarchy does not pile up float roundings.
Affine Compose(const Affine& parent, const aiMatrix4x4& local) {
  const double l[3][4] = {{local.a1, local.a2, local.a3, local.a4},
                          {local.b1, local.b2, local.b3, local.b4},
                          {local.c1, local.c2, local.c3, local.c4}};
  Affine out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      out.m[r][c] = parent.m[r][0] * l[0][c] + parent.m[r][1] * l[1][c] + parent.m[r][2] * l[2][c] +
                    (c == 3 ? parent.m[r][3] : 0.0);
    }
  }
  return out;
}

// The UV set every mesh of `node` has: 1 when all have a second, else 0 when all have a
// first, else -1.
int CommonUvSet(const aiScene& scene, const aiNode& node) {
  bool all_first = true, all_second = true;
  for (unsigned k = 0; k < node.mNumMeshes; ++k) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[k]];
    all_first = all_first && mesh.HasTextureCoords(0);
    all_second = all_second && mesh.HasTextureCoords(1);
  }
  return all_second ? 1 : (all_first ? 0 : -1);
}

void AppendNode(const aiScene& scene, const aiNode& node, const Affine& parent,
                const internal::NodeRoles& roles, std::vector<LightmapPart>* parts) {
  const Affine world = Compose(parent, node.mTransformation);
  LightmapPart part;
  part.node = node.mName.C_Str();
  part.node_role = roles.at(&node);
  part.uv_set = CommonUvSet(scene, node);
  for (unsigned k = 0; k < node.mNumMeshes; ++k) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[k]];
    const auto base = static_cast<uint32_t>(part.positions.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      part.positions.push_back(world.Apply(mesh.mVertices[v]));
      if (part.uv_set >= 0) {
        const aiVector3D& uv = mesh.mTextureCoords[part.uv_set][v];
        part.uvs.emplace_back(uv.x, uv.y);
      }
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;
      for (unsigned i = 0; i < 3; ++i) part.indices.push_back(base + face.mIndices[i]);
    }
  }
  if (!part.indices.empty()) parts->push_back(std::move(part));
  for (unsigned c = 0; c < node.mNumChildren; ++c) {
    AppendNode(scene, *node.mChildren[c], world, roles, parts);
  }
}

}  // namespace

absl::StatusOr<std::vector<LightmapPart>> LoadLightmapParts(const std::string& path,
                                                            const std::string& context) {
  if (absl::Status s = internal::CheckMeshFileExists(path, context); !s.ok()) return s;
  // The same import as LoadMeshFile's but for PreTransformVertices: the nodes stay apart.
  // FlipUVs puts the UV origin at the image's top-left, as LoadMeshFile's alpha masks have it.
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_FlipUVs);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    return CannotReadMesh(context, path, importer.GetErrorString());
  }
  size_t vertices = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) vertices += scene->mMeshes[m]->mNumVertices;
  if (vertices > std::numeric_limits<uint32_t>::max()) {
    return CannotReadMesh(context, path, absl::StrCat("too many vertices (", vertices, ")"));
  }
  absl::StatusOr<internal::NodeRoles> roles = internal::ReadNodeRoles(*scene, path, context);
  if (!roles.ok()) return roles.status();
  std::vector<LightmapPart> parts;
  AppendNode(*scene, *scene->mRootNode, Affine{}, *roles, &parts);
  if (parts.empty()) return CannotReadMesh(context, path, "no triangles");
  for (const LightmapPart& part : parts) {
    for (const glm::dvec3& p : part.positions) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        return CannotReadMesh(context, path,
                              absl::StrCat("node \"", part.node, "\": a position is not finite"));
      }
    }
    for (const glm::vec2& uv : part.uvs) {
      if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) {
        return CannotReadMesh(
            context, path,
            absl::StrCat("node \"", part.node, "\": a texture coordinate is not finite"));
      }
    }
  }
  return parts;
}

absl::StatusOr<std::vector<LightmapPart>> LoadSceneMeshParts(const std::string& scene_path,
                                                             int index,
                                                             const pdsm::v1::Mesh& mesh) {
  const std::string field = absl::StrCat("meshes[", index, "]");
  absl::StatusOr<std::vector<LightmapPart>> parts = LoadLightmapParts(
      ResolveMeshPath(scene_path, mesh.path()), absl::StrCat(scene_path, ": ", field, ".path"));
  if (!parts.ok()) return parts.status();
  const internal::FieldChecker checks(scene_path, {});
  for (LightmapPart& part : *parts) {
    absl::StatusOr<std::vector<glm::dvec3>> world =
        internal::PlaceInWorld(checks, field + ".transform", mesh.transform(), part.positions);
    if (!world.ok()) return world.status();
    part.positions = *std::move(world);
  }
  return parts;
}

}  // namespace pdsm
