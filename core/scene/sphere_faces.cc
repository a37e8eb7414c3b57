#include "core/scene/sphere_faces.h"

namespace pdsm {

const std::array<SphereFace, kSphereFaceCount>& SphereFaces() {
  // u chosen so that each face's frame is right-handed (u x v = n with v = n x u).
  static const std::array<SphereFace, kSphereFaceCount> faces = {{
      {"+x", {1, 0, 0}, {0, 0, -1}},
      {"-x", {-1, 0, 0}, {0, 0, 1}},
      {"+y", {0, 1, 0}, {1, 0, 0}},
      {"-y", {0, -1, 0}, {1, 0, 0}},
      {"+z", {0, 0, 1}, {1, 0, 0}},
      {"-z", {0, 0, -1}, {-1, 0, 0}},
  }};
  return faces;
}

std::string SphereFaceName(std::string_view sphere, const SphereFace& face) {
  std::string name(sphere.empty() ? std::string_view(kDefaultSphereName) : sphere);
  name += kSphereFaceSeparator;
  name += face.label;
  return name;
}

std::string_view SphereOfFace(std::string_view name) {
  const size_t at = name.rfind(kSphereFaceSeparator);
  return at == std::string_view::npos ? std::string_view() : name.substr(0, at);
}

LightSpec SphereFaceLight(const glm::dvec3& center, double radius, const SphereFace& face) {
  LightSpec light;
  light.shape = LightShape::kDisk;
  light.frame.center = center;
  light.frame.n = face.axis;
  light.frame.u = face.u;
  light.frame.v = glm::cross(face.axis, face.u);
  light.radius = radius;
  light.face_tangent = kSphereFaceTangent;
  return light;
}

}  // namespace pdsm
