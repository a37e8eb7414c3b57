// Extremes of the geometry: occluders within 1e-3 of the light plane, geometry behind or
// crossing it, rays that cross thousands of shadow-map texels, an empty scene.
#include <cmath>

#include <gtest/gtest.h>

#include "core/bake/bake_plan.h"
#include "tests/extremes/extremes_support.h"

namespace pdsm::extremes {
namespace {

// A 0.5 x 0.5 occluder 5e-4 below the 1 x 1 light hides a quarter of the light from every
// point of the scene: with 16 stratified samples (a 4 x 4 grid of cells) it covers exactly the
// four central cells, so the bake's share is exact too. Rays are scanned from the plan's scan floor
// (the depth where the shadow map reaches its texel budget), so the bake no longer needs a shadow
// map of 1e5 texels per side (it used to fail with RESOURCE_EXHAUSTED); points nearer than the
// floor read NaN.
TEST(ExtremesGeometry, OccluderWithin1e3OfTheLightPlane) {
  Scene control = PlateScene();
  control.bake.samples = 16;
  control.bake.sampling = SamplingPattern::kStratified;  // the 4 x 4 cells the claim needs
  Scene scene = control;
  scene.meshes.push_back(Quad(-0.25, 0.25, -0.25, 0.25, 5.0 - 5e-4, MeshRole::kCasterOnly));
  absl::StatusOr<BakePlan> plan = PlanBake(scene);
  ASSERT_TRUE(plan.ok());
  const double floor = plan->z_scan_floor;
  EXPECT_GT(floor, 5e-4);
  EXPECT_LT(floor, 2.5);  // the plate and the ground are resolved
  EXPECT_EQ(plan->geometry().z_valid_min, floor);

  const std::optional<Baked> baked = Bake(scene);
  ASSERT_TRUE(baked);
  EXPECT_EQ(baked->image.header.geometry.z_valid_min, floor);
  const Errors e = CompareWithExact(baked->image, scene, Grid(2.9, 30, 0.0));
  std::printf("occluder at 5e-4: floor %.4f, n=%zu mean %.4f max %.4f\n", floor, e.count, e.mean,
              e.max);
  EXPECT_EQ(e.nan, 0u);
  // The same scene without the near occluder, same window: the occluder adds no error.
  control.bake.frustum = FrustumOverride{baked->image.header.geometry.s_min,
                                         baked->image.header.geometry.s_max,
                                         baked->image.header.geometry.t_min,
                                         baked->image.header.geometry.t_max,
                                         2.5,
                                         5.0};
  const std::optional<Baked> control_baked = Bake(control);
  ASSERT_TRUE(control_baked);
  const Errors c = CompareWithExact(control_baked->image, control, Grid(2.9, 30, 0.0));
  std::printf("  without it: mean %.4f max %.4f\n", c.mean, c.max);
  // Measured: mean 0.0153 with the occluder, 0.0171 without.
  EXPECT_LT(e.mean, c.mean + 0.002);
  // The lit corner of the ground sees exactly the near occluder's share of the light.
  const std::vector<glm::dvec3> corner_point = {{2.8, 0, 2.8}};
  absl::StatusOr<std::vector<double>> corner = ExactAttenuation(scene, corner_point);
  ASSERT_TRUE(corner.ok());
  EXPECT_NEAR((*corner)[0], 0.25, 0.001);
  EXPECT_NEAR(QueryAttenuation(baked->image, {2.8, 0, 2.8}), (*corner)[0], 0.001);
  // Nearer than the floor: outside what the PDSM resolves.
  EXPECT_TRUE(std::isnan(QueryAttenuation(baked->image, {0, 5.0 - 0.5 * floor, 0})));
  // The largest shadow map stayed within the budget.
  EXPECT_LE(baked->summary.tasks_stats.shadow_map_texels,
            static_cast<int64_t>(baked->summary.tasks_stats.shadow_maps) *
                std::max(kShadowMapTexelBudget, int64_t{4} * 600 * 600));
}

// Geometry entirely behind the light plane is ignored; a caster crossing it shadows with its
// part in front. The exact reference clips occluders to z > 0 the same way.
TEST(ExtremesGeometry, GeometryBehindAndCrossingTheLightPlane) {
  Scene scene = PlateScene();
  // Behind: a big quad 1 above the light (would hide everything if it counted).
  scene.meshes.push_back(Quad(-3, 3, -3, 3, 6.0, MeshRole::kCasterOnly));
  // Crossing: a vertical quad from y = 4 to y = 6, x in [1.5, 1.8].
  TriangleMesh crossing;
  crossing.role = MeshRole::kCasterOnly;
  crossing.positions_world = {{1.5, 4, 0}, {1.8, 4, 0}, {1.8, 6, 0}, {1.5, 6, 0}};
  crossing.indices = {0, 1, 2, 0, 2, 3};
  scene.meshes.push_back(crossing);
  scene.bake.samples = 64;
  const std::optional<Baked> baked = Bake(scene);
  ASSERT_TRUE(baked);
  const Errors e = CompareWithExact(baked->image, scene, Grid(2.9, 30, 0.0));
  std::printf("behind/crossing: n=%zu nan %zu mean %.4f max %.4f\n", e.count, e.nan, e.mean, e.max);
  EXPECT_EQ(e.nan, 0u);
  EXPECT_LT(e.mean, 0.02);
  // Not everything is in shadow: the quad behind the light casts nothing.
  EXPECT_EQ(QueryAttenuation(baked->image, {2.8, 0, -2.8}), 0.0);
}

// Rays that cross thousands of texels: a 4 x 4 light 1 above a small caster, a 1.2-wide
// receiver just below it (the PDSM window is about 1 wide), 1024-texel shadow maps: a sample
// at the light's corner moves a ray's start by 2 / (1 / 1024) = 2048 texels on each axis.
// The scan floor (0.6, half the receiver's depth) is nearer than the caster: nothing is cut.
// The answer still matches the exact reference.
TEST(ExtremesGeometry, RaysAcrossThousandsOfTexels) {
  Scene scene = PlateScene(4.0);
  scene.meshes = {Quad(-0.6, 0.6, -0.6, 0.6, 3.8, MeshRole::kReceiverOnly),
                  Quad(-0.15, 0.15, -0.15, 0.15, 4.0, MeshRole::kCasterOnly)};
  scene.bake.width = scene.bake.height = 16;
  scene.bake.samples = 16;
  scene.bake.shadow_map_resolution = 1024;
  absl::StatusOr<BakePlan> plan = PlanBake(scene);
  ASSERT_TRUE(plan.ok());
  EXPECT_LT(plan->z_scan_floor, 1.0);
  EXPECT_EQ(plan->geometry().z_valid_min, 0.0);
  const std::optional<Baked> baked = Bake(scene);
  ASSERT_TRUE(baked);
  const TaskStats& stats = baked->summary.tasks_stats;
  // Per segment walked: a segment whose texels hold no caster is skipped without a walk.
  const int64_t walked_segments = stats.ray_segments - stats.segments_without_caster;
  ASSERT_GT(walked_segments, 0);
  const double per_ray = static_cast<double>(stats.texels_walked) / walked_segments;
  std::printf("thousands: %.0f texels per ray and sample\n", per_ray);
  EXPECT_GT(per_ray, 1000.0);
  const Errors e = CompareWithExact(baked->image, scene, Grid(0.55, 20, 3.8));
  std::printf("thousands: n=%zu mean %.4f max %.4f\n", e.count, e.mean, e.max);
  EXPECT_EQ(e.nan, 0u);
  EXPECT_LT(e.mean, 0.03);
}

// Nothing at all: one default frustum, every tile all lit without a shadow map, every pixel
// without a vertex, and in-frustum queries answer 0.
TEST(ExtremesGeometry, EmptyScene) {
  Scene scene = PlateScene();
  scene.meshes.clear();
  const std::optional<Baked> baked = Bake(scene);
  ASSERT_TRUE(baked);
  EXPECT_EQ(baked->summary.tasks_stats.shadow_maps, 0);
  EXPECT_EQ(baked->summary.tasks_stats.tiles_skipped, baked->summary.tiles);
  EXPECT_EQ(baked->summary.tiles_all_lit, baked->summary.tiles);
  EXPECT_EQ(VertexCount(baked->image), 0u);
  EXPECT_EQ(QueryAttenuation(baked->image, {0, 3.5, 0}), 0.0);  // light space z = 1.5
}

}  // namespace
}  // namespace pdsm::extremes
