#include "core/geometry/light_frame.h"

#include <cmath>

namespace pdsm {

LightFrame MakeLightFrame(const glm::dvec3& center, const glm::dvec3& normal,
                          const glm::dvec3* up) {
  LightFrame frame;
  frame.center = center;
  frame.n = glm::normalize(normal);
  if (up != nullptr) {
    const glm::dvec3 up_in_plane = *up - glm::dot(*up, frame.n) * frame.n;
    const double len = glm::length(up_in_plane);
    if (len > 1e-9 * glm::length(*up)) {
      frame.v = up_in_plane / len;
      frame.u = glm::cross(frame.v, frame.n);
      return frame;
    }
  }
  const glm::dvec3& n = frame.n;
  const double sign = std::copysign(1.0, n.z);
  const double a = -1.0 / (sign + n.z);
  const double b = n.x * n.y * a;
  frame.u = {1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x};
  frame.v = glm::cross(frame.n, frame.u);
  return frame;
}

}  // namespace pdsm
