#include "core/scene/world_file.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <assimp/scene.h>
#include <google/protobuf/util/json_util.h>
#include <assimp/Importer.hpp>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"

namespace pdsm {
namespace {

// The light's node to world: its ancestors' transforms and its own, root first, as
// aiProcess_PreTransformVertices applies them to the meshes.
aiMatrix4x4 WorldFromNode(const aiNode* node) {
  aiMatrix4x4 m;
  for (; node != nullptr; node = node->mParent) m = node->mTransformation * m;
  return m;
}

void SetVec3(const aiVector3D& v, google::protobuf::RepeatedField<double>* out) {
  out->Clear();
  out->Add(v.x);
  out->Add(v.y);
  out->Add(v.z);
}

// A number of the node's extras (Assimp's metadata), if it has one of that name.
std::optional<double> NumberExtra(const aiNode* node, const char* key) {
  if (node == nullptr || node->mMetaData == nullptr) return std::nullopt;
  const aiMetadata& meta = *node->mMetaData;
  for (unsigned i = 0; i < meta.mNumProperties; ++i) {
    if (std::string(meta.mKeys[i].C_Str()) != key) continue;
    const aiMetadataEntry& e = meta.mValues[i];
    switch (e.mType) {
      case AI_BOOL:
        return *static_cast<const bool*>(e.mData) ? 1.0 : 0.0;
      case AI_INT32:
        return *static_cast<const int32_t*>(e.mData);
      case AI_UINT64:
        return static_cast<double>(*static_cast<const uint64_t*>(e.mData));
      case AI_FLOAT:
        return *static_cast<const float*>(e.mData);
      case AI_DOUBLE:
        return *static_cast<const double*>(e.mData);
      default:
        return std::nullopt;
    }
  }
  return std::nullopt;
}

// The light node's extras that are bake fields, as a BakeParams.
absl::StatusOr<pdsm::v1::BakeParams> BakeExtras(const aiNode* node, const std::string& label) {
  static const char* const kFields[] = {
      "samples",  "shadowMapResolution", "epsilon",           "depthBias",
      "tileSize", "adaptiveTolerance",   "adaptiveMinSamples"};
  std::vector<std::string> members;
  for (const char* field : kFields) {
    if (const std::optional<double> v = NumberExtra(node, field)) {
      if (!std::isfinite(*v)) {
        return absl::InvalidArgumentError(absl::StrCat(label, ".", field, ": must be finite"));
      }
      members.push_back(absl::StrCat("\"", field, "\": ", *v));
    }
  }
  pdsm::v1::BakeParams bake;
  if (members.empty()) return bake;
  const std::string json = absl::StrCat("{", absl::StrJoin(members, ", "), "}");
  if (const auto parsed = google::protobuf::util::JsonStringToMessage(json, &bake); !parsed.ok()) {
    return absl::InvalidArgumentError(
        absl::StrCat(label, ": not valid bake fields: ", std::string(parsed.message())));
  }
  return bake;
}

// `name` made a valid, unused Light.name.
std::string LightName(const std::string& name, std::set<std::string>* used) {
  std::string base;
  for (char c : name.substr(0, 56)) {
    base +=
        std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-' ? c : '_';
  }
  if (base.empty()) base = "light";
  std::string out = base;
  for (int k = 2; !used->insert(out).second; ++k) out = absl::StrCat(base, "-", k);
  return out;
}

}  // namespace

bool IsWorldFile(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".gltf" || ext == ".glb" || ext == ".fbx" || ext == ".obj" || ext == ".dae";
}

absl::StatusOr<pdsm::v1::Scene> ReadWorldFile(const std::string& path,
                                              std::vector<std::string>* warnings) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return absl::NotFoundError(absl::StrCat(path, ": world file not found"));
  }
  Assimp::Importer importer;
  const aiScene* world = importer.ReadFile(path, 0);
  if (world == nullptr) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": cannot read the world file: ", importer.GetErrorString()));
  }
  pdsm::v1::Scene scene;
  scene.set_name(std::filesystem::path(path).stem().string());
  scene.add_meshes()->set_path(std::filesystem::path(path).filename().string());

  std::set<std::string> used;
  std::map<std::string, std::vector<std::string>> left_out;  // kind -> light names
  for (unsigned i = 0; i < world->mNumLights; ++i) {
    const aiLight& l = *world->mLights[i];
    const std::string source_name = l.mName.C_Str();
    const aiNode* node = world->mRootNode->FindNode(l.mName);
    const aiMatrix4x4 to_world = node != nullptr ? WorldFromNode(node) : aiMatrix4x4();
    const aiMatrix3x3 linear(to_world);
    const aiVector3D center = to_world * l.mPosition;
    aiVector3D direction = linear * l.mDirection;
    aiVector3D up = linear * l.mUp;
    if (direction.Length() > 0) direction.Normalize();
    if (up.Length() > 0) up.Normalize();
    const std::string label = absl::StrCat(path, ": light \"", source_name, "\"");

    pdsm::v1::Light light;
    switch (l.mType) {
      case aiLightSource_DIRECTIONAL: {
        pdsm::v1::SunLight* sun = light.mutable_sun();
        SetVec3(direction, sun->mutable_direction());
        sun->set_angular_diameter_deg(
            NumberExtra(node, "angularDiameterDeg").value_or(kDefaultSunDiameterDeg));
        break;
      }
      case aiLightSource_SPOT: {
        pdsm::v1::SpotLight* spot = light.mutable_spot();
        SetVec3(center, spot->mutable_center());
        SetVec3(direction, spot->mutable_normal());
        spot->set_radius(NumberExtra(node, "radius").value_or(kDefaultPunctualRadius));
        spot->set_cone_half_angle_deg(l.mAngleOuterCone * 180 / std::numbers::pi);
        break;
      }
      case aiLightSource_AREA: {
        pdsm::v1::RectLight* rect = light.mutable_rect();
        SetVec3(center, rect->mutable_center());
        SetVec3(direction, rect->mutable_normal());
        SetVec3(up, rect->mutable_up());
        rect->add_size(l.mSize.x);
        rect->add_size(l.mSize.y);
        break;
      }
      case aiLightSource_POINT: {
        pdsm::v1::SphereLight* sphere = light.mutable_sphere();
        SetVec3(center, sphere->mutable_center());
        sphere->set_radius(NumberExtra(node, "radius").value_or(kDefaultPunctualRadius));
        break;
      }
      default:
        left_out["ambient and other lights (they cast no shadow pdsm can bake)"].push_back(
            source_name);
        continue;
    }
    absl::StatusOr<pdsm::v1::BakeParams> bake = BakeExtras(node, label + " extras");
    if (!bake.ok()) return bake.status();
    if (bake->ByteSizeLong() > 0) *light.mutable_bake() = *std::move(bake);
    light.set_name(LightName(source_name, &used));
    *scene.add_lights() = std::move(light);
  }
  for (const auto& [kind, names] : left_out) {
    warnings->push_back(
        absl::StrCat(path, ": not baked, ", kind, ": ", absl::StrJoin(names, ", ")));
  }
  if (scene.lights_size() == 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(path,
                     ": no light pdsm can bake (a directional, spot, point or area light; glTF: "
                     "KHR_lights_punctual)",
                     left_out.empty() ? "" : absl::StrCat("; ", absl::StrJoin(*warnings, "; ")),
                     ". Add one to the file, or write a scene JSON that names this file as a mesh "
                     "(docs/scene_format.md)"));
  }
  return scene;
}

}  // namespace pdsm
