// Pieces of the scenes the plan's unit tests build in code (core/bake/*_test.cc).
#ifndef PDSM_CORE_BAKE_PLAN_TEST_SCENES_H_
#define PDSM_CORE_BAKE_PLAN_TEST_SCENES_H_

#include "core/scene/scene.h"

namespace pdsm {

// The 20 x 20 ground quad at world y = 0, centred on the origin, receiving only (labelled
// "ground").
inline TriangleMesh GroundQuad() {
  TriangleMesh ground;
  ground.label = "ground";
  ground.role = MeshRole::kReceiverOnly;
  ground.positions_world = {{-10, 0, -10}, {10, 0, -10}, {10, 0, 10}, {-10, 0, 10}};
  ground.indices = {0, 1, 2, 0, 2, 3};
  return ground;
}

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_PLAN_TEST_SCENES_H_
