#include "core/scene/scene.h"

#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/scene/sphere_faces.h"

namespace pdsm {

SceneLight LightOf(const Scene& scene, size_t i) {
  if (i == 0) return SceneLight{scene.light_name, scene.light, scene.bake};
  return scene.more_lights[i - 1];
}

Scene ForLight(const Scene& scene, size_t i) {
  Scene one;
  one.name = scene.name;
  one.source_path = scene.source_path;
  one.meshes = scene.meshes;
  SceneLight light = LightOf(scene, i);
  one.light = light.spec;
  one.bake = light.bake;
  one.light_name = std::move(light.name);
  return one;
}

int FindLight(const Scene& scene, std::string_view name) {
  for (size_t i = 0; i < scene.LightCount(); ++i) {
    const std::string& n = i == 0 ? scene.light_name : scene.more_lights[i - 1].name;
    if (n == name) return static_cast<int>(i);
  }
  return -1;
}

absl::StatusOr<Scene> OneLight(Scene scene, std::string_view light, std::string_view what,
                               std::string_view flag) {
  if (light.empty() && scene.LightCount() == 1) return scene;
  int index = light.empty() ? -1 : FindLight(scene, light);
  // A sphere light (its faces, core/scene/sphere_faces.h), named or the scene's only light: its
  // first face, which bakes that face and whose reference is the whole sphere's.
  const std::string_view sphere = SphereOfFace(scene.light_name);
  if (index < 0 && !sphere.empty() && (light.empty() || light == sphere)) {
    bool only_faces = true;
    for (size_t i = 1; i < scene.LightCount(); ++i) {
      only_faces = only_faces && SphereOfFace(scene.more_lights[i - 1].name) == sphere;
    }
    if (!light.empty() || only_faces) index = 0;
  }
  for (size_t i = 1; index < 0 && !light.empty() && i < scene.LightCount(); ++i) {
    if (SphereOfFace(scene.more_lights[i - 1].name) == light) index = static_cast<int>(i);
  }
  if (index >= 0) return index == 0 && scene.LightCount() == 1 ? scene : ForLight(scene, index);
  std::vector<std::string> names;
  for (size_t i = 0; i < scene.LightCount(); ++i) names.push_back(LightOf(scene, i).name);
  const std::string listed = absl::StrCat("\"", absl::StrJoin(names, "\", \""), "\"");
  if (light.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(
        scene.source_path, ": lights: ", std::string(what),
        " works on one light, and the scene has ", scene.LightCount(), " (", listed, ")",
        flag.empty() ? "" : absl::StrCat("; choose one with ", std::string(flag), " NAME")));
  }
  return absl::InvalidArgumentError(absl::StrCat(
      scene.source_path, ": no light \"", std::string(light), "\" (its lights: ", listed, ")"));
}

}  // namespace pdsm
