// A plan gathers only the casters some tile can reach (core/bake/caster_culling.h), changing
// no tile's reach: the same triangles (compared by their vertices) in the same order, the same
// ray blocks and depths. That is what keeps the bake's bytes: the ray blocks set where rays are
// scanned from and the shadow-map windows, and so the projections of the maps.
#include "core/bake/caster_culling.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "core/bake/bake_plan.h"
#include "core/bake/plan_test_scenes.h"
#include "core/bake/tile_reach.h"
#include "core/geometry/light_frame.h"
#include "core/scene/scene.h"

namespace pdsm {
namespace {

// A light 10 units above a 20 x 20 ground (receiver only, y = 0) facing down, casters between
// them, and a "world" of triangles scattered over 400 x 400 units from below the ground to
// above the light: many straddle the light's plane (world y = 10), where the reach's
// half-spaces are looser than in front of it, and most are out of the light's reach.
Scene WorldAroundALight(const std::string& kind, uint64_t seed) {
  std::mt19937_64 rng(seed);
  Scene scene;
  scene.name = "caster_culling_test";
  scene.source_path = "caster_culling_test.json";
  TriangleMesh casters;
  casters.role = MeshRole::kCasterOnly;
  const auto add_triangles = [&](int count, double half_side, double y_lo, double y_hi,
                                 double size) {
    std::uniform_real_distribution<double> xz(-half_side, half_side), y(y_lo, y_hi),
        offset(-size, size);
    for (int k = 0; k < count; ++k) {
      const glm::dvec3 centre(xz(rng), y(rng), xz(rng));
      for (int v = 0; v < 3; ++v) {
        casters.positions_world.push_back(centre +
                                          glm::dvec3(offset(rng), offset(rng), offset(rng)));
        casters.indices.push_back(static_cast<uint32_t>(casters.positions_world.size() - 1));
      }
    }
  };
  add_triangles(300, 6.0, 2.0, 8.0, 1.0);       // in reach
  add_triangles(300, 3.0, 9.0, 11.0, 1.5);      // around the light's plane
  add_triangles(3000, 200.0, -5.0, 20.0, 3.0);  // the world
  scene.meshes = {GroundQuad(), casters};
  const glm::dvec3 up(0, 0, 1);
  scene.light.frame = MakeLightFrame({0, 10, 0}, {0, -1, 0}, &up);
  scene.bake.width = 96;
  scene.bake.height = 64;
  scene.bake.tile_size = 16;
  scene.bake.samples = 16;
  scene.bake.shadow_map_resolution = 256;
  scene.bake.seed = seed;
  if (kind == "rect") {
    scene.light.shape = LightShape::kRect;
    scene.light.half_width = 1.5;
    scene.light.half_height = 0.5;
    scene.bake.frustum = FrustumOverride{-1.2, 1.2, -0.8, 1.0, 0.5, 12};
  } else if (kind == "spot") {
    scene.light.shape = LightShape::kDisk;
    scene.light.radius = 0.3;
    scene.light.cone_half_angle_deg = 40;
  } else if (kind == "sphere_face") {
    scene.light.shape = LightShape::kDisk;
    scene.light.radius = 0.5;
    scene.light.face_tangent = 1.0;
  } else {
    scene.light.shape = LightShape::kSun;
    scene.light.tan_half_angle = std::tan(2.0 * 3.14159265358979 / 180.0);
    // The fitted sun window would hold the whole world: this one holds the ground. (The sun's
    // frame sits a world's radius, ~283, before the world's middle.)
    scene.bake.frustum = FrustumOverride{-12, 12, -11, 12, 250, 300};
  }
  return scene;
}

// A triangle of a plan's casters by its vertices.
std::vector<glm::vec3> Vertices(const BakePlan& plan, const std::vector<uint32_t>& triangles) {
  std::vector<glm::vec3> out;
  for (uint32_t t : triangles) {
    for (int v = 0; v < 3; ++v)
      out.push_back(plan.casters.positions[plan.casters.indices[3 * t + v]]);
  }
  return out;
}

class CasterCullingTest : public testing::TestWithParam<std::string> {};

TEST_P(CasterCullingTest, EveryTileReachesWhatItReachedWithEveryCaster) {
  for (uint64_t seed : {1u, 7u}) {
    const Scene scene = WorldAroundALight(GetParam(), seed);
    absl::StatusOr<BakePlan> culled = PlanBake(scene);
    absl::StatusOr<BakePlan> every = PlanBake(scene, PlanCasters::kEvery);
    ASSERT_TRUE(culled.ok() && every.ok()) << culled.status() << every.status();
    EXPECT_EQ(every->casters_left_out, 0u);
    EXPECT_EQ(every->casters.TriangleCount(), 3600u);
    // Most of the world is out of reach, and what is left is what the tiles use.
    EXPECT_GT(culled->casters_left_out, 2000u) << "seed " << seed;
    EXPECT_EQ(culled->casters.TriangleCount() + culled->casters_left_out, 3600u);
    EXPECT_LT(culled->casters.positions.size(), every->casters.positions.size());
    ASSERT_EQ(culled->header.geometry.width, every->header.geometry.width);
    int tiles_reached = 0, blocks = 0;
    for (int i = 0; i < every->tile_count(); ++i) {
      const TileRect tile = every->tile(i);
      const TileReach a = ComputeTileReach(*culled, tile), b = ComputeTileReach(*every, tile);
      ASSERT_EQ(Vertices(*culled, a.triangles), Vertices(*every, b.triangles))
          << GetParam() << " seed " << seed << " tile " << i;
      ASSERT_EQ(a.blocks.size(), b.blocks.size()) << "tile " << i;
      for (size_t k = 0; k < a.blocks.size(); ++k) {
        EXPECT_EQ(a.blocks[k].rect.x0, b.blocks[k].rect.x0);
        EXPECT_EQ(a.blocks[k].rect.y0, b.blocks[k].rect.y0);
        EXPECT_EQ(a.blocks[k].z_begin, b.blocks[k].z_begin) << "tile " << i << " block " << k;
      }
      EXPECT_EQ(TileHasCasters(*culled, tile), TileHasCasters(*every, tile));
      tiles_reached += a.triangles.empty() ? 0 : 1;
      blocks += static_cast<int>(a.blocks.size());
    }
    // The tasks are the same: the tiles were marked with every caster.
    EXPECT_EQ(culled->tile_has_casters, every->tile_has_casters);
    EXPECT_GT(tiles_reached, 4) << GetParam();
    EXPECT_GT(blocks, 20) << GetParam();
    // The cut never reorders: the kept triangles keep their order among every caster.
    std::vector<uint32_t> all(culled->casters.TriangleCount());
    for (uint32_t t = 0; t < all.size(); ++t) all[t] = t;
    const std::vector<glm::vec3> kept = Vertices(*culled, all);
    size_t next = 0;
    for (size_t t = 0; t < every->casters.TriangleCount() && next < kept.size(); ++t) {
      if (Vertices(*every, {static_cast<uint32_t>(t)}) ==
          std::vector<glm::vec3>(kept.begin() + 3 * next, kept.begin() + 3 * next + 3)) {
        ++next;
      }
    }
    EXPECT_EQ(3 * next, kept.size()) << "kept triangles out of their order";
    // Each cluster keeps its kept triangles, its mask and the bounds of what it kept.
    size_t covered = 0;
    for (const CasterCluster& c : culled->caster_clusters) {
      EXPECT_EQ(c.first_triangle, covered);
      EXPECT_GT(c.triangle_count, 0u);
      covered += c.triangle_count;
      for (uint32_t t = c.first_triangle; t < c.first_triangle + c.triangle_count; ++t) {
        for (const glm::vec3& p : Vertices(*culled, {t})) {
          EXPECT_TRUE(glm::all(glm::lessThanEqual(c.lo, glm::dvec3(p))) &&
                      glm::all(glm::lessThanEqual(glm::dvec3(p), c.hi)));
        }
      }
    }
    EXPECT_EQ(covered, culled->casters.TriangleCount());
  }
}

INSTANTIATE_TEST_SUITE_P(Lights, CasterCullingTest,
                         testing::Values("rect", "spot", "sphere_face", "sun"),
                         [](const testing::TestParamInfo<std::string>& info) {
                           return info.param;
                         });

// Nothing to leave out: the plan is the one with every caster.
TEST(CasterCulling, ACasterEveryTileReachesIsKept) {
  Scene scene = WorldAroundALight("rect", 3);
  scene.meshes[1].positions_world = {{-1, 5, -1}, {1, 5, -1}, {0, 5, 1}};
  scene.meshes[1].indices = {0, 1, 2};
  absl::StatusOr<BakePlan> plan = PlanBake(scene);
  absl::StatusOr<BakePlan> every = PlanBake(scene, PlanCasters::kEvery);
  ASSERT_TRUE(plan.ok() && every.ok()) << plan.status() << every.status();
  EXPECT_EQ(plan->casters_left_out, 0u);
  EXPECT_EQ(plan->casters.TriangleCount(), 1u);
  EXPECT_EQ(plan->casters.positions, every->casters.positions);
  EXPECT_EQ(plan->casters.indices, every->casters.indices);
}

}  // namespace
}  // namespace pdsm
