#include "core/scene/mesh_file.h"

#include <cmath>
#include <filesystem>
#include <limits>
#include <system_error>

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/string_view.h"

namespace pdsm {
namespace {

absl::Status CannotRead(const std::string& context, const std::string& path,
                        absl::string_view reason) {
  return absl::InvalidArgumentError(
      absl::StrCat(context, ": cannot read \"", path, "\": ", reason));
}

// Assimp reports a missing file as a generic open failure; say what happened instead.
absl::Status CheckIsRegularFile(const std::string& path, const std::string& context) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) {
    return CannotRead(context, path, "no such file");
  }
  if (ec) return CannotRead(context, path, ec.message());
  if (status.type() != std::filesystem::file_type::regular) {
    return CannotRead(context, path, "not a regular file");
  }
  return absl::OkStatus();
}

// Appends the triangles of one (already pre-transformed) Assimp mesh; points and lines, which
// triangulation leaves alone, cast no shadow and are skipped.
void AppendTriangles(const aiMesh& mesh, MeshFileData* data) {
  const uint32_t base = static_cast<uint32_t>(data->positions.size());
  for (unsigned i = 0; i < mesh.mNumVertices; ++i) {
    const aiVector3D& p = mesh.mVertices[i];
    data->positions.emplace_back(p.x, p.y, p.z);
  }
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices != 3) continue;
    for (unsigned k = 0; k < 3; ++k) data->indices.push_back(base + face.mIndices[k]);
  }
}

}  // namespace

absl::StatusOr<MeshFileData> LoadMeshFile(const std::string& path, const std::string& context) {
  if (absl::Status status = CheckIsRegularFile(path, context); !status.ok()) return status;

  // PreTransformVertices flattens the node hierarchy (instances are duplicated) so one flat
  // triangle list comes out; JoinIdenticalVertices undoes the per-face vertex copies some
  // importers (OBJ) make, and drops vertices no face uses.
  Assimp::Importer importer;
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                  aiProcess_PreTransformVertices);
  if (scene == nullptr) return CannotRead(context, path, importer.GetErrorString());

  size_t vertex_count = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    vertex_count += scene->mMeshes[m]->mNumVertices;
  }
  if (vertex_count > std::numeric_limits<uint32_t>::max()) {
    return CannotRead(context, path, absl::StrCat("too many vertices (", vertex_count, ")"));
  }

  MeshFileData data;
  data.positions.reserve(vertex_count);
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) AppendTriangles(*scene->mMeshes[m], &data);
  if (data.indices.empty()) return CannotRead(context, path, "no triangles");
  for (const glm::dvec3& p : data.positions) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      return CannotRead(context, path, "a vertex coordinate is not finite");
    }
  }
  return data;
}

}  // namespace pdsm
