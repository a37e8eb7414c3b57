// What the coordinator keeps of a job's lights (PlanJobLights): each light's plan without its
// render geometry, with the fingerprint of the whole plan (the one a worker's plan must
// match), and everything the coordinator tiles, numbers and assembles with unchanged; a
// surfaces-only plan keeps its receivers, which place the assembly's depth windows.
#include "server/job_admission.h"

#include <gtest/gtest.h>

#include "core/bake/plan_fingerprint.h"
#include "core/scene/scene_loader.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

using testing::TempDir;

class PlanJobLightsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    absl::StatusOr<std::unique_ptr<CoordinatorAssets>> assets =
        CoordinatorAssets::Open(dir_.File("assets"), 1 << 20);
    ASSERT_TRUE(assets.ok()) << assets.status();
    assets_ = *std::move(assets);
  }

  // The courtyard's three lights, planned by the coordinator and as the local bake plans them.
  void ExpectSlimPlansOf(const pdsm::v1::BakeParams& overrides) {
    const std::string path = testing::ExamplePath("courtyard");
    absl::StatusOr<pdsm::v1::Scene> message = ParseSceneFile(path, overrides);
    ASSERT_TRUE(message.ok()) << message.status();
    absl::StatusOr<std::vector<PlannedLight>> planned =
        PlanJobLights(*message, "scene", *assets_, nullptr);
    ASSERT_TRUE(planned.ok()) << planned.status();
    absl::StatusOr<Scene> scene = LoadSceneFile(path, overrides);
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_EQ(planned->size(), scene->LightCount());
    ASSERT_EQ(planned->size(), 3u);
    for (size_t i = 0; i < planned->size(); ++i) {
      absl::StatusOr<BakePlan> full = PlanBake(ForLight(*scene, i));
      ASSERT_TRUE(full.ok()) << full.status();
      const BakePlan& slim = *(*planned)[i].plan;
      ASSERT_GT(full->casters.TriangleCount(), 0u);
      EXPECT_EQ((*planned)[i].fingerprint, PlanFingerprint(*full)) << i;
      EXPECT_EQ(slim.casters.TriangleCount(), 0u) << i;
      EXPECT_TRUE(slim.caster_clusters.empty()) << i;
      EXPECT_EQ(slim.receivers.TriangleCount(),
                full->header.surfaces_only ? full->receivers.TriangleCount() : 0u)
          << i;
      EXPECT_EQ(slim.tile_count(), full->tile_count()) << i;
      EXPECT_EQ(slim.group_side, full->group_side) << i;
      EXPECT_EQ(slim.tile_has_casters, full->tile_has_casters) << i;
      EXPECT_EQ(slim.header.geometry.s_min, full->header.geometry.s_min) << i;
      EXPECT_EQ(slim.header.geometry.z_far, full->header.geometry.z_far) << i;
      EXPECT_EQ(slim.samples, full->samples) << i;
    }
  }

  TempDir dir_;
  std::unique_ptr<CoordinatorAssets> assets_;
};

TEST_F(PlanJobLightsTest, KeepsNoRenderGeometryAndTheWholePlansFingerprint) {
  ExpectSlimPlansOf({});
}

TEST_F(PlanJobLightsTest, ASurfacesOnlyPlanKeepsItsReceivers) {
  pdsm::v1::BakeParams overrides;
  overrides.set_surfaces_only(true);
  ExpectSlimPlansOf(overrides);
}

}  // namespace
}  // namespace pdsm
