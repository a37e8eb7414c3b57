#include "core/bake/receiver_coverage.h"

#include <cmath>

#include <gtest/gtest.h>

#include "core/bake/bake_plan.h"
#include "core/scene/scene_loader.h"

namespace pdsm {
namespace {

// A square floor of side `side` at y = 0, receiving only.
TriangleMesh Floor(double side) {
  TriangleMesh mesh;
  mesh.role = MeshRole::kReceiverOnly;
  const double h = 0.5 * side;
  mesh.positions_world = {{-h, 0, -h}, {h, 0, -h}, {h, 0, h}, {-h, 0, h}};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  return mesh;
}

// A light 3 above the floor's centre, looking down.
LightFrame LightAbove(double height) {
  LightFrame f;
  f.center = {0, height, 0};
  f.u = {1, 0, 0};
  f.v = {0, 0, -1};
  f.n = {0, -1, 0};
  return f;
}

// The case: a light 3 above a 100 x 100 floor, the window clamped at 85 degrees
// (tan 11.43) on both axes, covers a 68.58 x 68.58 square of it.
TEST(ReceiverCoverage, LowLightOverAWideFloorLeavesTheFarFloorOut) {
  Scene scene;
  scene.meshes = {Floor(100)};
  PdsmGeometry g;
  g.frame = LightAbove(3);
  g.s_min = g.t_min = -kMaxWindowTangent;
  g.s_max = g.t_max = kMaxWindowTangent;
  const double covered = 2 * 3 * kMaxWindowTangent / 100;
  EXPECT_NEAR(ReceiverAreaOutsideFrustum(scene, g), 1 - covered * covered, 1e-12);
  // A window holding the whole floor: nothing outside.
  g.s_min = g.t_min = -20;
  g.s_max = g.t_max = 20;
  EXPECT_NEAR(ReceiverAreaOutsideFrustum(scene, g), 0, 1e-12);
}

// Behind a perspective light is outside whatever the window; a caster-only mesh does not count.
TEST(ReceiverCoverage, BehindTheLightIsOutsideAndCastersDoNotCount) {
  Scene scene;
  scene.meshes = {Floor(10)};
  scene.meshes.push_back(Floor(10));
  scene.meshes.back().role = MeshRole::kCasterOnly;
  for (glm::dvec3& p : scene.meshes.back().positions_world) p.y = 5;  // would be behind
  PdsmGeometry g;
  g.frame = LightAbove(3);
  g.s_min = g.t_min = -100;
  g.s_max = g.t_max = 100;
  EXPECT_NEAR(ReceiverAreaOutsideFrustum(scene, g), 0, 1e-12);
  // A light at the floor's centre looking along +x: the half with x < 0 is behind it, and of
  // the other half the sliver x < |z| / 100 (where |t| = |z| / x > 100) is beyond the window:
  // 2 * (integral of z / 100 for z in 0..5) = 0.25 of the 100 units of area.
  g.frame.center = {0, 0, 0};
  g.frame.u = {0, 1, 0};
  g.frame.v = {0, 0, 1};
  g.frame.n = {1, 0, 0};
  EXPECT_NEAR(ReceiverAreaOutsideFrustum(scene, g), 0.5 + 0.25 / 100, 1e-12);
}

// Orthographic (sun): the window in world units; half the floor beyond one side.
TEST(ReceiverCoverage, OrthographicWindowCutsTheFloor) {
  Scene scene;
  scene.meshes = {Floor(10)};
  PdsmGeometry g;
  g.projection = Projection::kOrthographic;
  g.frame = LightAbove(20);
  g.s_min = 0;
  g.s_max = 100;
  g.t_min = -100;
  g.t_max = 100;
  EXPECT_NEAR(ReceiverAreaOutsideFrustum(scene, g), 0.5, 1e-12);
}

// A planned bake fits its window to the receivers: nothing of plates is outside.
TEST(ReceiverCoverage, PlannedPlatesCoverEveryReceiver) {
  absl::StatusOr<Scene> scene =
      LoadSceneFile(std::string(PDSM_SOURCE_DIR) + "/examples/plates/scene.json");
  ASSERT_TRUE(scene.ok()) << scene.status();
  absl::StatusOr<BakePlan> plan = PlanBake(*scene);
  ASSERT_TRUE(plan.ok()) << plan.status();
  EXPECT_LT(ReceiverAreaOutsideFrustum(*scene, plan->header.geometry), 1e-9);
}

}  // namespace
}  // namespace pdsm
