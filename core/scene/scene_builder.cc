#include "core/scene/scene_builder.h"

#include <set>
#include <utility>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "core/scene/scene_bake.h"
#include "core/scene/scene_light.h"
#include "core/scene/sphere_faces.h"

namespace pdsm::internal {
namespace {

// Light names become PDSM file part names and command-line arguments: a safe alphabet.
bool IsLightNameChar(char c) {
  return absl::ascii_isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-';
}

absl::Status CheckLightName(const FieldChecker& checks, const std::string& field,
                            const std::string& name, bool required) {
  if (name.empty()) {
    if (!required) return absl::OkStatus();
    return checks.Error(field, "required when the scene has several lights");
  }
  if (name.size() > kMaxLightNameBytes) {
    return checks.Error(
        field, absl::StrCat("at most ", kMaxLightNameBytes, " bytes (got ", name.size(), ")"));
  }
  for (char c : name) {
    if (!IsLightNameChar(c)) {
      return checks.Error(field, absl::StrCat("may hold only letters, digits, '_', '.' and '-' "
                                              "(got \"",
                                              absl::CEscape(name), "\")"));
    }
  }
  return absl::OkStatus();
}

}  // namespace

SceneBuilder::SceneBuilder(std::string source, std::string base_dir,
                           std::set<std::string> overridden, const MeshAssetResolver* assets,
                           std::vector<std::string>* warnings)
    : checks_(std::move(source), std::move(overridden)),
      sources_{std::move(base_dir), assets != nullptr && *assets ? assets : nullptr, warnings} {}

absl::StatusOr<Scene> SceneBuilder::Build(const pdsm::v1::Scene& message) const {
  Scene scene;
  if (message.name().size() > kMaxSceneNameBytes) {
    return checks_.Error("name", absl::StrCat("at most ", kMaxSceneNameBytes, " bytes (got ",
                                              message.name().size(), ")"));
  }
  scene.name = message.name();
  scene.source_path = checks_.source();
  // Lights and bake first: they are cheap, and a typo there should not wait for a mesh load.
  absl::StatusOr<std::vector<SceneLight>> lights = BuildLights(message);
  if (!lights.ok()) return lights.status();
  scene.light = (*lights)[0].spec;
  scene.bake = (*lights)[0].bake;
  scene.light_name = std::move((*lights)[0].name);
  scene.more_lights.assign(std::make_move_iterator(lights->begin() + 1),
                           std::make_move_iterator(lights->end()));
  scene.meshes.reserve(message.meshes_size());
  for (int i = 0; i < message.meshes_size(); ++i) {
    absl::StatusOr<std::vector<TriangleMesh>> parts =
        BuildMesh(checks_, sources_, i, message.meshes(i));
    if (!parts.ok()) return parts.status();
    for (TriangleMesh& part : *parts) scene.meshes.push_back(std::move(part));
  }
  return scene;
}

absl::StatusOr<std::vector<SceneLight>> SceneBuilder::BuildLights(
    const pdsm::v1::Scene& message) const {
  if (message.has_light() && message.lights_size() > 0) {
    return checks_.Error("lights", "give either light (one light) or lights, not both");
  }
  if (message.lights_size() > kMaxLights) {
    return checks_.Error("lights", absl::StrCat("at most ", kMaxLights, " lights (got ",
                                                message.lights_size(), ")"));
  }
  const bool one = message.lights_size() == 0;
  std::vector<SceneLight> lights;
  std::set<std::string> names;
  for (int i = 0; i < (one ? 1 : message.lights_size()); ++i) {
    const pdsm::v1::Light& entry = one ? message.light() : message.lights(i);
    const std::string label = one ? "light" : Indexed("lights", i);
    // The light's checks spell its fields "light.rect.center" and "bake.samples": the user
    // wrote "lights[2].rect.center", and "lights[2].bake.samples" where the light has its own.
    FieldChecker checks = checks_.Renamed("light", label);
    if (absl::Status s =
            CheckLightName(checks, label + ".name", entry.name(), message.lights_size() > 1);
        !s.ok()) {
      return s;
    }
    if (!entry.name().empty() && !names.insert(entry.name()).second) {
      return checks.Error(label + ".name",
                          absl::StrCat("\"", entry.name(), "\" names another light already"));
    }
    // A sphere is several lights, its faces (core/scene/sphere_faces.h); any other shape one.
    std::vector<LightSpec> specs;
    if (entry.has_sphere()) {
      absl::StatusOr<std::vector<LightSpec>> faces = BuildSphereFaces(checks, entry.sphere());
      if (!faces.ok()) return faces.status();
      specs = *std::move(faces);
    } else {
      absl::StatusOr<LightSpec> spec = BuildLight(checks, entry);
      if (!spec.ok()) return spec.status();
      specs.push_back(*spec);
    }
    std::set<std::string> own;  // the bake fields this light sets itself
    const pdsm::v1::BakeParams bake = MergedBakeParams(message.bake(), entry.bake(), &own);
    for (const std::string& field : own) {
      checks = checks.Renamed(absl::StrCat("bake.", field), absl::StrCat(label, ".bake.", field));
    }
    absl::StatusOr<BakeSettings> settings = BuildBake(checks, bake, specs[0].shape);
    if (!settings.ok()) return settings.status();
    if (entry.has_sphere() && settings->frustum.has_value()) {
      return checks.Error("bake.frustum",
                          "not for a sphere light: each of its faces covers its own directions");
    }
    if (!entry.has_sphere()) {
      lights.push_back(SceneLight{entry.name(), specs[0], *settings});
      continue;
    }
    for (size_t f = 0; f < specs.size(); ++f) {
      lights.push_back(
          SceneLight{SphereFaceName(entry.name(), SphereFaces()[f]), specs[f], *settings});
    }
  }
  // Each face of a sphere is a part of the file: the bound is on parts.
  if (lights.size() > static_cast<size_t>(kMaxLights)) {
    return checks_.Error("lights",
                         absl::StrCat("at most ", kMaxLights, " lights, a sphere counting as ",
                                      kSphereFaceCount, " (got ", lights.size(), ")"));
  }
  return lights;
}

}  // namespace pdsm::internal
