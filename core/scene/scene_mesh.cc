#include "core/scene/scene_mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/status.h"
#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "core/assets/mesh_asset.h"
#include "core/scene/mesh_file.h"
#include "core/scene/node_roles.h"
#include "spdlog/spdlog.h"

namespace pdsm::internal {
namespace {

using Transform = std::array<double, 16>;  // row-major, column-vector convention

absl::StatusOr<Transform> BuildTransform(const FieldChecker& checks, absl::string_view field,
                                         const RepeatedDoubles& values) {
  Transform m = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  if (values.empty()) return m;
  if (values.size() != 16) {
    return checks.Error(field, absl::StrCat("must have 0 or 16 numbers (got ", values.size(), ")"));
  }
  if (absl::Status s = checks.CheckAllFinite(field, values); !s.ok()) return s;
  std::copy(values.begin(), values.end(), m.begin());
  // A projective last row has no meaning for geometry; it is usually a column-major matrix.
  if (m[12] != 0 || m[13] != 0 || m[14] != 0 || m[15] != 1) {
    return checks.Error(field, absl::StrCat("the last row must be 0, 0, 0, 1; the matrix is "
                                            "row-major with the translation in elements 3, 7, "
                                            "11 (got last row ",
                                            FormatDouble(m[12]), ", ", FormatDouble(m[13]), ", ",
                                            FormatDouble(m[14]), ", ", FormatDouble(m[15]), ")"));
  }
  // Scale-free singularity test: Hadamard's inequality bounds |det| by the product of the
  // row lengths, with equality for orthogonal rows.
  const glm::dvec3 r0(m[0], m[1], m[2]), r1(m[4], m[5], m[6]), r2(m[8], m[9], m[10]);
  const double det = glm::dot(r0, glm::cross(r1, r2));
  const double bound = glm::length(r0) * glm::length(r1) * glm::length(r2);
  if (!(std::abs(det) > 1e-12 * bound)) {
    return checks.Error(field, absl::StrCat("the 3x3 part must be invertible (got determinant ",
                                            FormatDouble(det), ")"));
  }
  return m;
}

absl::Status LoadInline(const FieldChecker& checks, absl::string_view field,
                        const pdsm::v1::InlineMesh& mesh, std::vector<glm::dvec3>* positions,
                        std::vector<uint32_t>* indices) {
  const std::string positions_field = absl::StrCat(field, ".positions");
  const std::string indices_field = absl::StrCat(field, ".indices");
  if (mesh.positions_size() % 3 != 0) {
    return checks.Error(positions_field, absl::StrCat("the count must be a multiple of 3 (got ",
                                                      mesh.positions_size(), ")"));
  }
  if (absl::Status s = checks.CheckAllFinite(positions_field, mesh.positions()); !s.ok()) {
    return s;
  }
  if (mesh.indices_size() % 3 != 0) {
    return checks.Error(indices_field, absl::StrCat("the count must be a multiple of 3 (got ",
                                                    mesh.indices_size(), ")"));
  }
  if (mesh.indices().empty()) return checks.Error(indices_field, "no triangles (got 0 indices)");
  const uint32_t vertex_count = static_cast<uint32_t>(mesh.positions_size() / 3);
  for (int i = 0; i < mesh.indices_size(); ++i) {
    if (mesh.indices(i) >= vertex_count) {
      return checks.Error(Indexed(indices_field, i),
                          absl::StrCat("must be < ", vertex_count, ", the vertex count (got ",
                                       mesh.indices(i), ")"));
    }
  }
  positions->reserve(vertex_count);
  for (uint32_t v = 0; v < vertex_count; ++v) {
    positions->emplace_back(mesh.positions(3 * v), mesh.positions(3 * v + 1),
                            mesh.positions(3 * v + 2));
  }
  indices->assign(mesh.indices().begin(), mesh.indices().end());
  return absl::OkStatus();
}

absl::Status LoadPath(const FieldChecker& checks, const MeshSources& sources,
                      absl::string_view field, const std::string& path,
                      std::vector<MeshFileData>* out) {
  if (sources.base_dir.empty()) {
    return checks.Error(field, "mesh files are not accepted here; send inline geometry");
  }
  if (path.empty()) return checks.Error(field, "must not be empty");
  absl::StatusOr<std::vector<MeshFileData>> parts = LoadMeshFileByRole(
      ResolveAgainst(sources.base_dir, path), absl::StrCat(checks.source(), ": ", field));
  if (!parts.ok()) return parts.status();
  *out = *std::move(parts);
  return absl::OkStatus();
}

absl::Status LoadAsset(const FieldChecker& checks, const MeshSources& sources,
                       absl::string_view field, const std::string& sha256, MeshFileData* out) {
  if (sources.assets == nullptr) {
    return checks.Error(field,
                        "mesh assets are only accepted by the coordinator; use path or inline");
  }
  if (!IsSha256Hex(sha256)) {
    constexpr size_t kShown = 80;  // the hash comes from a client: cut it short
    return checks.Error(field, absl::StrCat("must be a SHA-256, 64 lowercase hex digits (got \"",
                                            absl::CEscape(sha256.substr(0, kShown)),
                                            sha256.size() > kShown ? "..." : "", "\")"));
  }
  absl::StatusOr<MeshFileData> data =
      (*sources.assets)(sha256, absl::StrCat(checks.source(), ": ", field));
  if (!data.ok()) return data.status();
  *out = *std::move(data);
  return absl::OkStatus();
}

// The model-space mesh (positions, indices, alpha masks) of `mesh`, from whichever source it
// names (a file: one part per role its nodes set), and its label for messages.
absl::Status LoadSource(const FieldChecker& checks, const MeshSources& sources,
                        const std::string& field, const pdsm::v1::Mesh& mesh,
                        std::vector<MeshFileData>* parts, std::string* label) {
  switch (mesh.source_case()) {
    case pdsm::v1::Mesh::kPath:
      *label = absl::StrCat(field, " (", mesh.path(), ")");
      return LoadPath(checks, sources, field + ".path", mesh.path(), parts);
    case pdsm::v1::Mesh::kInline:
      *label = absl::StrCat(field, " (inline)");
      parts->resize(1);
      return LoadInline(checks, field + ".inline", mesh.inline_(), &parts->front().positions,
                        &parts->front().indices);
    case pdsm::v1::Mesh::kAssetSha256:
      *label = absl::StrCat(field, " (asset ", mesh.asset_sha256().substr(0, 12), ")");
      parts->resize(1);
      return LoadAsset(checks, sources, field + ".assetSha256", mesh.asset_sha256(),
                       &parts->front());
    case pdsm::v1::Mesh::SOURCE_NOT_SET:
      break;
  }
  return checks.Error(field, "one of path, inline, assetSha256 is required");
}

}  // namespace

std::string ResolveAgainst(const std::string& base_dir, const std::string& path) {
  std::filesystem::path file(path);
  if (file.is_relative()) file = (std::filesystem::path(base_dir) / file).lexically_normal();
  return file.string();
}

absl::StatusOr<std::vector<TriangleMesh>> BuildMesh(const FieldChecker& checks,
                                                    const MeshSources& sources, int index,
                                                    const pdsm::v1::Mesh& mesh) {
  const std::string field = Indexed("meshes", index);
  if (!mesh.lights_from().empty()) {
    // Reading the scene file resolves it (file_lights.h); a message arriving otherwise (a
    // coordinator's) must hold the lights themselves.
    return checks.Error(field + ".lightsFrom",
                        "is resolved where the scene file is read; send the file's lights");
  }
  MeshRole entry_role = MeshRole::kCasterAndReceiver;
  switch (mesh.role()) {
    case pdsm::v1::CASTER_AND_RECEIVER:
      entry_role = MeshRole::kCasterAndReceiver;
      break;
    case pdsm::v1::CASTER_ONLY:
      entry_role = MeshRole::kCasterOnly;
      break;
    case pdsm::v1::RECEIVER_ONLY:
      entry_role = MeshRole::kReceiverOnly;
      break;
    default:
      return checks.Error(field + ".role", absl::StrCat("unknown value (got ", mesh.role(), ")"));
  }
  if (mesh.has_refine() && entry_role == MeshRole::kCasterOnly) {
    return checks.Error(field + ".refine",
                        "a CASTER_ONLY mesh receives no shadow to refine; set it on receivers");
  }
  if (absl::Status s = BuildTransform(checks, field + ".transform", mesh.transform()).status();
      !s.ok()) {
    return s;  // before the mesh is read: a bad transform is named whatever the file holds
  }
  std::vector<MeshFileData> parts;
  std::string label;
  if (absl::Status s = LoadSource(checks, sources, field, mesh, &parts, &label); !s.ok()) {
    return s;
  }
  std::vector<TriangleMesh> out;
  for (MeshFileData& data : parts) {
    for (std::string& warning : data.warnings) {
      if (sources.warnings != nullptr) {
        sources.warnings->push_back(std::move(warning));
      } else {
        spdlog::warn("{}", warning);
      }
    }
    TriangleMesh& part = out.emplace_back();
    part.entry = index;
    part.role = data.node_role.value_or(entry_role);
    part.refine = !mesh.has_refine() || mesh.refine();
    part.label = data.node_role.has_value()
                     ? absl::StrCat(label, " nodes ", MeshRoleName(*data.node_role))
                     : label;
    part.indices = std::move(data.indices);
    part.uvs = std::move(data.uvs);
    part.triangle_masks = std::move(data.triangle_masks);
    part.masks = std::move(data.masks);
    absl::StatusOr<std::vector<glm::dvec3>> world =
        PlaceInWorld(checks, field + ".transform", mesh.transform(), data.positions);
    if (!world.ok()) return world.status();
    part.positions_world = *std::move(world);
  }
  return out;
}

absl::StatusOr<std::vector<glm::dvec3>> PlaceInWorld(const FieldChecker& checks,
                                                     absl::string_view field,
                                                     const RepeatedDoubles& transform,
                                                     const std::vector<glm::dvec3>& model) {
  absl::StatusOr<Transform> checked = BuildTransform(checks, field, transform);
  if (!checked.ok()) return checked.status();
  // World positions in double, in a fixed order of operations, so a world far from the origin
  // keeps its precision and every build computes the same bits.
  const Transform& m = *checked;
  std::vector<glm::dvec3> world;
  world.reserve(model.size());
  for (const glm::dvec3& p : model) {
    world.emplace_back(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3],
                       m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                       m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
  }
  for (size_t v = 0; v < world.size(); ++v) {
    const glm::dvec3& p = world[v];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      return checks.Error(field, absl::StrCat("moves vertex ", v, " out of the finite range"));
    }
  }
  return world;
}

}  // namespace pdsm::internal
