#include "core/bake/tile_reach.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <set>
#include <vector>

#include "core/bake/bake_plan.h"
#include "core/bake/caster_clusters.h"
#include "core/bake/plan_test_scenes.h"
#include "core/geometry/light_frame.h"
#include "core/scene/scene.h"

namespace pdsm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------------
// Scenes: a light 10 units above a 20 x 20 ground quad (receiver only) at y = 0, random caster
// triangles in between. Light space: x = world x, y = world z, depth z = 10 - world y.

TriangleMesh RandomCasters(uint64_t seed, int count) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> centre_xz(-6.0, 6.0);
  std::uniform_real_distribution<double> centre_y(2.0, 8.0);
  std::uniform_real_distribution<double> offset(-1.5, 1.5);
  TriangleMesh casters;
  casters.label = "casters";
  casters.role = MeshRole::kCasterOnly;
  for (int k = 0; k < count; ++k) {
    const glm::dvec3 centre(centre_xz(rng), centre_y(rng), centre_xz(rng));
    for (int v = 0; v < 3; ++v) {
      casters.positions_world.push_back(centre +
                                        glm::dvec3(offset(rng), 0.3 * offset(rng), offset(rng)));
      casters.indices.push_back(static_cast<uint32_t>(casters.positions_world.size() - 1));
    }
  }
  return casters;
}

Scene MakeScene(LightShape shape, uint64_t seed, int caster_count = 40) {
  Scene scene;
  scene.name = "tile_reach_test";
  scene.source_path = "tile_reach_test.json";
  scene.meshes = {GroundQuad(), RandomCasters(seed, caster_count)};
  const glm::dvec3 up(0, 0, 1);
  scene.light.shape = shape;
  scene.light.frame = MakeLightFrame({0, 10, 0}, {0, -1, 0}, &up);
  scene.light.half_width = 1.5;
  scene.light.half_height = 1.5;
  scene.light.tan_half_angle = std::tan(0.3 * std::numbers::pi / 180.0);
  scene.bake.width = 64;
  scene.bake.height = 48;
  scene.bake.tile_size = 16;
  scene.bake.samples = 32;
  scene.bake.shadow_map_resolution = 256;
  scene.bake.seed = seed;
  return scene;
}

BakePlan Plan(const Scene& scene) {
  absl::StatusOr<BakePlan> plan = PlanBake(scene);
  EXPECT_TRUE(plan.ok()) << plan.status();
  return plan.ok() ? *std::move(plan) : BakePlan{};
}

bool IsSun(const BakePlan& plan) { return plan.geometry().projection == Projection::kOrthographic; }

// ---------------------------------------------------------------------------------------------
// Geometry helpers.

// Möller–Trumbore: the parameter in [0, 1] where segment from -> to meets the triangle.
std::optional<double> SegmentHitsTriangle(const glm::dvec3& from, const glm::dvec3& to,
                                          const glm::dvec3& v0, const glm::dvec3& v1,
                                          const glm::dvec3& v2) {
  const glm::dvec3 d = to - from;
  const glm::dvec3 e1 = v1 - v0, e2 = v2 - v0;
  const glm::dvec3 p = glm::cross(d, e2);
  const double det = glm::dot(e1, p);
  if (std::abs(det) < 1e-300) return std::nullopt;
  const double inv = 1.0 / det;
  const glm::dvec3 tv = from - v0;
  const double u = glm::dot(tv, p) * inv;
  if (u < 0.0 || u > 1.0) return std::nullopt;
  const glm::dvec3 q = glm::cross(tv, e1);
  const double v = glm::dot(d, q) * inv;
  if (v < 0.0 || u + v > 1.0) return std::nullopt;
  const double t = glm::dot(e2, q) * inv;
  if (t < 0.0 || t > 1.0) return std::nullopt;
  return t;
}

glm::dvec3 CasterVertex(const BakePlan& plan, size_t triangle, int corner) {
  return glm::dvec3(plan.casters.positions[plan.casters.indices[3 * triangle + corner]]);
}

// Light-space point of PDSM ray (s, t) at depth z.
glm::dvec3 RayPoint(const BakePlan& plan, double s, double t, double z) {
  return IsSun(plan) ? glm::dvec3(s, t, z) : glm::dvec3(s * z, t * z, z);
}

// The sample's shadow-map coordinates of a light-space point (DESIGN.md): perspective
// ((x - a) / z, (y - b) / z); sun (x - a z, y - b z).
glm::dvec2 ShadowMapCoords(const BakePlan& plan, const glm::dvec3& p, const glm::dvec2& sample) {
  if (IsSun(plan)) return {p.x - sample.x * p.z, p.y - sample.y * p.z};
  return {(p.x - sample.x) / p.z, (p.y - sample.y) / p.z};
}

// The point of the ray's shadow-map segment at depth z: linear in w = 1/z (perspective) or in z
// (sun) between the segment's ends.
glm::dvec2 SegmentPointAtDepth(const BakePlan& plan, const RayInShadowMap& ray, double z) {
  double f;  // 0 at st_near, 1 at st_far
  if (IsSun(plan)) {
    f = (z - ray.z_near) / (ray.z_far - ray.z_near);
  } else {
    f = 1.0 - (1.0 / z) / (1.0 / ray.z_near);
  }
  return ray.st_near + f * (ray.st_far - ray.st_near);
}

// The segment from a ray point toward a light sample: to the sample's point on the light plane
// (perspective), or along the sample's direction back to the plane z = 0 (sun).
glm::dvec3 TowardSample(const BakePlan& plan, const glm::dvec3& q, const glm::dvec2& sample) {
  if (IsSun(plan)) return q - q.z * glm::dvec3(sample.x, sample.y, 1.0);
  return {sample.x, sample.y, 0.0};
}

struct RandomRay {
  TileRect tile;
  double s, t;
};

RandomRay PickRay(const BakePlan& plan, std::mt19937_64& rng) {
  std::uniform_int_distribution<size_t> tile_dist(0, plan.tile_count() - 1);
  const TileRect tile = plan.tile(static_cast<int>(tile_dist(rng)));
  std::uniform_int_distribution<int> x_dist(tile.x0, tile.x0 + tile.width - 1);
  std::uniform_int_distribution<int> y_dist(tile.y0, tile.y0 + tile.height - 1);
  return {tile, plan.geometry().PixelCenterS(x_dist(rng)),
          plan.geometry().PixelCenterT(y_dist(rng))};
}

// ---------------------------------------------------------------------------------------------
// The plan.

class BakePlanTest : public testing::TestWithParam<LightShape> {};

TEST_P(BakePlanTest, WindowAndDepthsHoldAllGeometry) {
  for (uint64_t seed : {1, 2, 3}) {
    const Scene scene = MakeScene(GetParam(), seed);
    const BakePlan plan = Plan(scene);
    const PdsmGeometry& g = plan.geometry();
    ASSERT_EQ(g.width, 64);
    ASSERT_EQ(g.height, 48);
    ASSERT_EQ(g.projection, GetParam() == LightShape::kSun ? Projection::kOrthographic
                                                           : Projection::kPerspective);
    ASSERT_LT(g.s_min, g.s_max);
    ASSERT_LT(g.t_min, g.t_max);
    ASSERT_GT(g.z_near, 0.0);
    ASSERT_LE(g.z_near, g.z_far);
    double min_caster_z = kInf;
    for (const TriangleMesh& mesh : scene.meshes) {
      for (const glm::dvec3& p_world : mesh.positions_world) {
        const glm::dvec3 p = g.frame.LightFromWorld(p_world);
        ASSERT_GT(p.z, 0.0) << "the scene is in front of the light";
        const std::optional<glm::dvec2> st = g.WindowFromLight(p);
        ASSERT_TRUE(st.has_value());
        EXPECT_GE(st->x, g.s_min);
        EXPECT_LE(st->x, g.s_max);
        EXPECT_GE(st->y, g.t_min);
        EXPECT_LE(st->y, g.t_max);
        EXPECT_LE(p.z, g.z_far * (1 + 1e-12));
        EXPECT_TRUE(g.Locate(p_world).has_value());
        if (Casts(mesh.role)) min_caster_z = std::min(min_caster_z, p.z);
      }
    }
    EXPECT_LE(g.z_near, min_caster_z);
    EXPECT_LE(plan.z_clip_near, g.z_near);
    EXPECT_GT(plan.z_clip_near, 0.0);
    EXPECT_EQ(plan.samples.size(), 32u);
    EXPECT_EQ(plan.casters.TriangleCount(), 40u);
    // Only a surfaces-only plan or the preview (AddLightSpaceReceivers) holds the receivers.
    EXPECT_EQ(plan.receivers.TriangleCount(), 0u);
    BakePlan with_receivers = plan;
    AddLightSpaceReceivers(scene, &with_receivers);
    EXPECT_EQ(with_receivers.receivers.TriangleCount(), 2u);
  }
}

TEST_P(BakePlanTest, TilesCoverTheImageExactlyOnce) {
  struct Size {
    int width, height, tile;
  };
  for (const Size size :
       {Size{100, 37, 16}, Size{64, 48, 16}, Size{1, 1, 64}, Size{17, 33, 16}, Size{5, 200, 7}}) {
    Scene scene = MakeScene(GetParam(), 1, 4);
    scene.bake.width = size.width;
    scene.bake.height = size.height;
    scene.bake.tile_size = size.tile;
    const BakePlan plan = Plan(scene);
    ASSERT_EQ(plan.tiles_x, (size.width + size.tile - 1) / size.tile);
    ASSERT_EQ(plan.tiles_y, (size.height + size.tile - 1) / size.tile);
    ASSERT_EQ(plan.tile_count(), static_cast<size_t>(plan.tiles_x) * plan.tiles_y);
    std::vector<int> covered(static_cast<size_t>(size.width) * size.height, 0);
    for (size_t k = 0; k < plan.tile_count(); ++k) {
      const TileRect tile = plan.tile(static_cast<int>(k));
      EXPECT_EQ(tile.index, static_cast<int>(k));
      // Row-major grid.
      EXPECT_EQ(tile.x0, static_cast<int>(k % plan.tiles_x) * size.tile);
      EXPECT_EQ(tile.y0, static_cast<int>(k / plan.tiles_x) * size.tile);
      ASSERT_GT(tile.width, 0);
      ASSERT_GT(tile.height, 0);
      ASSERT_LE(tile.width, size.tile);
      ASSERT_LE(tile.height, size.tile);
      ASSERT_LE(tile.x0 + tile.width, size.width);
      ASSERT_LE(tile.y0 + tile.height, size.height);
      for (int y = tile.y0; y < tile.y0 + tile.height; ++y) {
        for (int x = tile.x0; x < tile.x0 + tile.width; ++x) ++covered[y * size.width + x];
      }
    }
    for (size_t p = 0; p < covered.size(); ++p) {
      ASSERT_EQ(covered[p], 1) << size.width << "x" << size.height << " pixel " << p;
    }
  }
}

TEST_P(BakePlanTest, SamplesLieOnTheLight) {
  const BakePlan plan = Plan(MakeScene(GetParam(), 4));
  for (const glm::dvec2& sample : plan.samples) {
    if (GetParam() == LightShape::kSun) {
      EXPECT_LE(glm::length(sample), std::tan(0.3 * std::numbers::pi / 180.0) * (1 + 1e-12));
    } else {
      EXPECT_LE(std::abs(sample.x), 1.5);
      EXPECT_LE(std::abs(sample.y), 1.5);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Rays in shadow maps.

class TileReachTest : public testing::TestWithParam<LightShape> {};

// A world point on a PDSM ray, projected into a sample's shadow map, is the point of
// RayForSample's segment at the same depth.
TEST_P(TileReachTest, RaySegmentMatchesShadowMapProjection) {
  const BakePlan plan = Plan(MakeScene(GetParam(), 5));
  const PdsmGeometry& g = plan.geometry();
  std::mt19937_64 rng(55);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<size_t> sample_dist(0, plan.samples.size() - 1);
  for (int trial = 0; trial < 5000; ++trial) {
    const RandomRay ray = PickRay(plan, rng);
    const glm::dvec2 sample = plan.samples[sample_dist(rng)];
    const double z_near = g.z_near * (0.5 + unit(rng));
    const RayInShadowMap segment = RayForSample(plan, ray.s, ray.t, sample, z_near);
    ASSERT_EQ(segment.z_near, z_near);
    double z;
    if (IsSun(plan)) {
      ASSERT_GE(segment.z_far, g.z_far);
      z = z_near + unit(rng) * (segment.z_far - z_near);
    } else {
      ASSERT_EQ(segment.z_far, kInf);
      z = z_near / (1e-6 + unit(rng));  // w = 1/z over (0, 1/z_near]
    }
    const glm::dvec2 expected = ShadowMapCoords(plan, RayPoint(plan, ray.s, ray.t, z), sample);
    const glm::dvec2 actual = SegmentPointAtDepth(plan, segment, z);
    ASSERT_NEAR(actual.x, expected.x, 1e-9 * (1 + std::abs(expected.x))) << "trial " << trial;
    ASSERT_NEAR(actual.y, expected.y, 1e-9 * (1 + std::abs(expected.y))) << "trial " << trial;
  }
  // The segment's ends: the nearest point, and the farthest (w = 0: (s, t); sun: z_far).
  const glm::dvec2 sample = plan.samples.front();
  const RayInShadowMap segment = RayForSample(plan, 0.1, -0.2, sample, g.z_near);
  const glm::dvec2 near = ShadowMapCoords(plan, RayPoint(plan, 0.1, -0.2, g.z_near), sample);
  EXPECT_NEAR(segment.st_near.x, near.x, 1e-12);
  EXPECT_NEAR(segment.st_near.y, near.y, 1e-12);
  if (!IsSun(plan)) {
    EXPECT_EQ(segment.st_far, glm::dvec2(0.1, -0.2));
  }
}

TEST_P(TileReachTest, CentreSampleMapsARayToOnePoint) {
  const BakePlan plan = Plan(MakeScene(GetParam(), 6));
  const RayInShadowMap segment =
      RayForSample(plan, 0.3, 0.4, glm::dvec2(0.0), plan.geometry().z_near);
  EXPECT_EQ(segment.st_near, segment.st_far);
  EXPECT_EQ(segment.st_near, glm::dvec2(0.3, 0.4));
}

// Every ray segment of the tile, for every sample, lies in the sample's lattice window.
TEST_P(TileReachTest, ShadowMapWindowHoldsEveryRaySegment) {
  const BakePlan plan = Plan(MakeScene(GetParam(), 7));
  const ShadowMapLattice& lattice = plan.lattice;
  for (const TileRect& tile : AllTiles(plan)) {
    const TileReach reach = ComputeTileReach(plan, tile);
    for (double z_near : {plan.z_clip_near, reach.empty() ? plan.z_clip_near : reach.z_near}) {
      for (const glm::dvec2& sample : plan.samples) {
        const ShadowMapWindow window = ShadowMapWindowFor(plan, tile, sample, z_near);
        ASSERT_GE(window.width, 1);
        ASSERT_GE(window.height, 1);
        int64_t used_x_lo = INT64_MAX, used_x_hi = INT64_MIN;
        int64_t used_y_lo = INT64_MAX, used_y_hi = INT64_MIN;
        for (int y = tile.y0; y < tile.y0 + tile.height; ++y) {
          for (int x = tile.x0; x < tile.x0 + tile.width; ++x) {
            const RayInShadowMap segment =
                RayForSample(plan, plan.geometry().PixelCenterS(x), plan.geometry().PixelCenterT(y),
                             sample, z_near);
            for (double f : {0.0, 0.25, 0.5, 1.0}) {
              const glm::dvec2 st = segment.st_near + f * (segment.st_far - segment.st_near);
              const int64_t tx = lattice.TexelS(st.x), ty = lattice.TexelT(st.y);
              ASSERT_GE(tx, window.x0) << "tile " << tile.index << " pixel " << x << "," << y;
              ASSERT_LT(tx, window.x0 + window.width);
              ASSERT_GE(ty, window.y0);
              ASSERT_LT(ty, window.y0 + window.height);
              used_x_lo = std::min(used_x_lo, tx);
              used_x_hi = std::max(used_x_hi, tx);
              used_y_lo = std::min(used_y_lo, ty);
              used_y_hi = std::max(used_y_hi, ty);
            }
          }
        }
        // The window is no larger than what the pixel-centre rays need.
        EXPECT_LE(window.width, used_x_hi - used_x_lo + 1);
        EXPECT_LE(window.height, used_y_hi - used_y_lo + 1);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Culling.

// The block of the reach holding the ray's pixel, or null.
const RayBlock* BlockOf(const BakePlan& plan, const TileReach& reach, const RandomRay& ray) {
  const PdsmGeometry& g = plan.geometry();
  const int i = static_cast<int>(std::lround((ray.s - g.s_min) / g.PixelPitchS() - 0.5));
  const int j = static_cast<int>(std::lround((ray.t - g.t_min) / g.PixelPitchT() - 0.5));
  for (const RayBlock& b : reach.blocks) {
    if (i >= b.rect.x0 && i < b.rect.x0 + b.rect.width && j >= b.rect.y0 &&
        j < b.rect.y0 + b.rect.height) {
      return &b;
    }
  }
  return nullptr;
}

// If a sample's segment to a point of one of the tile's rays crosses a caster, the caster is in
// the tile's reach, and the shadowed point is no nearer than its block's z_begin.
void CheckConservativeCulling(LightShape shape, double far_factor) {
  int hits = 0;
  for (uint64_t seed : {11, 12, 13, 14}) {
    const BakePlan plan = Plan(MakeScene(shape, seed));
    const PdsmGeometry& g = plan.geometry();
    std::map<int, TileReach> reaches;
    std::mt19937_64 rng(seed * 31);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::uniform_int_distribution<size_t> sample_dist(0, plan.samples.size() - 1);
    for (int trial = 0; trial < 10000; ++trial) {
      const RandomRay ray = PickRay(plan, rng);
      auto it = reaches.find(ray.tile.index);
      if (it == reaches.end()) {
        it = reaches.emplace(ray.tile.index, ComputeTileReach(plan, ray.tile)).first;
      }
      const TileReach& reach = it->second;
      const double z = g.z_near + unit(rng) * (far_factor * g.z_far - g.z_near);
      const glm::dvec2 sample = plan.samples[sample_dist(rng)];
      const glm::dvec3 q = RayPoint(plan, ray.s, ray.t, z);
      const glm::dvec3 light_end = TowardSample(plan, q, sample);
      for (size_t k = 0; k < plan.casters.TriangleCount(); ++k) {
        const std::optional<double> hit =
            SegmentHitsTriangle(light_end, q, CasterVertex(plan, k, 0), CasterVertex(plan, k, 1),
                                CasterVertex(plan, k, 2));
        if (!hit) continue;
        ++hits;
        const bool kept = std::find(reach.triangles.begin(), reach.triangles.end(),
                                    static_cast<uint32_t>(k)) != reach.triangles.end();
        ASSERT_TRUE(kept) << "seed " << seed << " trial " << trial << ": triangle " << k
                          << " shadows tile " << ray.tile.index << " ray (" << ray.s << ", "
                          << ray.t << ") at z " << z << " from sample (" << sample.x << ", "
                          << sample.y << ") but was culled";
        // The shadowed point is no nearer than the reach's z_near, where the tile's rays start.
        ASSERT_GE(q.z, reach.z_near * (1 - 1e-12)) << "seed " << seed << " trial " << trial;
        // The shadowed point q is no nearer than its block's z_begin (per-ray clipping).
        const RayBlock* block = BlockOf(plan, reach, ray);
        ASSERT_NE(block, nullptr) << "seed " << seed << " trial " << trial
                                  << ": a shadowed ray's block was dropped";
        ASSERT_GE(q.z, block->z_begin * (1 - 1e-12)) << "seed " << seed << " trial " << trial;
      }
    }
  }
  // The property was exercised, not vacuously true.
  EXPECT_GT(hits, 1000);
}

TEST_P(TileReachTest, CullingIsConservative) {
  // Perspective rays are infinite: test well beyond the farthest geometry. The sun's rays end
  // at z_far (RayForSample), and its shadowing region is bounded by it.
  CheckConservativeCulling(GetParam(), GetParam() == LightShape::kSun ? 1.0 : 3.0);
}

TEST_P(TileReachTest, ReachIsUniqueAndItsDepthBoundsItsTriangles) {
  const BakePlan plan = Plan(MakeScene(GetParam(), 21));
  size_t kept = 0;
  for (const TileRect& tile : AllTiles(plan)) {
    const TileReach reach = ComputeTileReach(plan, tile);
    kept += reach.triangles.size();
    std::vector<uint32_t> sorted = reach.triangles;
    std::sort(sorted.begin(), sorted.end());
    ASSERT_TRUE(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end())
        << "a triangle listed twice";
    if (reach.empty()) continue;
    EXPECT_GE(reach.z_near, plan.z_clip_near);
    // Rays start no nearer than the nearest kept caster: nothing can shadow them before it.
    double nearest = kInf;
    for (uint32_t k : reach.triangles) {
      ASSERT_LT(k, plan.casters.TriangleCount());
      for (int corner = 0; corner < 3; ++corner) {
        nearest = std::min(nearest, CasterVertex(plan, k, corner).z);
      }
    }
    EXPECT_GE(reach.z_near, nearest * (1 - 1e-12));
    for (const RayBlock& b : reach.blocks) {
      EXPECT_GE(b.z_begin, reach.z_near);
      EXPECT_GE(b.rect.x0, tile.x0);
      EXPECT_LE(b.rect.x0 + b.rect.width, tile.x0 + tile.width);
      EXPECT_GE(b.rect.y0, tile.y0);
      EXPECT_LE(b.rect.y0 + b.rect.height, tile.y0 + tile.height);
    }
  }
  // Culling culls: with 40 small casters over 12 tiles, far fewer than all pairs are kept.
  EXPECT_LT(kept, plan.tile_count() * plan.casters.TriangleCount() * 3 / 4);
  EXPECT_GT(kept, 0u);
}

// One small caster over the ground's -x edge is in the reach of the tiles below it and not in
// that of the tiles on the far +x side.
TEST_P(TileReachTest, CasterFarToTheSideIsCulled) {
  Scene scene = MakeScene(GetParam(), 1, 0);
  TriangleMesh caster;
  caster.role = MeshRole::kCasterOnly;
  caster.positions_world = {{-9.0, 5.0, -0.5}, {-8.0, 5.0, -0.5}, {-8.5, 5.0, 0.5}};
  caster.indices = {0, 1, 2};
  scene.meshes[1] = caster;
  const BakePlan plan = Plan(scene);
  ASSERT_EQ(plan.casters.TriangleCount(), 1u);
  int kept_left = 0, culled_right = 0, right_tiles = 0;
  for (const TileRect& tile : AllTiles(plan)) {
    const TileReach reach = ComputeTileReach(plan, tile);
    if (tile.x0 == 0 && !reach.empty()) ++kept_left;
    if (tile.x0 + tile.width == plan.geometry().width) {
      ++right_tiles;
      if (reach.empty()) ++culled_right;
    }
  }
  EXPECT_GT(kept_left, 0);
  EXPECT_EQ(culled_right, right_tiles);
  EXPECT_GT(right_tiles, 0);
}

// An occluder 1e-4 under the light: the plan's scan floor keeps every tile's shadow map within
// the texel budget and every ray within kMaxRayTexels per axis, records the floor as the
// PDSM's nearest valid depth, and keeps the window on the receivers (not stretched to
// tan 85 degrees by the occluder's projection).
TEST(ScanFloor, NearLightOccluderStaysWithinTheBudgets) {
  Scene scene = MakeScene(LightShape::kRect, 3, 10);
  TriangleMesh near_light;
  near_light.role = MeshRole::kCasterOnly;
  near_light.positions_world = {
      {-0.5, 10 - 1e-4, -0.5}, {0.5, 10 - 1e-4, -0.5}, {0.0, 10 - 1e-4, 0.5}};
  near_light.indices = {0, 1, 2};
  scene.meshes.push_back(near_light);
  const BakePlan plan = Plan(scene);
  const PdsmGeometry& g = plan.geometry();
  EXPECT_LT(g.z_near, 2e-4);
  ASSERT_GT(plan.z_scan_floor, g.z_near);
  EXPECT_EQ(g.z_valid_min, plan.z_scan_floor);
  EXPECT_LT(plan.z_scan_floor, 1.0);  // the ground is at depth 10, the casters at 2 to 8
  EXPECT_LT(g.s_max - g.s_min, 2.5);  // the 20 x 20 ground at depth 10: about 2 wide
  const double tile_x = plan.header.tile_size * g.PixelPitchS() / plan.lattice.pitch_s + 2;
  const double tile_y = plan.header.tile_size * g.PixelPitchT() / plan.lattice.pitch_t + 2;
  const double budget = std::max(static_cast<double>(kShadowMapTexelBudget), 4 * tile_x * tile_y);
  int64_t largest = 0;
  for (const TileRect& tile : AllTiles(plan)) {
    const TileReach reach = ComputeTileReach(plan, tile);
    for (const RayBlock& b : reach.blocks) EXPECT_GE(b.z_begin, plan.z_scan_floor);
    for (const glm::dvec2& sample : plan.samples) {
      ShadowMapWindow window;
      for (const RayBlock& b : reach.blocks) {
        window = UnionWindow(window, ShadowMapWindowFor(plan, b.rect, sample, b.z_begin));
        const RayInShadowMap ray = RayForSample(plan, g.PixelCenterS(b.rect.x0),
                                                g.PixelCenterT(b.rect.y0), sample, b.z_begin);
        EXPECT_LE(std::abs(ray.st_far.x - ray.st_near.x) / plan.lattice.pitch_s,
                  kMaxRayTexels * (1 + 1e-9));
      }
      largest = std::max(largest, int64_t{window.width} * window.height);
    }
  }
  EXPECT_GT(largest, 0);
  EXPECT_LE(static_cast<double>(largest), budget);
}

// The clusters only save work: the reach is the same, triangle for triangle and depth for
// depth, as with one cluster holding every caster (which prunes nothing: brute force), on
// scenes dense enough that boxes are pruned.
TEST_P(TileReachTest, ClustersGiveTheBruteForceReachExactly) {
  for (uint64_t seed : {3u, 17u, 99u}) {
    const BakePlan plan = Plan(MakeScene(GetParam(), seed, 1500));
    ASSERT_GT(plan.caster_clusters.size(), 5u);
    BakePlan brute = plan;
    CasterCluster all;
    all.first_triangle = 0;
    all.triangle_count = static_cast<uint32_t>(plan.casters.TriangleCount());
    all.lo = glm::dvec3(kInf);
    all.hi = glm::dvec3(-kInf);
    for (const glm::vec3& p : plan.casters.positions) {
      all.lo = glm::min(all.lo, glm::dvec3(p));
      all.hi = glm::max(all.hi, glm::dvec3(p));
    }
    brute.caster_clusters = {all};
    int compared_blocks = 0;
    for (const TileRect& tile : AllTiles(plan)) {
      const TileReach a = ComputeTileReach(plan, tile), b = ComputeTileReach(brute, tile);
      ASSERT_EQ(a.triangles, b.triangles) << "seed " << seed << " tile " << tile.index;
      ASSERT_EQ(a.blocks.size(), b.blocks.size()) << "seed " << seed << " tile " << tile.index;
      for (size_t k = 0; k < a.blocks.size(); ++k) {
        ASSERT_EQ(a.blocks[k].z_begin, b.blocks[k].z_begin) << "seed " << seed;
        ++compared_blocks;
      }
      EXPECT_EQ(TileHasCasters(plan, tile), TileHasCasters(brute, tile));
    }
    EXPECT_GT(compared_blocks, 20);
  }
}

// The plan's per-tile flags never miss a tile the exact test keeps, and skip most of the
// others (casters over a corner of the ground). Every caster here lies beyond the near clip
// plane, where the two tests agree (TilesCastersMayReach says where they need not).
TEST_P(TileReachTest, TilesCastersMayReachIsASupersetOfTileHasCasters) {
  int exact = 0, flagged = 0;
  for (uint64_t seed : {2u, 8u}) {
    Scene scene = MakeScene(GetParam(), seed, 600);
    for (glm::dvec3& p : scene.meshes[1].positions_world) {
      p = {0.25 * p.x - 6.5, p.y, 0.25 * p.z - 6.5};  // the casters shrunk into one corner
    }
    scene.bake.width = 256;
    scene.bake.height = 192;
    const BakePlan plan = Plan(scene);
    ASSERT_EQ(plan.tile_has_casters.size(), plan.tile_count());
    for (const TileRect& tile : AllTiles(plan)) {
      const bool has = TileHasCasters(plan, tile);
      if (has) EXPECT_TRUE(plan.tile_has_casters[tile.index]) << "tile " << tile.index;
      exact += has;
      flagged += plan.tile_has_casters[tile.index];
    }
  }
  EXPECT_GT(exact, 0);
  EXPECT_LT(flagged, 2 * 192);  // of 2 x 192 tiles
}

// Casters scattered far apart share a cluster whose box spans the map; each triangle's own box
// flags only the tiles near it (a sparse world's roofs: bench/sparse_world.py), and never
// misses a tile the exact test keeps.
TEST_P(TileReachTest, ScatteredCastersFlagOnlyTheTilesNearThem) {
  Scene scene = MakeScene(GetParam(), 5, 0);
  TriangleMesh casters;
  casters.role = MeshRole::kCasterOnly;
  for (const glm::dvec3 c : {glm::dvec3(-7, 5, -5), glm::dvec3(7, 5, 5), glm::dvec3(-7, 5, 5)}) {
    for (const glm::dvec3 d : {glm::dvec3(0, 0, 0), glm::dvec3(0.5, 0, 0), glm::dvec3(0, 0, 0.5)}) {
      casters.positions_world.push_back(c + d);
      casters.indices.push_back(static_cast<uint32_t>(casters.indices.size()));
    }
  }
  scene.meshes[1] = casters;
  scene.bake.width = 256;
  scene.bake.height = 192;
  const BakePlan plan = Plan(scene);
  ASSERT_EQ(plan.caster_clusters.size(), 1u);
  ASSERT_EQ(plan.tile_has_casters.size(), plan.tile_count());
  int exact = 0, flagged = 0;
  for (const TileRect& tile : AllTiles(plan)) {
    const bool has = TileHasCasters(plan, tile);
    if (has) EXPECT_TRUE(plan.tile_has_casters[tile.index]) << "tile " << tile.index;
    exact += has;
    flagged += plan.tile_has_casters[tile.index];
  }
  EXPECT_GE(exact, 3);
  // The cluster's box alone flagged far more: rect 192, sun 104 of the 192 tiles.
  EXPECT_LE(flagged, std::max(2 * exact, 12)) << "exact " << exact;
}

TEST_P(TileReachTest, NoCastersMeansEmptyReach) {
  const BakePlan plan = Plan(MakeScene(GetParam(), 1, 0));
  EXPECT_FALSE(plan.has_casters());
  for (const TileRect& tile : AllTiles(plan)) EXPECT_TRUE(ComputeTileReach(plan, tile).empty());
}

std::string ShapeName(const testing::TestParamInfo<LightShape>& info) {
  switch (info.param) {
    case LightShape::kRect:
      return "Rect";
    case LightShape::kDisk:
      return "Disk";
    case LightShape::kSun:
      return "Sun";
  }
  return "Unknown";
}

INSTANTIATE_TEST_SUITE_P(Lights, BakePlanTest, testing::Values(LightShape::kRect, LightShape::kSun),
                         ShapeName);
INSTANTIATE_TEST_SUITE_P(Lights, TileReachTest,
                         testing::Values(LightShape::kRect, LightShape::kSun), ShapeName);

}  // namespace
}  // namespace pdsm
