#include "core/scene/file_lights.h"

#include <cmath>
#include <set>
#include <utility>

#include <glm/glm.hpp>

#include "absl/strings/str_cat.h"
#include "core/scene/scene_loader.h"
#include "core/scene/world_file.h"

namespace pdsm::internal {
namespace {

using Doubles = google::protobuf::RepeatedField<double>;

// The entry's transform (row-major, column vectors), identity when absent.
struct Placement {
  glm::dmat3 linear{1.0};  // glm is column-major: linear[col][row]
  glm::dvec3 translation{0.0};
  double scale = 1;  // cube root of |det linear|: what a size is multiplied by
};

Placement PlacementOf(const pdsm::v1::Mesh& mesh) {
  Placement p;
  if (mesh.transform_size() != 16) return p;
  const Doubles& m = mesh.transform();
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) p.linear[col][row] = m[4 * row + col];
    p.translation[row] = m[4 * row + 3];
  }
  p.scale = std::cbrt(std::abs(glm::determinant(p.linear)));
  return p;
}

glm::dvec3 Get(const Doubles& v) {
  return v.size() == 3 ? glm::dvec3(v[0], v[1], v[2]) : glm::dvec3(0.0);
}

void Set(const glm::dvec3& v, Doubles* out) {
  out->Clear();
  out->Add(v.x);
  out->Add(v.y);
  out->Add(v.z);
}

void MovePoint(const Placement& p, Doubles* v) {
  if (v->size() == 3) Set(p.linear * Get(*v) + p.translation, v);
}

void TurnDirection(const Placement& p, Doubles* v) {
  if (v->size() != 3) return;
  const glm::dvec3 d = p.linear * Get(*v);
  const double length = glm::length(d);
  if (length > 0) Set(d / length, v);
}

void Place(const Placement& p, pdsm::v1::Light* light) {
  switch (light->shape_case()) {
    case pdsm::v1::Light::kRect: {
      pdsm::v1::RectLight* rect = light->mutable_rect();
      MovePoint(p, rect->mutable_center());
      TurnDirection(p, rect->mutable_normal());
      TurnDirection(p, rect->mutable_up());
      for (double& size : *rect->mutable_size()) size *= p.scale;
      break;
    }
    case pdsm::v1::Light::kDisk:
      MovePoint(p, light->mutable_disk()->mutable_center());
      TurnDirection(p, light->mutable_disk()->mutable_normal());
      light->mutable_disk()->set_radius(light->disk().radius() * p.scale);
      break;
    case pdsm::v1::Light::kSpot:
      MovePoint(p, light->mutable_spot()->mutable_center());
      TurnDirection(p, light->mutable_spot()->mutable_normal());
      light->mutable_spot()->set_radius(light->spot().radius() * p.scale);
      break;
    case pdsm::v1::Light::kSphere:
      MovePoint(p, light->mutable_sphere()->mutable_center());
      light->mutable_sphere()->set_radius(light->sphere().radius() * p.scale);
      break;
    case pdsm::v1::Light::kSun:
      TurnDirection(p, light->mutable_sun()->mutable_direction());
      break;
    case pdsm::v1::Light::SHAPE_NOT_SET:
      break;
  }
}

}  // namespace

absl::Status AddLightsFromMeshFiles(const std::string& scene_path, pdsm::v1::Scene* message,
                                    std::vector<std::string>* warnings) {
  std::vector<pdsm::v1::Light> added;
  for (int i = 0; i < message->meshes_size(); ++i) {
    pdsm::v1::Mesh& mesh = *message->mutable_meshes(i);
    if (mesh.lights_from().empty()) continue;
    const std::string field = absl::StrCat(scene_path, ": meshes[", i, "].lightsFrom: ");
    if (mesh.lights_from() != "file") {
      return absl::InvalidArgumentError(
          absl::StrCat(field, "must be \"file\" or absent (got \"", mesh.lights_from(), "\")"));
    }
    if (mesh.source_case() != pdsm::v1::Mesh::kPath) {
      return absl::InvalidArgumentError(
          absl::StrCat(field, "needs the mesh's `path`: only a file holds lights"));
    }
    absl::StatusOr<pdsm::v1::Scene> world =
        ReadWorldFile(ResolveMeshPath(scene_path, mesh.path()), warnings);
    if (!world.ok()) {
      return absl::InvalidArgumentError(absl::StrCat(field, world.status().message()));
    }
    const Placement placement = PlacementOf(mesh);
    for (pdsm::v1::Light& light : *world->mutable_lights()) {
      Place(placement, &light);
      added.push_back(std::move(light));
    }
    mesh.clear_lights_from();
  }
  if (added.empty()) return absl::OkStatus();
  if (message->has_light() && message->lights_size() == 0) {
    pdsm::v1::Light first = message->light();
    if (first.name().empty()) first.set_name("light");
    message->clear_light();
    *message->add_lights() = std::move(first);
  }
  std::set<std::string> used;
  for (const pdsm::v1::Light& light : message->lights()) used.insert(light.name());
  for (pdsm::v1::Light& light : added) {
    const std::string base = light.name();
    for (int k = 2; used.count(light.name()) > 0; ++k) light.set_name(absl::StrCat(base, "-", k));
    used.insert(light.name());
    *message->add_lights() = std::move(light);
  }
  return absl::OkStatus();
}

}  // namespace pdsm::internal
