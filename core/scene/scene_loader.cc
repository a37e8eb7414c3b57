#include "core/scene/scene_loader.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>
#include <system_error>
#include <tuple>
#include <utility>
#include <vector>

#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <google/protobuf/util/json_util.h>

#include "absl/status/status.h"
#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/string_view.h"
#include "core/assets/mesh_asset.h"
#include "core/sampling/light_samples.h"
#include "core/scene/json_number_range.h"
#include "core/scene/mesh_file.h"

namespace pdsm {
namespace {

using RepeatedDoubles = google::protobuf::RepeatedField<double>;
using RepeatedUints = google::protobuf::RepeatedField<uint32_t>;
using Transform = std::array<double, 16>;  // row-major, column-vector convention

// Shortest text that reads back to the same double, with the JSON spellings of the
// non-finite values so the message shows what the user wrote.
std::string FormatDouble(double x) {
  if (std::isnan(x)) return "NaN";
  if (std::isinf(x)) return x > 0 ? "Infinity" : "-Infinity";
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), x);
  return std::string(buffer, result.ptr);
}

std::string FormatDoubles(const RepeatedDoubles& values) {
  return absl::StrCat(
      "[", absl::StrJoin(values, ", ",
                         [](std::string* out, double x) { out->append(FormatDouble(x)); }),
      "]");
}

std::string Indexed(absl::string_view field, int index) {
  return absl::StrCat(field, "[", index, "]");
}

// `path` as is when absolute, else against `base_dir`.
std::string ResolveAgainst(const std::string& base_dir, const std::string& path) {
  std::filesystem::path file(path);
  if (file.is_relative()) file = (std::filesystem::path(base_dir) / file).lexically_normal();
  return file.string();
}

// The folder relative mesh paths of a scene file resolve against ("." for a bare file name,
// since an empty base_dir means "no mesh files").
std::string SceneFolder(const std::string& scene_path) {
  const std::filesystem::path folder = std::filesystem::path(scene_path).parent_path();
  return folder.empty() ? std::string(".") : folder.string();
}

// Validates one pdsm.v1.Scene into a Scene. Every error is INVALID_ARGUMENT
// "SOURCE: FIELD: what (got VALUE)", FIELD spelled with the JSON names the user wrote.
class SceneBuilder {
 public:
  SceneBuilder(std::string source, std::string base_dir, std::set<std::string> overridden,
               const MeshAssetResolver* assets = nullptr)
      : source_(std::move(source)),
        base_dir_(std::move(base_dir)),
        overridden_(std::move(overridden)),
        assets_(assets != nullptr && *assets ? assets : nullptr) {}

  absl::StatusOr<Scene> Build(const pdsm::v1::Scene& message) const;

 private:
  absl::Status Error(absl::string_view field, absl::string_view what) const {
    return absl::InvalidArgumentError(
        absl::StrCat(source_, ": ", field, OverrideMark(field), ": ", what));
  }
  // " (override)" when a bake field's value came from the overrides, not from the file.
  absl::string_view OverrideMark(absl::string_view field) const;

  absl::Status CheckFinite(absl::string_view field, double x) const;
  absl::Status CheckAllFinite(absl::string_view field, const RepeatedDoubles& values) const;
  absl::StatusOr<glm::dvec3> Vec3(absl::string_view field, const RepeatedDoubles& values) const;
  absl::StatusOr<glm::dvec3> Direction(absl::string_view field,
                                       const RepeatedDoubles& values) const;
  absl::Status CheckPositive(absl::string_view field, double x) const;

  absl::StatusOr<TriangleMesh> BuildMesh(int index, const pdsm::v1::Mesh& mesh) const;
  absl::StatusOr<Transform> BuildTransform(absl::string_view field,
                                           const RepeatedDoubles& values) const;
  absl::Status LoadInline(absl::string_view field, const pdsm::v1::InlineMesh& mesh,
                          std::vector<glm::dvec3>* positions,
                          std::vector<uint32_t>* indices) const;
  absl::Status LoadPath(absl::string_view field, const std::string& path,
                        std::vector<glm::dvec3>* positions,
                        std::vector<uint32_t>* indices) const;
  absl::Status LoadAsset(absl::string_view field, const std::string& sha256,
                         std::vector<glm::dvec3>* positions,
                         std::vector<uint32_t>* indices) const;

  absl::StatusOr<LightSpec> BuildLight(const pdsm::v1::Light& light) const;
  absl::StatusOr<LightSpec> BuildRect(const pdsm::v1::RectLight& rect) const;
  absl::StatusOr<LightSpec> BuildDisk(const pdsm::v1::DiskLight& disk) const;
  absl::StatusOr<LightSpec> BuildSun(const pdsm::v1::SunLight& sun) const;

  absl::StatusOr<BakeSettings> BuildBake(const pdsm::v1::BakeParams& bake,
                                         LightShape shape) const;
  absl::Status CheckUintRange(absl::string_view field, uint32_t value, int max) const;
  absl::Status BuildAdaptive(const pdsm::v1::BakeParams& bake, BakeSettings* out) const;
  absl::StatusOr<FrustumOverride> BuildFrustum(const pdsm::v1::Frustum& frustum,
                                               LightShape shape) const;

  std::string source_;
  std::string base_dir_;  // empty: mesh files refused
  std::set<std::string> overridden_;
  const MeshAssetResolver* assets_;  // null: mesh assets refused
};

absl::string_view SceneBuilder::OverrideMark(absl::string_view field) const {
  constexpr absl::string_view kBake = "bake.";
  if (field.substr(0, kBake.size()) != kBake) return "";
  absl::string_view name = field.substr(kBake.size());
  name = name.substr(0, name.find_first_of(".["));
  return overridden_.count(std::string(name)) ? " (override)" : "";
}

absl::Status SceneBuilder::CheckFinite(absl::string_view field, double x) const {
  if (std::isfinite(x)) return absl::OkStatus();
  return Error(field, absl::StrCat("must be finite (got ", FormatDouble(x), ")"));
}

absl::Status SceneBuilder::CheckAllFinite(absl::string_view field,
                                          const RepeatedDoubles& values) const {
  for (int i = 0; i < values.size(); ++i) {
    if (absl::Status s = CheckFinite(Indexed(field, i), values[i]); !s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::StatusOr<glm::dvec3> SceneBuilder::Vec3(absl::string_view field,
                                              const RepeatedDoubles& values) const {
  if (values.size() != 3) {
    return Error(field, absl::StrCat("must have 3 numbers (got ", values.size(), ")"));
  }
  if (absl::Status s = CheckAllFinite(field, values); !s.ok()) return s;
  return glm::dvec3(values[0], values[1], values[2]);
}

// A unit vector. Divides by the largest component first so that neither 1e-200 nor 1e200
// components underflow or overflow in the length.
absl::StatusOr<glm::dvec3> SceneBuilder::Direction(absl::string_view field,
                                                   const RepeatedDoubles& values) const {
  absl::StatusOr<glm::dvec3> v = Vec3(field, values);
  if (!v.ok()) return v.status();
  const double scale = std::max({std::abs(v->x), std::abs(v->y), std::abs(v->z)});
  if (scale == 0) {
    return Error(field, absl::StrCat("must be non-zero (got ", FormatDoubles(values), ")"));
  }
  return glm::normalize(*v / scale);
}

absl::Status SceneBuilder::CheckPositive(absl::string_view field, double x) const {
  if (absl::Status s = CheckFinite(field, x); !s.ok()) return s;
  if (x > 0) return absl::OkStatus();
  return Error(field, absl::StrCat("must be > 0 (got ", FormatDouble(x), ")"));
}

// ---- Meshes ----------------------------------------------------------------------------

absl::StatusOr<Transform> SceneBuilder::BuildTransform(absl::string_view field,
                                                       const RepeatedDoubles& values) const {
  Transform m = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  if (values.empty()) return m;
  if (values.size() != 16) {
    return Error(field,
                 absl::StrCat("must have 0 or 16 numbers (got ", values.size(), ")"));
  }
  if (absl::Status s = CheckAllFinite(field, values); !s.ok()) return s;
  std::copy(values.begin(), values.end(), m.begin());
  // A projective last row has no meaning for geometry; it is usually a column-major matrix.
  if (m[12] != 0 || m[13] != 0 || m[14] != 0 || m[15] != 1) {
    return Error(field, absl::StrCat("the last row must be 0, 0, 0, 1; the matrix is "
                                     "row-major with the translation in elements 3, 7, 11 "
                                     "(got last row ",
                                     FormatDouble(m[12]), ", ", FormatDouble(m[13]), ", ",
                                     FormatDouble(m[14]), ", ", FormatDouble(m[15]), ")"));
  }
  // Scale-free singularity test: Hadamard's inequality bounds |det| by the product of the
  // row lengths, with equality for orthogonal rows.
  const glm::dvec3 r0(m[0], m[1], m[2]), r1(m[4], m[5], m[6]), r2(m[8], m[9], m[10]);
  const double det = glm::dot(r0, glm::cross(r1, r2));
  const double bound = glm::length(r0) * glm::length(r1) * glm::length(r2);
  if (!(std::abs(det) > 1e-12 * bound)) {
    return Error(field, absl::StrCat("the 3x3 part must be invertible (got determinant ",
                                     FormatDouble(det), ")"));
  }
  return m;
}

absl::Status SceneBuilder::LoadInline(absl::string_view field, const pdsm::v1::InlineMesh& mesh,
                                      std::vector<glm::dvec3>* positions,
                                      std::vector<uint32_t>* indices) const {
  const std::string positions_field = absl::StrCat(field, ".positions");
  const std::string indices_field = absl::StrCat(field, ".indices");
  if (mesh.positions_size() % 3 != 0) {
    return Error(positions_field, absl::StrCat("the count must be a multiple of 3 (got ",
                                               mesh.positions_size(), ")"));
  }
  if (absl::Status s = CheckAllFinite(positions_field, mesh.positions()); !s.ok()) return s;
  if (mesh.indices_size() % 3 != 0) {
    return Error(indices_field, absl::StrCat("the count must be a multiple of 3 (got ",
                                             mesh.indices_size(), ")"));
  }
  if (mesh.indices().empty()) return Error(indices_field, "no triangles (got 0 indices)");
  const uint32_t vertex_count = static_cast<uint32_t>(mesh.positions_size() / 3);
  for (int i = 0; i < mesh.indices_size(); ++i) {
    if (mesh.indices(i) >= vertex_count) {
      return Error(Indexed(indices_field, i),
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

absl::Status SceneBuilder::LoadPath(absl::string_view field, const std::string& path,
                                    std::vector<glm::dvec3>* positions,
                                    std::vector<uint32_t>* indices) const {
  if (base_dir_.empty()) {
    return Error(field, "mesh files are not accepted here; send inline geometry");
  }
  if (path.empty()) return Error(field, "must not be empty");
  absl::StatusOr<MeshFileData> data =
      LoadMeshFile(ResolveAgainst(base_dir_, path), absl::StrCat(source_, ": ", field));
  if (!data.ok()) return data.status();
  *positions = std::move(data->positions);
  *indices = std::move(data->indices);
  return absl::OkStatus();
}

absl::Status SceneBuilder::LoadAsset(absl::string_view field, const std::string& sha256,
                                     std::vector<glm::dvec3>* positions,
                                     std::vector<uint32_t>* indices) const {
  if (assets_ == nullptr) {
    return Error(field, "mesh assets are only accepted by the coordinator; use path or inline");
  }
  if (!IsSha256Hex(sha256)) {
    constexpr size_t kShown = 80;  // the hash comes from a client: cut it short
    return Error(field, absl::StrCat("must be a SHA-256, 64 lowercase hex digits (got \"",
                                     absl::CEscape(sha256.substr(0, kShown)),
                                     sha256.size() > kShown ? "..." : "", "\")"));
  }
  absl::StatusOr<MeshFileData> data = (*assets_)(sha256, absl::StrCat(source_, ": ", field));
  if (!data.ok()) return data.status();
  *positions = std::move(data->positions);
  *indices = std::move(data->indices);
  return absl::OkStatus();
}

absl::StatusOr<TriangleMesh> SceneBuilder::BuildMesh(int index,
                                                     const pdsm::v1::Mesh& mesh) const {
  const std::string field = Indexed("meshes", index);
  TriangleMesh out;
  switch (mesh.role()) {
    case pdsm::v1::CASTER_AND_RECEIVER: out.role = MeshRole::kCasterAndReceiver; break;
    case pdsm::v1::CASTER_ONLY: out.role = MeshRole::kCasterOnly; break;
    case pdsm::v1::RECEIVER_ONLY: out.role = MeshRole::kReceiverOnly; break;
    default:
      return Error(field + ".role", absl::StrCat("unknown value (got ", mesh.role(), ")"));
  }
  absl::StatusOr<Transform> transform = BuildTransform(field + ".transform", mesh.transform());
  if (!transform.ok()) return transform.status();

  std::vector<glm::dvec3> positions_model;
  absl::Status loaded;
  switch (mesh.source_case()) {
    case pdsm::v1::Mesh::kPath:
      out.label = absl::StrCat(field, " (", mesh.path(), ")");
      loaded = LoadPath(field + ".path", mesh.path(), &positions_model, &out.indices);
      break;
    case pdsm::v1::Mesh::kInline:
      out.label = absl::StrCat(field, " (inline)");
      loaded = LoadInline(field + ".inline", mesh.inline_(), &positions_model, &out.indices);
      break;
    case pdsm::v1::Mesh::kAssetSha256:
      out.label = absl::StrCat(field, " (asset ", mesh.asset_sha256().substr(0, 12), ")");
      loaded = LoadAsset(field + ".assetSha256", mesh.asset_sha256(), &positions_model,
                         &out.indices);
      break;
    case pdsm::v1::Mesh::SOURCE_NOT_SET:
      return Error(field, "one of path, inline, assetSha256 is required");
  }
  if (!loaded.ok()) return loaded;

  // World positions in double, in a fixed order of operations, so a world far from the origin
  // keeps its precision and every build computes the same bits.
  const Transform& m = *transform;
  out.positions_world.reserve(positions_model.size());
  for (const glm::dvec3& p : positions_model) {
    out.positions_world.emplace_back(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3],
                                     m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                                     m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
  }
  for (size_t v = 0; v < out.positions_world.size(); ++v) {
    const glm::dvec3& p = out.positions_world[v];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      return Error(field + ".transform",
                   absl::StrCat("moves vertex ", v, " out of the finite range"));
    }
  }
  return out;
}

// ---- Light -----------------------------------------------------------------------------

absl::StatusOr<LightSpec> SceneBuilder::BuildRect(const pdsm::v1::RectLight& rect) const {
  absl::StatusOr<glm::dvec3> center = Vec3("light.rect.center", rect.center());
  if (!center.ok()) return center.status();
  absl::StatusOr<glm::dvec3> normal = Direction("light.rect.normal", rect.normal());
  if (!normal.ok()) return normal.status();
  absl::StatusOr<glm::dvec3> up = Direction("light.rect.up", rect.up());
  if (!up.ok()) return up.status();
  // sin(angle between up and normal); below this v would be mostly rounding noise.
  if (glm::length(*up - glm::dot(*up, *normal) * *normal) < 1e-6) {
    return Error("light.rect.up", absl::StrCat("must not be parallel to light.rect.normal (got ",
                                               FormatDoubles(rect.up()), ")"));
  }
  if (rect.size_size() != 2) {
    return Error("light.rect.size",
                 absl::StrCat("must have 2 numbers [width, height] (got ", rect.size_size(),
                              ")"));
  }
  for (int i = 0; i < 2; ++i) {
    if (absl::Status s = CheckPositive(Indexed("light.rect.size", i), rect.size(i)); !s.ok()) {
      return s;
    }
  }
  LightSpec light;
  light.shape = LightShape::kRect;
  light.frame = MakeLightFrame(*center, *normal, &*up);
  light.half_width = 0.5 * rect.size(0);
  light.half_height = 0.5 * rect.size(1);
  return light;
}

absl::StatusOr<LightSpec> SceneBuilder::BuildDisk(const pdsm::v1::DiskLight& disk) const {
  absl::StatusOr<glm::dvec3> center = Vec3("light.disk.center", disk.center());
  if (!center.ok()) return center.status();
  absl::StatusOr<glm::dvec3> normal = Direction("light.disk.normal", disk.normal());
  if (!normal.ok()) return normal.status();
  if (absl::Status s = CheckPositive("light.disk.radius", disk.radius()); !s.ok()) return s;
  LightSpec light;
  light.shape = LightShape::kDisk;
  light.frame = MakeLightFrame(*center, *normal, nullptr);
  light.radius = disk.radius();
  return light;
}

absl::StatusOr<LightSpec> SceneBuilder::BuildSun(const pdsm::v1::SunLight& sun) const {
  absl::StatusOr<glm::dvec3> direction = Direction("light.sun.direction", sun.direction());
  if (!direction.ok()) return direction.status();
  const double degrees = sun.angular_diameter_deg();
  const char* field = "light.sun.angularDiameterDeg";
  if (absl::Status s = CheckFinite(field, degrees); !s.ok()) return s;
  if (!(degrees > 0 && degrees < 90)) {
    return Error(field, absl::StrCat("must be in (0, 90) degrees (got ", FormatDouble(degrees),
                                     ")"));
  }
  LightSpec light;
  light.shape = LightShape::kSun;
  // The centre stays at the origin: the bake plan places the sun's plane in front of the scene.
  light.frame = MakeLightFrame(glm::dvec3(0.0), *direction, nullptr);
  light.tan_half_angle = std::tan(0.5 * degrees * (std::numbers::pi / 180.0));
  return light;
}

absl::StatusOr<LightSpec> SceneBuilder::BuildLight(const pdsm::v1::Light& light) const {
  switch (light.shape_case()) {
    case pdsm::v1::Light::kRect: return BuildRect(light.rect());
    case pdsm::v1::Light::kDisk: return BuildDisk(light.disk());
    case pdsm::v1::Light::kSun: return BuildSun(light.sun());
    case pdsm::v1::Light::SHAPE_NOT_SET: break;
  }
  return Error("light", "one of rect, disk, sun is required");
}

// ---- Bake settings ---------------------------------------------------------------------

absl::Status SceneBuilder::CheckUintRange(absl::string_view field, uint32_t value,
                                          int max) const {
  if (value >= 1 && value <= static_cast<uint32_t>(max)) return absl::OkStatus();
  return Error(field, absl::StrCat("must be in [1, ", max, "] (got ", value, ")"));
}

absl::StatusOr<FrustumOverride> SceneBuilder::BuildFrustum(const pdsm::v1::Frustum& frustum,
                                                           LightShape shape) const {
  const std::string window_field = "bake.frustum.window";
  const std::string depth_field = "bake.frustum.depthRange";
  if (frustum.window_size() != 4) {
    return Error(window_field,
                 absl::StrCat("must have 4 numbers [sMin, sMax, tMin, tMax] (got ",
                              frustum.window_size(), ")"));
  }
  if (absl::Status s = CheckAllFinite(window_field, frustum.window()); !s.ok()) return s;
  if (frustum.depth_range_size() != 2) {
    return Error(depth_field, absl::StrCat("must have 2 numbers [near, far] (got ",
                                           frustum.depth_range_size(), ")"));
  }
  if (absl::Status s = CheckAllFinite(depth_field, frustum.depth_range()); !s.ok()) return s;
  FrustumOverride out{frustum.window(0),      frustum.window(1),     frustum.window(2),
                      frustum.window(3),      frustum.depth_range(0), frustum.depth_range(1)};
  if (!(out.s_min < out.s_max && out.t_min < out.t_max)) {
    return Error(window_field, absl::StrCat("needs sMin < sMax and tMin < tMax (got ",
                                            FormatDoubles(frustum.window()), ")"));
  }
  // A perspective PDSM divides by depth, so its range must lie in front of the light; the
  // sun's orthographic one may start behind the plane the plan puts it on.
  if (shape != LightShape::kSun && !(out.z_near > 0)) {
    return Error(depth_field, absl::StrCat("needs 0 < near < far (got ",
                                           FormatDoubles(frustum.depth_range()), ")"));
  }
  if (!(out.z_near < out.z_far)) {
    return Error(depth_field, absl::StrCat("needs near < far (got ",
                                           FormatDoubles(frustum.depth_range()), ")"));
  }
  return out;
}

absl::StatusOr<BakeSettings> SceneBuilder::BuildBake(const pdsm::v1::BakeParams& bake,
                                                     LightShape shape) const {
  BakeSettings out;
  if (!bake.resolution().empty()) {
    if (bake.resolution_size() != 2) {
      return Error("bake.resolution",
                   absl::StrCat("must have 2 numbers [width, height] (got ",
                                bake.resolution_size(), ")"));
    }
    for (int i = 0; i < 2; ++i) {
      if (absl::Status s = CheckUintRange(Indexed("bake.resolution", i), bake.resolution(i),
                                          kMaxPdsmResolution);
          !s.ok()) {
        return s;
      }
    }
    out.width = static_cast<int>(bake.resolution(0));
    out.height = static_cast<int>(bake.resolution(1));
  }
  if (bake.has_samples()) {
    if (absl::Status s = CheckUintRange("bake.samples", bake.samples(), kMaxSamples); !s.ok()) {
      return s;
    }
    out.samples = static_cast<int>(bake.samples());
  }
  if (bake.has_shadow_map_resolution()) {
    if (absl::Status s = CheckUintRange("bake.shadowMapResolution",
                                        bake.shadow_map_resolution(), kMaxShadowMapResolution);
        !s.ok()) {
      return s;
    }
    out.shadow_map_resolution = static_cast<int>(bake.shadow_map_resolution());
  }
  if (bake.has_tile_size()) {
    if (absl::Status s = CheckUintRange("bake.tileSize", bake.tile_size(), kMaxTileSize);
        !s.ok()) {
      return s;
    }
    out.tile_size = static_cast<int>(bake.tile_size());
  }
  if (bake.has_epsilon()) {
    const char* field = "bake.epsilon";
    if (absl::Status s = CheckFinite(field, bake.epsilon()); !s.ok()) return s;
    if (!(bake.epsilon() >= 0 && bake.epsilon() <= 1)) {
      return Error(field, absl::StrCat("must be in [0, 1] (got ", FormatDouble(bake.epsilon()),
                                       ")"));
    }
    out.epsilon = bake.epsilon();
  }
  for (const auto& [name, has, value] :
       {std::tuple("bake.depthBias", bake.has_depth_bias(), bake.depth_bias()),
        std::tuple("bake.slopeBias", bake.has_slope_bias(), bake.slope_bias())}) {
    if (!has) continue;
    if (absl::Status s = CheckFinite(name, value); !s.ok()) return s;
    if (!(value >= 0)) {
      return Error(name, absl::StrCat("must be >= 0 (got ", FormatDouble(value), ")"));
    }
  }
  if (bake.has_depth_bias()) out.depth_bias = bake.depth_bias();
  if (bake.has_slope_bias()) out.slope_bias = bake.slope_bias();
  if (bake.has_seed()) out.seed = bake.seed();
  if (bake.has_surfaces_only()) out.surfaces_only = bake.surfaces_only();

  switch (bake.sampling()) {
    case pdsm::v1::SAMPLING_DEFAULT:
    case pdsm::v1::STRATIFIED: out.sampling = SamplingPattern::kStratified; break;
    case pdsm::v1::UNIFORM: out.sampling = SamplingPattern::kUniform; break;
    case pdsm::v1::SOBOL: out.sampling = SamplingPattern::kSobol; break;
    case pdsm::v1::HALTON: out.sampling = SamplingPattern::kHalton; break;
    case pdsm::v1::BLUE_NOISE: out.sampling = SamplingPattern::kBlueNoise; break;
    default:
      return Error("bake.sampling",
                   absl::StrCat("unknown value (got ", bake.sampling(), ")"));
  }
  switch (bake.compression_metric()) {
    case pdsm::v1::COMPRESSION_METRIC_DEFAULT:
    case pdsm::v1::VERTICAL: out.compression_metric = CompressionMetric::kVertical; break;
    case pdsm::v1::PERPENDICULAR: out.compression_metric = CompressionMetric::kPerpendicular; break;
    default:
      return Error("bake.compressionMetric",
                   absl::StrCat("unknown value (got ", bake.compression_metric(), ")"));
  }
  if (bake.has_frustum()) {
    absl::StatusOr<FrustumOverride> frustum = BuildFrustum(bake.frustum(), shape);
    if (!frustum.ok()) return frustum.status();
    out.frustum = *frustum;
  }
  if (absl::Status s = BuildAdaptive(bake, &out); !s.ok()) return s;
  return out;
}

// Adaptive sampling needs a progressive pattern: a tile uses a prefix of the samples.
absl::Status SceneBuilder::BuildAdaptive(const pdsm::v1::BakeParams& bake,
                                         BakeSettings* out) const {
  if (bake.has_adaptive_min_samples()) {
    if (absl::Status s = CheckUintRange("bake.adaptiveMinSamples", bake.adaptive_min_samples(),
                                        kMaxSamples);
        !s.ok()) {
      return s;
    }
    out->adaptive_min_samples = static_cast<int>(bake.adaptive_min_samples());
  }
  if (!bake.has_adaptive_tolerance()) return absl::OkStatus();
  const double tolerance = bake.adaptive_tolerance();
  if (absl::Status s = CheckFinite("bake.adaptiveTolerance", tolerance); !s.ok()) return s;
  if (!(tolerance >= 0 && tolerance <= 1)) {
    return Error("bake.adaptiveTolerance",
                 absl::StrCat("must be in [0, 1] (got ", FormatDouble(tolerance), ")"));
  }
  out->adaptive_tolerance = tolerance;
  if (!out->adaptive()) return absl::OkStatus();
  if (bake.sampling() == pdsm::v1::SAMPLING_DEFAULT) {
    out->sampling = SamplingPattern::kSobol;  // the default pattern of adaptive bakes
  } else if (!IsProgressive(out->sampling)) {
    return Error("bake.sampling",
                 "STRATIFIED cannot be used with bake.adaptiveTolerance: a tile uses the first "
                 "n samples, so the pattern must be progressive (SOBOL, HALTON, BLUE_NOISE, "
                 "UNIFORM)");
  }
  out->adaptive_min_samples = std::min(out->adaptive_min_samples, out->samples);
  return absl::OkStatus();
}

absl::StatusOr<Scene> SceneBuilder::Build(const pdsm::v1::Scene& message) const {
  Scene scene;
  scene.name = message.name();
  scene.source_path = source_;
  // Light and bake first: they are cheap, and a typo there should not wait for a mesh load.
  absl::StatusOr<LightSpec> light = BuildLight(message.light());
  if (!light.ok()) return light.status();
  scene.light = *light;
  absl::StatusOr<BakeSettings> bake = BuildBake(message.bake(), light->shape);
  if (!bake.ok()) return bake.status();
  scene.bake = *bake;
  scene.meshes.reserve(message.meshes_size());
  for (int i = 0; i < message.meshes_size(); ++i) {
    absl::StatusOr<TriangleMesh> mesh = BuildMesh(i, message.meshes(i));
    if (!mesh.ok()) return mesh.status();
    scene.meshes.push_back(*std::move(mesh));
  }
  return scene;
}

// Every field set in `overrides` replaces the scene's (a repeated field as a whole, the
// frustum as a whole). Returns the JSON names of the replaced fields, for messages.
std::set<std::string> ApplyOverrides(const pdsm::v1::BakeParams& overrides,
                                     pdsm::v1::BakeParams* bake) {
  // ListFields gives exactly the "set" fields: present optionals and messages, non-empty
  // repeated fields, non-default proto3 enums.
  std::vector<const google::protobuf::FieldDescriptor*> fields;
  overrides.GetReflection()->ListFields(overrides, &fields);
  std::set<std::string> names;
  for (const google::protobuf::FieldDescriptor* field : fields) {
    bake->GetReflection()->ClearField(bake, field);
    names.insert(field->json_name());
  }
  bake->MergeFrom(overrides);
  return names;
}

// Protobuf reports a syntax error on three lines: the message, the text around the error and
// a caret under it. One line reads better on a terminal and in logs.
std::string OneLineJsonError(absl::string_view message) {
  std::vector<absl::string_view> lines = absl::StrSplit(message, '\n');
  if (lines.size() < 3 || lines[1].empty()) return std::string(lines[0]);
  return absl::StrCat(lines[0], " near \"", absl::CEscape(lines[1]), "\"");
}

absl::StatusOr<std::string> ReadSceneFile(const std::string& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) {
    return absl::NotFoundError(absl::StrCat(path, ": scene file not found"));
  }
  if (status.type() == std::filesystem::file_type::directory) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": is a directory, not a scene file"));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::InvalidArgumentError(absl::StrCat(path, ": cannot open the scene file"));
  std::ostringstream text;
  text << in.rdbuf();  // sets failbit on `text` for an empty file: the JSON parser says so
  if (in.bad()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": cannot read the scene file"));
  }
  return std::move(text).str();
}

// Reads and parses the scene file and applies the overrides. Returns the JSON names of the
// overridden bake fields, for messages.
absl::StatusOr<std::set<std::string>> ParseWithOverrides(const std::string& path,
                                                         const pdsm::v1::BakeParams& overrides,
                                                         pdsm::v1::Scene* message) {
  absl::StatusOr<std::string> text = ReadSceneFile(path);
  if (!text.ok()) return text.status();

  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;  // a misspelt field must not be silently dropped
  const auto parsed = google::protobuf::util::JsonStringToMessage(*text, message, options);
  if (!parsed.ok()) {
    // The parser names no field for a number beyond double's range (1e400): find it.
    if (const std::optional<OutOfRangeNumber> bad = FindOutOfRangeNumber(*text)) {
      return absl::InvalidArgumentError(absl::StrCat(
          path, ": ", bad->field, ": must be finite (got ", bad->literal,
          ", beyond the range of a double)"));
    }
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": invalid scene JSON: ",
                     OneLineJsonError(std::string(parsed.message()))));
  }
  return ApplyOverrides(overrides, message->mutable_bake());
}

}  // namespace

absl::StatusOr<pdsm::v1::Scene> ParseSceneFile(const std::string& path,
                                               const pdsm::v1::BakeParams& overrides) {
  pdsm::v1::Scene message;
  absl::StatusOr<std::set<std::string>> overridden =
      ParseWithOverrides(path, overrides, &message);
  if (!overridden.ok()) return overridden.status();
  return message;
}

std::string ResolveMeshPath(const std::string& scene_path, const std::string& mesh_path) {
  return ResolveAgainst(SceneFolder(scene_path), mesh_path);
}

absl::StatusOr<Scene> LoadSceneFile(const std::string& path,
                                    const pdsm::v1::BakeParams& overrides) {
  pdsm::v1::Scene message;
  absl::StatusOr<std::set<std::string>> overridden =
      ParseWithOverrides(path, overrides, &message);
  if (!overridden.ok()) return overridden.status();
  // No asset resolver: a scene file names meshes by path or inline, never by asset.
  return SceneBuilder(path, SceneFolder(path), *std::move(overridden)).Build(message);
}

absl::StatusOr<Scene> SceneFromProto(const pdsm::v1::Scene& message,
                                     const std::string& source_label,
                                     const std::string& base_dir,
                                     const MeshAssetResolver& assets) {
  return SceneBuilder(source_label, base_dir, {}, &assets).Build(message);
}

}  // namespace pdsm
