// Ray <-> shadow-map geometry (DESIGN.md): a PDSM ray is a straight segment in every
// sample's shadow map, linear in w = 1/z, and every tile's segments lie in its window.
#include <random>

#include <gtest/gtest.h>

#include "core/bake/bake_plan.h"
#include "core/bake/tile_reach.h"

namespace pdsm {
namespace {

Scene QuadScene(LightShape shape) {
  Scene scene;
  scene.light.shape = shape;
  const glm::dvec3 up(0, 0, 1);
  scene.light.frame = MakeLightFrame({0, 10, 0}, {0.1, -1, 0.05}, &up);
  scene.light.half_width = 1.5;
  scene.light.half_height = 0.7;
  scene.light.tan_half_angle = 0.05;
  TriangleMesh ground;
  ground.positions_world = {{-8, 0, -8}, {8, 0, -8}, {8, 0, 8}, {-8, 0, 8}};
  ground.indices = {0, 1, 2, 0, 2, 3};
  TriangleMesh caster = ground;
  for (auto& p : caster.positions_world) p = p * 0.2 + glm::dvec3(0, 4, 0);
  scene.meshes = {ground, caster};
  scene.bake.width = 40;
  scene.bake.height = 24;
  scene.bake.tile_size = 16;
  scene.bake.samples = 9;
  return scene;
}

TEST(RayGeometry, PerspectiveRayIsLinearInInverseDepth) {
  const BakePlan plan = *PlanBake(QuadScene(LightShape::kRect));
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 1000; ++trial) {
    const double s = -0.5 + u(rng), t = -0.5 + u(rng), z = 2 + 20 * u(rng);
    const glm::dvec2 sample = plan.samples[trial % plan.samples.size()];
    const glm::dvec3 p(s * z, t * z, z);  // light space, on the PDSM ray (s, t)
    const glm::dvec2 in_sm((p.x - sample.x) / z, (p.y - sample.y) / z);
    const RayInShadowMap ray = RayForSample(plan, s, t, sample, plan.geometry().z_near);
    const double f = 1.0 - (1.0 / z) / (1.0 / ray.z_near);  // w runs from 1/z_near to 0
    const glm::dvec2 on_segment = ray.st_near + f * (ray.st_far - ray.st_near);
    ASSERT_NEAR(on_segment.x, in_sm.x, 1e-12);
    ASSERT_NEAR(on_segment.y, in_sm.y, 1e-12);
  }
}

TEST(RayGeometry, SunRayIsLinearInDepth) {
  const BakePlan plan = *PlanBake(QuadScene(LightShape::kSun));
  const PdsmGeometry& g = plan.geometry();
  for (int k = 0; k < static_cast<int>(plan.samples.size()); ++k) {
    const glm::dvec2 sample = plan.samples[k];
    const RayInShadowMap ray = RayForSample(plan, 0.3, -0.2, sample, g.z_near);
    for (double f : {0.0, 0.25, 0.5, 1.0}) {
      const double z = g.z_near + f * (ray.z_far - g.z_near);
      const glm::dvec2 in_sm(0.3 - sample.x * z, -0.2 - sample.y * z);
      const glm::dvec2 on_segment = ray.st_near + f * (ray.st_far - ray.st_near);
      ASSERT_NEAR(glm::length(on_segment - in_sm), 0.0, 1e-12);
    }
  }
}

TEST(RayGeometry, TileWindowsHoldEveryRaySegment) {
  for (LightShape shape : {LightShape::kRect, LightShape::kSun}) {
    const BakePlan plan = *PlanBake(QuadScene(shape));
    const PdsmGeometry& g = plan.geometry();
    for (const TileRect& tile : plan.tiles) {
      const TileReach reach = ComputeTileReach(plan, tile);
      for (const glm::dvec2& sample : plan.samples) {
        const ShadowMapWindow w = ShadowMapWindowFor(plan, tile, sample, reach.z_near);
        for (int j = 0; j < tile.height; ++j) {
          for (int i = 0; i < tile.width; ++i) {
            const RayInShadowMap ray = RayForSample(plan, g.PixelCenterS(tile.x0 + i),
                                                    g.PixelCenterT(tile.y0 + j), sample,
                                                    reach.z_near);
            for (const glm::dvec2& end : {ray.st_near, ray.st_far}) {
              const int64_t tx = plan.lattice.TexelS(end.x), ty = plan.lattice.TexelT(end.y);
              ASSERT_GE(tx, w.x0);
              ASSERT_LT(tx, w.x0 + w.width);
              ASSERT_GE(ty, w.y0);
              ASSERT_LT(ty, w.y0 + w.height);
            }
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace pdsm
