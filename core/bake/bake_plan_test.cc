// PlanBake(scene, i) plans light i of a scene of several lights without copying its meshes: the
// plan must be the one of PlanBake(ForLight(scene, i)), which the local bake, the workers and
// the coordinator all relied on before.
#include "core/bake/bake_plan.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/bake/plan_fingerprint.h"
#include "core/bake/plan_test_scenes.h"
#include "core/geometry/light_frame.h"
#include "core/scene/scene.h"

namespace pdsm {
namespace {

Scene ThreeLights() {
  Scene scene;
  scene.name = "three_lights";
  scene.source_path = "three_lights.json";
  TriangleMesh casters;
  casters.role = MeshRole::kCasterOnly;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> xz(-8, 8), y(1, 4), offset(-0.7, 0.7);
  for (int k = 0; k < 200; ++k) {
    const glm::dvec3 centre(xz(rng), y(rng), xz(rng));
    for (int v = 0; v < 3; ++v) {
      casters.positions_world.push_back(centre + glm::dvec3(offset(rng), offset(rng), offset(rng)));
      casters.indices.push_back(static_cast<uint32_t>(casters.positions_world.size() - 1));
    }
  }
  scene.meshes = {GroundQuad(), casters};
  const glm::dvec3 up(0, 0, 1);
  scene.light.shape = LightShape::kSun;
  scene.light.frame = MakeLightFrame({0, 0, 0}, glm::normalize(glm::dvec3(0.2, -1, 0.1)), &up);
  scene.light.tan_half_angle = std::tan(0.3 * 3.14159265358979 / 180);
  scene.light_name = "sun";
  scene.bake.width = scene.bake.height = 64;
  scene.bake.tile_size = 16;
  scene.bake.samples = 8;
  SceneLight lamp{"lamp", {}, scene.bake};
  lamp.spec.shape = LightShape::kDisk;
  lamp.spec.frame = MakeLightFrame({3, 6, -2}, {0, -1, 0}, &up);
  lamp.spec.radius = 0.2;
  lamp.spec.cone_half_angle_deg = 40;
  lamp.bake.samples = 16;
  SceneLight panel{"panel", {}, scene.bake};
  panel.spec.shape = LightShape::kRect;
  panel.spec.frame = MakeLightFrame({-4, 5, 4}, {0, -1, 0}, &up);
  panel.spec.half_width = 0.5;
  panel.spec.half_height = 0.3;
  panel.bake.frustum = FrustumOverride{-1, 1, -1, 1, 0.2, 8};
  scene.more_lights = {lamp, panel};
  return scene;
}

TEST(PlanBake, EachLightIsPlannedAsForLightPlansIt) {
  const Scene scene = ThreeLights();
  for (size_t i = 0; i < scene.LightCount(); ++i) {
    absl::StatusOr<BakePlan> by_index = PlanBake(scene, i);
    absl::StatusOr<BakePlan> copied = PlanBake(ForLight(scene, i));
    ASSERT_TRUE(by_index.ok() && copied.ok()) << by_index.status() << copied.status();
    EXPECT_EQ(PlanFingerprint(*by_index), PlanFingerprint(*copied)) << "light " << i;
    EXPECT_EQ(by_index->header.light_name, LightOf(scene, i).name);
    EXPECT_EQ(by_index->header.samples, LightOf(scene, i).bake.samples);
    EXPECT_EQ(by_index->casters.positions, copied->casters.positions);
    EXPECT_EQ(by_index->casters.indices, copied->casters.indices);
    EXPECT_EQ(by_index->tile_has_casters, copied->tile_has_casters);
    EXPECT_GT(by_index->casters.TriangleCount(), 0u) << "light " << i;
  }
  // The lights differ: the test compares three plans, not one.
  EXPECT_NE(PlanFingerprint(*PlanBake(scene, 1)), PlanFingerprint(*PlanBake(scene, 2)));
}

}  // namespace
}  // namespace pdsm
