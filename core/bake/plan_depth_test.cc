// The planned depth range counts a caster's depth only where it can shadow a point of the
// window (bake_plan.cc, FitTriangle): a ground crossing a sideways light's plane far below the
// light once made the nearest caster 1e-5 away, and its bake 75 times slower.
#include <gtest/gtest.h>

#include <vector>

#include "core/bake/bake_plan.h"
#include "core/scene/scene.h"

namespace pdsm {
namespace {

TriangleMesh Mesh(MeshRole role, std::vector<glm::dvec3> positions) {
  TriangleMesh mesh;
  mesh.label = "mesh";
  mesh.role = role;
  mesh.positions_world = std::move(positions);
  for (uint32_t k = 0; k < mesh.positions_world.size(); ++k) mesh.indices.push_back(k);
  if (mesh.positions_world.size() == 4) mesh.indices = {0, 1, 2, 0, 2, 3};
  return mesh;
}

// A spot of radius 0.2 three units above a 16 x 16 ground that casts, looking along +z with a
// 45-degree cone (|s|, |t| <= 1): its plane, z = 3 in world, cuts the ground.
Scene SidewaysSpot() {
  Scene scene;
  scene.name = "plan_depth_test";
  scene.source_path = "plan_depth_test.json";
  scene.meshes = {
      Mesh(MeshRole::kCasterAndReceiver, {{-8, 0, -8}, {8, 0, -8}, {8, 0, 8}, {-8, 0, 8}})};
  scene.light.shape = LightShape::kDisk;
  scene.light.frame = MakeLightFrame({0, 3, 3}, {0, 0, 1}, nullptr);
  scene.light.radius = 0.2;
  scene.light.cone_half_angle_deg = 45;
  scene.bake.width = scene.bake.height = 64;
  scene.bake.tile_size = 32;
  scene.bake.samples = 4;
  return scene;
}

TEST(PlanDepth, AGroundCrossingTheLightsPlaneOutsideItsConeIsNotItsNearestCaster) {
  absl::StatusOr<BakePlan> plan = PlanBake(SidewaysSpot());
  ASSERT_TRUE(plan.ok()) << plan.status();
  // The ground enters the cone's pyramid, widened by the light's radius, at depth (3 - 0.2) / 1.
  EXPECT_NEAR(plan->geometry().z_near, 2.8, 1e-9);
  EXPECT_EQ(plan->geometry().z_valid_min, 0) << "nothing is nearer than the scan floor";
}

TEST(PlanDepth, CastersThatCanShadowTheWindowStillCount) {
  // In the cone at depth 0.5, and beside it (x = 0.6 > 0.5, the cone's edge there) but within
  // the light's radius of it: a ray from a sample 0.2 off the centre passes there.
  for (const double x : {0.0, 0.6}) {
    Scene scene = SidewaysSpot();
    scene.meshes.push_back(
        Mesh(MeshRole::kCasterOnly, {{x - 0.05, 3, 3.5}, {x + 0.05, 3, 3.5}, {x, 3.05, 3.5}}));
    absl::StatusOr<BakePlan> plan = PlanBake(scene);
    ASSERT_TRUE(plan.ok()) << plan.status();
    EXPECT_NEAR(plan->geometry().z_near, 0.5, 1e-9) << "a caster at x = " << x;
  }
  // Beyond the radius (x = 0.8 > 0.5 + 0.2): it cannot shadow the window.
  Scene scene = SidewaysSpot();
  scene.meshes.push_back(
      Mesh(MeshRole::kCasterOnly, {{0.76, 3, 3.5}, {0.86, 3, 3.5}, {0.8, 3.05, 3.5}}));
  absl::StatusOr<BakePlan> plan = PlanBake(scene);
  ASSERT_TRUE(plan.ok()) << plan.status();
  EXPECT_NEAR(plan->geometry().z_near, 2.8, 1e-9);
}

}  // namespace
}  // namespace pdsm
