// A unit box resting on a 4 x 4 receiving plane under a rect light low on its -x side: the
// contact scene of adaptive resolution's tests (issue #15 items 2 and 3). The box casts and
// receives; its lit wall is x = -0.5, and 128^2 pixels, 64 samples, 512^2 shadow maps.
#ifndef PDSM_TESTS_BOX_ON_PLANE_H_
#define PDSM_TESTS_BOX_ON_PLANE_H_

#include <algorithm>
#include <vector>

#include <glm/glm.hpp>

#include "core/pdsm/pdsm_image.h"

namespace pdsm::testing {

inline constexpr char kBoxOnPlaneJson[] = R"({
  "name": "box on plane",
  "meshes": [
    {"inline": {"positions": [-2,0,-2, 2,0,-2, 2,0,2, -2,0,2], "indices": [0,2,1, 0,3,2]},
     "role": "RECEIVER_ONLY"},
    {"inline": {"positions": [-0.5,0,-0.5, 0.5,0,-0.5, 0.5,0,0.5, -0.5,0,0.5,
                              -0.5,1,-0.5, 0.5,1,-0.5, 0.5,1,0.5, -0.5,1,0.5],
                "indices": [0,1,2, 0,2,3, 4,6,5, 4,7,6, 0,4,5, 0,5,1,
                            1,5,6, 1,6,2, 2,6,7, 2,7,3, 3,7,4, 3,4,0]}}
  ],
  "light": {"rect": {"center": [-3,4,0], "normal": [0,-1,0], "up": [0,0,1], "size": [0.5,0.5]}},
  "bake": {"resolution": [128,128], "samples": 64, "shadowMapResolution": 512, "epsilon": 0.005}
})";

// The size of a pixel of a map of `g` on the ground at `p` (the ground is square to the
// light's axis).
inline double BoxGroundPixel(const PdsmGeometry& g, const glm::dvec3& p) {
  return std::max(g.PixelPitchS(), g.PixelPitchT()) * g.frame.LightFromWorld(p).z;
}

// Ground points at distance `d` outside the wall x = side * 0.5 (inside for d < 0), along its
// middle 0.8.
inline std::vector<glm::dvec3> AlongBoxWall(double side, double d) {
  std::vector<glm::dvec3> points;
  for (int k = 0; k < 17; ++k) points.emplace_back(side * (0.5 + d), 0.0, -0.4 + 0.05 * k);
  return points;
}

}  // namespace pdsm::testing

#endif  // PDSM_TESTS_BOX_ON_PLANE_H_
