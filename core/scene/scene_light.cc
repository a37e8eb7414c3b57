#include "core/scene/scene_light.h"

#include <cmath>
#include <numbers>

#include <glm/glm.hpp>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/geometry/light_frame.h"
#include "core/scene/sphere_faces.h"

namespace pdsm::internal {
namespace {

absl::StatusOr<LightSpec> BuildRect(const FieldChecker& checks, const pdsm::v1::RectLight& rect) {
  absl::StatusOr<glm::dvec3> center = checks.Vec3("light.rect.center", rect.center());
  if (!center.ok()) return center.status();
  absl::StatusOr<glm::dvec3> normal = checks.Direction("light.rect.normal", rect.normal());
  if (!normal.ok()) return normal.status();
  absl::StatusOr<glm::dvec3> up = checks.Direction("light.rect.up", rect.up());
  if (!up.ok()) return up.status();
  // sin(angle between up and normal); below this v would be mostly rounding noise.
  if (glm::length(*up - glm::dot(*up, *normal) * *normal) < 1e-6) {
    return checks.Error("light.rect.up",
                        absl::StrCat("must not be parallel to light.rect.normal (got ",
                                     FormatDoubles(rect.up()), ")"));
  }
  if (rect.size_size() != 2) {
    return checks.Error("light.rect.size", absl::StrCat("must have 2 numbers [width, height] (got ",
                                                        rect.size_size(), ")"));
  }
  for (int i = 0; i < 2; ++i) {
    if (absl::Status s = checks.CheckPositive(Indexed("light.rect.size", i), rect.size(i));
        !s.ok()) {
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

absl::StatusOr<LightSpec> BuildDisk(const FieldChecker& checks, const pdsm::v1::DiskLight& disk) {
  absl::StatusOr<glm::dvec3> center = checks.Vec3("light.disk.center", disk.center());
  if (!center.ok()) return center.status();
  absl::StatusOr<glm::dvec3> normal = checks.Direction("light.disk.normal", disk.normal());
  if (!normal.ok()) return normal.status();
  if (absl::Status s = checks.CheckPositive("light.disk.radius", disk.radius()); !s.ok()) {
    return s;
  }
  LightSpec light;
  light.shape = LightShape::kDisk;
  light.frame = MakeLightFrame(*center, *normal, nullptr);
  light.radius = disk.radius();
  return light;
}

absl::StatusOr<LightSpec> BuildSpot(const FieldChecker& checks, const pdsm::v1::SpotLight& spot) {
  pdsm::v1::DiskLight disk;
  *disk.mutable_center() = spot.center();
  *disk.mutable_normal() = spot.normal();
  disk.set_radius(spot.radius());
  // The disk's checks, its fields spelt as the spot's.
  absl::StatusOr<LightSpec> light = BuildDisk(checks.Renamed("light.disk", "light.spot"), disk);
  if (!light.ok()) return light.status();
  const double degrees = spot.cone_half_angle_deg();
  const char* field = "light.spot.coneHalfAngleDeg";
  if (absl::Status s = checks.CheckFinite(field, degrees); !s.ok()) return s;
  if (!(degrees > 0 && degrees <= kMaxConeHalfAngleDeg)) {
    return checks.Error(field, absl::StrCat("must be in (0, ", kMaxConeHalfAngleDeg,
                                            "] degrees (got ", FormatDouble(degrees), ")"));
  }
  light->cone_half_angle_deg = degrees;
  return light;
}

absl::StatusOr<LightSpec> BuildSun(const FieldChecker& checks, const pdsm::v1::SunLight& sun) {
  absl::StatusOr<glm::dvec3> direction = checks.Direction("light.sun.direction", sun.direction());
  if (!direction.ok()) return direction.status();
  const double degrees = sun.angular_diameter_deg();
  const char* field = "light.sun.angularDiameterDeg";
  if (absl::Status s = checks.CheckFinite(field, degrees); !s.ok()) return s;
  if (!(degrees > 0 && degrees < 90)) {
    return checks.Error(
        field, absl::StrCat("must be in (0, 90) degrees (got ", FormatDouble(degrees), ")"));
  }
  LightSpec light;
  light.shape = LightShape::kSun;
  // The centre stays at the origin: the bake plan places the sun's plane in front of the scene.
  light.frame = MakeLightFrame(glm::dvec3(0.0), *direction, nullptr);
  light.tan_half_angle = std::tan(0.5 * degrees * (std::numbers::pi / 180.0));
  return light;
}

}  // namespace

absl::StatusOr<std::vector<LightSpec>> BuildSphereFaces(const FieldChecker& checks,
                                                        const pdsm::v1::SphereLight& sphere) {
  absl::StatusOr<glm::dvec3> center = checks.Vec3("light.sphere.center", sphere.center());
  if (!center.ok()) return center.status();
  if (absl::Status s = checks.CheckPositive("light.sphere.radius", sphere.radius()); !s.ok()) {
    return s;
  }
  std::vector<LightSpec> faces;
  for (const SphereFace& face : SphereFaces()) {
    faces.push_back(SphereFaceLight(*center, sphere.radius(), face));
  }
  return faces;
}

absl::StatusOr<LightSpec> BuildLight(const FieldChecker& checks, const pdsm::v1::Light& light) {
  switch (light.shape_case()) {
    case pdsm::v1::Light::kRect:
      return BuildRect(checks, light.rect());
    case pdsm::v1::Light::kDisk:
      return BuildDisk(checks, light.disk());
    case pdsm::v1::Light::kSun:
      return BuildSun(checks, light.sun());
    case pdsm::v1::Light::kSpot:
      return BuildSpot(checks, light.spot());
    case pdsm::v1::Light::kSphere:
      break;  // several lights: BuildSphereFaces
    case pdsm::v1::Light::SHAPE_NOT_SET:
      break;
  }
  return checks.Error("light", "one of rect, disk, spot, sphere, sun is required");
}

}  // namespace pdsm::internal
