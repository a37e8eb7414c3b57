// Where the PDSM's pixels are: the light frame, the projection and the window. This is all
// that evaluating a PDSM needs besides its functions, so it is stored in the file header.
//
// Perspective (rect and disk lights): pixel (i, j) is the ray from the light centre with
// light-space direction (s, t, 1), s = s_min + (i + 0.5) * (s_max - s_min) / width, same for t
// with j. A light-space point (x, y, z), z > 0, projects to (x / z, y / z).
// Orthographic (sun): pixel (i, j) is the line x = s, y = t, parallel to n.
// In both, depth is light-space z (world units along n, from the light centre).
#ifndef PDSM_CORE_PDSM_PDSM_GEOMETRY_H_
#define PDSM_CORE_PDSM_PDSM_GEOMETRY_H_

#include <optional>

#include <glm/glm.hpp>

#include "core/geometry/light_frame.h"

namespace pdsm {

enum class Projection { kPerspective, kOrthographic };

// A point located in the PDSM: continuous pixel coordinates (pixel centres at k + 0.5) and
// light-space depth.
struct PdsmPoint {
  double px;
  double py;
  double z;
};

struct PdsmGeometry {
  Projection projection = Projection::kPerspective;
  LightFrame frame;
  int width = 0;
  int height = 0;
  double s_min = -1, s_max = 1, t_min = -1, t_max = 1;  // the window
  double z_near = 0, z_far = 0;  // depth range holding casters (near) and any geometry (far)
  // Points nearer than this are outside what the PDSM resolves (a caster lies nearer than the
  // bake's scan floor, docs/algorithms.md): Locate refuses them. 0: no limit.
  double z_valid_min = 0;

  double PixelPitchS() const { return (s_max - s_min) / width; }
  double PixelPitchT() const { return (t_max - t_min) / height; }
  double PixelCenterS(int i) const { return s_min + (i + 0.5) * PixelPitchS(); }
  double PixelCenterT(int j) const { return t_min + (j + 0.5) * PixelPitchT(); }

  // Window coordinates (s, t) of a light-space point; nullopt when it has no projection
  // (perspective and z <= 0).
  std::optional<glm::dvec2> WindowFromLight(const glm::dvec3& p_light) const {
    if (projection == Projection::kOrthographic) return glm::dvec2(p_light.x, p_light.y);
    if (!(p_light.z > 0.0)) return std::nullopt;
    return glm::dvec2(p_light.x / p_light.z, p_light.y / p_light.z);
  }

  // The point in pixel coordinates; nullopt outside the frustum (behind the light, outside
  // the window, or nearer than z_valid_min).
  std::optional<PdsmPoint> Locate(const glm::dvec3& p_world) const {
    const glm::dvec3 p_light = frame.LightFromWorld(p_world);
    const auto st = WindowFromLight(p_light);
    if (!st) return std::nullopt;
    // Written so that a NaN (a non-finite query point) is outside too.
    if (!(st->x >= s_min && st->x <= s_max && st->y >= t_min && st->y <= t_max)) {
      return std::nullopt;
    }
    if (!(p_light.z >= z_valid_min)) return std::nullopt;
    return PdsmPoint{(st->x - s_min) / PixelPitchS(), (st->y - t_min) / PixelPitchT(), p_light.z};
  }
};

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_PDSM_GEOMETRY_H_
