// The light's orthonormal frame and the change of coordinates world <-> light space.
// Light space: origin at the light centre C, x along u, y along v, z along n (into the scene).
// Everything is double and relative to C, so worlds at 1e6 units keep their precision.
#ifndef PDSM_CORE_GEOMETRY_LIGHT_FRAME_H_
#define PDSM_CORE_GEOMETRY_LIGHT_FRAME_H_

#include <glm/glm.hpp>

namespace pdsm {

struct LightFrame {
  glm::dvec3 center{0.0};       // world
  glm::dvec3 u{1.0, 0.0, 0.0};  // world, unit
  glm::dvec3 v{0.0, 1.0, 0.0};  // world, unit
  glm::dvec3 n{0.0, 0.0, 1.0};  // world, unit, u x v = n

  glm::dvec3 LightFromWorld(const glm::dvec3& p_world) const {
    const glm::dvec3 d = p_world - center;
    return {glm::dot(d, u), glm::dot(d, v), glm::dot(d, n)};
  }
  glm::dvec3 WorldFromLight(const glm::dvec3& p_light) const {
    return center + p_light.x * u + p_light.y * v + p_light.z * n;
  }
};

// A right-handed frame with the given normal; `up` fixes v when given and not parallel to n,
// else a stable basis is chosen (Duff et al., "Building an Orthonormal Basis, Revisited").
// REQUIRES: normal and up finite, |normal| > 0.
LightFrame MakeLightFrame(const glm::dvec3& center, const glm::dvec3& normal, const glm::dvec3* up);

}  // namespace pdsm

#endif  // PDSM_CORE_GEOMETRY_LIGHT_FRAME_H_
