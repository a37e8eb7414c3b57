#include "core/bake/scene_index.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "core/bake/caster_clusters.h"
#include "core/geometry/light_frame.h"

namespace pdsm {
namespace {

// `count` small triangles scattered over a 200 x 200 x 50 field.
TriangleMesh Scattered(MeshRole role, int count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-100, 100);
  TriangleMesh mesh;
  mesh.role = role;
  for (int t = 0; t < count; ++t) {
    const glm::dvec3 c(u(rng), u(rng) / 4, u(rng));
    for (const glm::dvec3& d : {glm::dvec3(0), glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0.5)}) {
      mesh.indices.push_back(static_cast<uint32_t>(mesh.positions_world.size()));
      mesh.positions_world.push_back(c + d);
    }
  }
  return mesh;
}

Scene ThreeRoles() {
  Scene scene;
  scene.source_path = "scene_index_test.json";
  scene.meshes = {Scattered(MeshRole::kReceiverOnly, 300, 1),
                  Scattered(MeshRole::kCasterAndReceiver, 700, 2),
                  Scattered(MeshRole::kCasterOnly, 500, 3)};
  return scene;
}

TEST(SceneIndex, EveryTriangleOnceCastersFirstInSpatialClustersWithTheirBounds) {
  const Scene scene = ThreeRoles();
  absl::StatusOr<std::shared_ptr<const SceneIndex>> built = SceneIndex::Build(scene);
  ASSERT_TRUE(built.ok()) << built.status();
  const SceneIndex& index = **built;
  ASSERT_EQ(index.triangles().size(), 1500u);
  EXPECT_EQ(index.caster_count(), 1200u);
  std::set<std::pair<uint32_t, uint32_t>> seen;
  for (size_t k = 0; k < index.triangles().size(); ++k) {
    const SceneTriangle& t = index.triangles()[k];
    EXPECT_TRUE(seen.insert({t.mesh, t.triangle}).second);
    EXPECT_EQ(Casts(scene.meshes[t.mesh].role), k < index.caster_count()) << k;
  }
  uint32_t next = 0;
  double box_area = 0;
  for (const SceneCluster& c : index.clusters()) {
    EXPECT_EQ(c.first, next);
    EXPECT_GT(c.count, 0u);
    EXPECT_LE(c.count, kClusterTriangles);
    next += c.count;
    EXPECT_EQ(c.casts, c.first < index.caster_count());
    bool receives = false;
    for (uint32_t k = c.first; k < c.first + c.count; ++k) {
      const SceneTriangle& t = index.triangles()[k];
      const TriangleMesh& mesh = scene.meshes[t.mesh];
      EXPECT_EQ(Casts(mesh.role), c.casts) << "a cluster across groups";
      receives = receives || Receives(mesh.role);
      for (int v = 0; v < 3; ++v) {
        const glm::dvec3& p = mesh.positions_world[mesh.indices[3 * t.triangle + v]];
        EXPECT_TRUE(glm::all(glm::lessThanEqual(c.lo, p)) && glm::all(glm::lessThanEqual(p, c.hi)));
      }
    }
    EXPECT_EQ(c.receives, receives);
    box_area += (c.hi.x - c.lo.x) * (c.hi.z - c.lo.z);
  }
  EXPECT_EQ(next, 1500u);
  // Spatial runs: the boxes together cover far less than as many boxes of the whole field (3.4
  // of its 13 here; a random order covers ~13).
  EXPECT_LT(box_area, index.clusters().size() * 200.0 * 200.0 / 3);
  // The tree: each box bounds its children, up to one root.
  ASSERT_FALSE(index.tree().empty());
  EXPECT_EQ(index.tree().back().size(), 1u);
  for (size_t level = 0; level < index.tree().size(); ++level) {
    for (size_t i = 0; i < index.tree()[level].size(); ++i) {
      const SceneIndex::Box& box = index.tree()[level][i];
      const size_t n = level == 0 ? index.clusters().size() : index.tree()[level - 1].size();
      for (size_t c = 8 * i; c < std::min(n, 8 * i + 8); ++c) {
        const glm::dvec3 lo = level == 0 ? index.clusters()[c].lo : index.tree()[level - 1][c].lo;
        const glm::dvec3 hi = level == 0 ? index.clusters()[c].hi : index.tree()[level - 1][c].hi;
        EXPECT_TRUE(glm::all(glm::lessThanEqual(box.lo, lo)) &&
                    glm::all(glm::lessThanEqual(hi, box.hi)));
      }
    }
  }
}

// The order depends only on the scene: two builds agree, and the casters' masks are grouped.
TEST(SceneIndex, SameSceneSameOrder) {
  const Scene scene = ThreeRoles();
  const auto a = SceneIndex::Build(scene), b = SceneIndex::Build(scene);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ((*a)->triangles().size(), (*b)->triangles().size());
  for (size_t k = 0; k < (*a)->triangles().size(); ++k) {
    EXPECT_EQ((*a)->triangles()[k].mesh, (*b)->triangles()[k].mesh);
    EXPECT_EQ((*a)->triangles()[k].triangle, (*b)->triangles()[k].triangle);
  }
}

TEST(SceneIndex, AnEmptySceneHasNoClusters) {
  Scene scene;
  const auto index = SceneIndex::Build(scene);
  ASSERT_TRUE(index.ok());
  EXPECT_TRUE((*index)->empty());
  EXPECT_TRUE((*index)->clusters().empty());
  EXPECT_TRUE((*index)->tree().empty());
}

// A light box holds every point of its world box as the plan will hold it: transformed, then
// rounded to float; also for a world 10^5 units from its origin and a light far from it.
TEST(LightBoxOf, HoldsEveryPointAsAPlanRoundsIt) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1), unit(0, 1);
  for (const double offset : {0.0, 1e5}) {
    for (int trial = 0; trial < 200; ++trial) {
      const glm::dvec3 normal = glm::normalize(glm::dvec3(u(rng), u(rng), u(rng)));
      const LightFrame frame = MakeLightFrame(
          glm::dvec3(offset) + 50.0 * glm::dvec3(u(rng), u(rng), u(rng)), normal, nullptr);
      const glm::dvec3 lo = glm::dvec3(offset) + 100.0 * glm::dvec3(u(rng), u(rng), u(rng));
      const glm::dvec3 hi = lo + 10.0 * glm::dvec3(unit(rng), unit(rng), unit(rng));
      const LightBox box = LightBoxOf(frame, lo, hi);
      for (int k = 0; k < 64; ++k) {
        // Corners (k < 8) and points inside.
        const glm::dvec3 f = k < 8 ? glm::dvec3(k & 1, (k >> 1) & 1, (k >> 2) & 1)
                                   : glm::dvec3(unit(rng), unit(rng), unit(rng));
        const glm::dvec3 p = glm::dvec3(glm::vec3(frame.LightFromWorld(lo + f * (hi - lo))));
        ASSERT_TRUE(glm::all(glm::lessThanEqual(box.lo, p)) &&
                    glm::all(glm::lessThanEqual(p, box.hi)))
            << "trial " << trial << " offset " << offset;
      }
    }
  }
}

}  // namespace
}  // namespace pdsm
