// What the coordinator keeps of a job's lights (PlanJobLights): each light's plan without its
// render geometry, with the fingerprint of the whole plan (the one a worker's plan must
// match), and everything the coordinator tiles, numbers and assembles with unchanged; a
// surfaces-only plan keeps its receivers, which place the assembly's depth windows.
// And what that holds (JobHeldBytes, what --max-planned-mib counts), checked against the heap
// as the allocator's bytes in use grow; and the limit itself: a job is refused before anything
// is planned when its smallest plans exceed it, and as it is planned when its plans do.
#include "server/job_admission.h"

#include <malloc.h>

#include <functional>
#include <memory>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/bake/plan_fingerprint.h"
#include "core/bake/plan_memory.h"
#include "core/pipeline/engine_test_support.h"
#include "core/scene/scene_loader.h"
#include "tests/test_support.h"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define PDSM_SANITIZER_ALLOCATOR 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define PDSM_SANITIZER_ALLOCATOR 1
#endif
#endif
#ifdef PDSM_SANITIZER_ALLOCATOR
#include <sanitizer/allocator_interface.h>
#endif

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

// A refined light is planned with its receivers kept through the release (the coordinator
// chooses its refined pixels from them), and its level is planned as a worker plans it.
TEST_F(PlanJobLightsTest, ARefinedLightKeepsItsReceiversAndItsLevelIsTheWorkersPlan) {
  pdsm::v1::BakeParams overrides;
  overrides.set_max_refinement(4);
  absl::StatusOr<pdsm::v1::Scene> message =
      ParseSceneFile(testing::ExamplePath("courtyard"), overrides);
  ASSERT_TRUE(message.ok()) << message.status();
  absl::StatusOr<std::vector<PlannedLight>> plans =
      PlanJobLights(*message, "scene", *assets_, nullptr);
  ASSERT_TRUE(plans.ok()) << plans.status();
  ASSERT_EQ(plans->size(), 3u);  // its first light's level
  const BakePlan& base = *plans->front().plan;
  EXPECT_EQ(base.header.max_refinement, 4);
  EXPECT_GT(base.receivers.TriangleCount(), 0u);

  std::vector<std::vector<RefinedPixel>> by_tile(base.tile_count());
  const TileRect first = base.tile(0);
  by_tile[0] = {{first.x0, first.y0, {{base.geometry().z_near, base.geometry().z_far}}}};
  auto refined = std::make_shared<const RefinedPixels>(base.geometry(), base.header.tile_size, 4,
                                                       std::move(by_tile));
  absl::StatusOr<PlannedLight> level =
      PlanJobLightLevel(*message, "scene", *assets_, 0, base, refined);
  ASSERT_TRUE(level.ok()) << level.status();
  EXPECT_EQ(level->plan->geometry().width, 4 * base.geometry().width);
  EXPECT_EQ(level->plan->refinement, 4);
  EXPECT_TRUE(level->plan->casters.indices.empty()) << "released of its render geometry";
  EXPECT_GT(level->plan->receivers.TriangleCount(), 0u) << "its scan windows need them";

  // A worker's plan: the scene loaded on its own, the full base plan.
  int64_t triangles = 0;
  absl::StatusOr<Scene> scene =
      SceneFromProto(*message, "scene", "", assets_->Resolver(0, &triangles));
  ASSERT_TRUE(scene.ok()) << scene.status();
  absl::StatusOr<std::shared_ptr<const SceneIndex>> index = SceneIndex::Build(*scene);
  ASSERT_TRUE(index.ok()) << index.status();
  absl::StatusOr<BakePlan> worker_base = PlanBake(**index, 0);
  ASSERT_TRUE(worker_base.ok()) << worker_base.status();
  absl::StatusOr<BakePlan> worker_level = PlanRefinementLevel(**index, 0, *worker_base, refined);
  ASSERT_TRUE(worker_level.ok()) << worker_level.status();
  EXPECT_EQ(PlanFingerprint(*worker_level), level->fingerprint);
}

// Bytes the program's allocations hold now (the sanitizers replace malloc: ask theirs).
int64_t HeapBytesInUse() {
#ifdef PDSM_SANITIZER_ALLOCATOR
  return static_cast<int64_t>(__sanitizer_get_current_allocated_bytes());
#else
  const struct mallinfo2 info = mallinfo2();
  return static_cast<int64_t>(info.uordblks + info.hblkhd);  // small blocks + mmapped ones
#endif
}

class JobMemoryTest : public PlanJobLightsTest {
 protected:
  // The plates example at `resolution`^2 in `tile`-pixel tiles.
  static pdsm::v1::Scene Plates(int resolution, int tile, bool surfaces_only = false,
                                int group_side = 0) {
    pdsm::v1::BakeParams overrides;
    overrides.add_resolution(resolution);
    overrides.add_resolution(resolution);
    overrides.set_tile_size(tile);
    overrides.set_samples(16);
    if (surfaces_only) overrides.set_surfaces_only(true);
    if (group_side > 0) overrides.set_tile_group_size(group_side);
    absl::StatusOr<pdsm::v1::Scene> scene =
        ParseSceneFile(testing::ExamplePath("plates"), overrides);
    EXPECT_TRUE(scene.ok()) << scene.status();
    return scene.ok() ? *scene : pdsm::v1::Scene();
  }

  // The plates with a `side` x `side` grid of quads added below them as a receiver (ground
  // at y = -0.5, 8 x 8 units): a surfaces-only plan keeps it.
  static pdsm::v1::Scene PlatesOverGrid(int side) {
    pdsm::v1::Scene scene = Plates(256, 16, /*surfaces_only=*/true);
    pdsm::v1::InlineMesh* grid = scene.add_meshes()->mutable_inline_();
    scene.mutable_meshes(scene.meshes_size() - 1)->set_role(pdsm::v1::RECEIVER_ONLY);
    for (int j = 0; j <= side; ++j) {
      for (int i = 0; i <= side; ++i) {
        for (double v : {8.0 * i / side - 4, -0.5, 8.0 * j / side - 4}) grid->add_positions(v);
      }
    }
    for (int j = 0; j < side; ++j) {
      for (int i = 0; i < side; ++i) {
        const uint32_t a = j * (side + 1) + i, b = a + 1, c = a + side + 1, d = c + 1;
        for (uint32_t k : {a, c, b, b, c, d}) grid->add_indices(k);
      }
    }
    return scene;
  }

  // Heap bytes that planning `scene` and adding its lights to an engine leave held, with what
  // JobHeldBytes counts for them (less the scene, made before the measure).
  void Measure(const pdsm::v1::Scene& scene, int64_t* measured, int64_t* counted) {
    std::vector<std::function<void()>> queued;  // the engine's heavy work, never run here
    EngineOptions options;
    options.scheduler.verify_fraction = 0.02;  // the coordinator's default: per-tile records
    options.executor = [&queued](std::function<void()> work) { queued.push_back(std::move(work)); };
    auto engine = std::make_unique<BakeEngine>(std::move(options));
    auto output = std::make_shared<testing::RecordingOutput>();
    queued.reserve(16);
    const int64_t before = HeapBytesInUse();
    {
      absl::StatusOr<std::vector<PlannedLight>> plans =
          PlanJobLights(scene, "scene", *assets_, nullptr);
      ASSERT_TRUE(plans.ok()) << plans.status();
      for (size_t i = 0; i < plans->size(); ++i) {
        EngineJob job;
        job.job_id = "job/" + std::to_string(i);
        job.plan = (*plans)[i].plan;
        job.output = output;
        ASSERT_TRUE(engine->AddJob(std::move(job)).ok());
      }
      // What the engine queued (storing the unreached tiles: transient) is not held.
      queued.clear();
      *counted = JobHeldBytes(*plans, pdsm::v1::Scene()) - JobHeldBytes({}, pdsm::v1::Scene());
    }
    *measured = HeapBytesInUse() - before;
    engine.reset();
  }
};

TEST_F(JobMemoryTest, AJobHoldsABitPerTileNotARecord) {
  int64_t measured = 0, counted = 0;
  Measure(Plates(64, 4), &measured, &counted);  // warms up what is made once per process
  // 65,536 tiles in few groups: tiles and groups are made on demand, and the engine keeps a
  // stored bit per tile (it kept 3.35 MB of per-tile records before).
  Measure(Plates(1024, 4), &measured, &counted);
  std::printf("65,536 tiles: %lld bytes held, %lld counted\n", static_cast<long long>(measured),
              static_cast<long long>(counted));
  EXPECT_LT(measured, 32 << 10);
  EXPECT_GE(counted, measured);
  EXPECT_LE(counted, measured * 3 / 2);
}

TEST_F(JobMemoryTest, JobHeldBytesCountsWhatTheHeapHoldsForAJob) {
  int64_t measured = 0, counted = 0;
  Measure(Plates(64, 4), &measured, &counted);
  // What is per group: a group per tile, 65,536 of them.
  Measure(Plates(1024, 4, /*surfaces_only=*/false, /*group_side=*/1), &measured, &counted);
  std::printf("65,536 groups: %lld bytes held, %lld counted\n", static_cast<long long>(measured),
              static_cast<long long>(counted));
  ASSERT_GT(measured, 65536 * 32) << "the measure misses the groups' entries";
  EXPECT_GE(counted, measured);
  EXPECT_LE(counted, measured * 3 / 2);
  // Surfaces only: the receivers are kept too (a 200 x 200 grid: 40,401 vertices and 80,000
  // triangles, 1.4 MB in light space).
  Measure(PlatesOverGrid(200), &measured, &counted);
  std::printf("surfaces only: %lld bytes held, %lld counted\n", static_cast<long long>(measured),
              static_cast<long long>(counted));
  ASSERT_GT(measured, 40401 * 12 + 80000 * 12) << "the measure misses the receivers";
  EXPECT_GE(counted, measured);
  EXPECT_LE(counted, measured * 3 / 2);
}

TEST_F(JobMemoryTest, TheLowerBoundBeforePlanningNeverExceedsWhatAPlanHolds) {
  for (const bool surfaces_only : {false, true}) {
    for (const int tile : {1, 4, 16, 64}) {
      const pdsm::v1::Scene message = Plates(256, tile, surfaces_only);
      absl::StatusOr<Scene> scene = SceneFromProto(message, "scene", "", nullptr);
      ASSERT_TRUE(scene.ok()) << scene.status();
      int64_t vertices = 0, triangles = 0;
      for (const TriangleMesh& m : scene->meshes) {
        if (!Receives(m.role)) continue;
        vertices += static_cast<int64_t>(m.positions_world.size());
        triangles += static_cast<int64_t>(m.indices.size() / 3);
      }
      absl::StatusOr<BakePlan> plan = PlanBake(*scene);
      ASSERT_TRUE(plan.ok()) << plan.status();
      ReleaseRenderGeometry(&*plan);
      const int64_t lower = MinReleasedPlanBytes(scene->bake, vertices, triangles);
      EXPECT_LE(lower, PlanHeldBytes(*plan)) << "tile " << tile << " surfaces " << surfaces_only;
      // Tight where the tiles dominate: the grouping is all it leaves out.
      if (tile == 1) EXPECT_GE(lower, PlanHeldBytes(*plan) * 9 / 10);
    }
  }
}

// A refinement level (a plan that keeps the receivers, its refined pixels and their bands) and
// its engine job hold what LightHeldBytes counts: the coordinator adds it to its job's bytes
// when the level starts (server/plan_budget.h, Grow).
TEST_F(JobMemoryTest, LightHeldBytesCountsWhatARefinementLevelHolds) {
  pdsm::v1::Scene scene = Plates(256, 16);
  scene.mutable_bake()->set_max_refinement(4);
  absl::StatusOr<std::vector<PlannedLight>> plans =
      PlanJobLights(scene, "scene", *assets_, nullptr);
  ASSERT_TRUE(plans.ok()) << plans.status();
  const BakePlan& base = *plans->front().plan;
  // Every `stride`-th pixel refined, each with two bands.
  const auto measure = [&](int stride, int64_t* measured, int64_t* counted) {
    std::vector<std::function<void()>> queued;
    EngineOptions options;
    options.executor = [&queued](std::function<void()> work) { queued.push_back(std::move(work)); };
    auto engine = std::make_unique<BakeEngine>(std::move(options));
    auto output = std::make_shared<testing::RecordingOutput>();
    queued.reserve(16);
    const double z0 = base.geometry().z_near, z1 = base.geometry().z_far;
    const int64_t before = HeapBytesInUse();
    {
      std::vector<std::vector<RefinedPixel>> by_tile(base.tile_count());
      for (int t = 0; t < base.tile_count(); ++t) {
        const TileRect rect = base.tile(t);
        for (int y = rect.y0; y < rect.y0 + rect.height; ++y) {
          for (int x = rect.x0; x < rect.x0 + rect.width; ++x) {
            if ((y * base.geometry().width + x) % stride != 0) continue;
            by_tile[t].push_back({x, y, {{z0, z0 + (z1 - z0) / 4}, {(z0 + z1) / 2, z1}}});
          }
        }
      }
      auto refined = std::make_shared<const RefinedPixels>(base.geometry(), base.header.tile_size,
                                                           4, std::move(by_tile));
      absl::StatusOr<PlannedLight> level =
          PlanJobLightLevel(scene, "scene", *assets_, 0, base, std::move(refined));
      ASSERT_TRUE(level.ok()) << level.status();
      EngineJob job;
      job.job_id = "job/refined";
      job.plan = level->plan;
      job.output = output;
      ASSERT_TRUE(engine->AddJob(std::move(job)).ok());
      queued.clear();
      *counted = LightHeldBytes(*level->plan);
    }
    *measured = HeapBytesInUse() - before;
    engine.reset();
  };
  int64_t measured = 0, counted = 0;
  measure(64, &measured, &counted);  // warms up what is made once per process
  measure(3, &measured, &counted);   // 21,846 refined pixels of 65,536
  std::printf("a level of 21,846 refined pixels: %lld bytes held, %lld counted\n",
              static_cast<long long>(measured), static_cast<long long>(counted));
  ASSERT_GT(measured, 21846 * (8 + 32)) << "the measure misses the refined pixels";
  EXPECT_GE(counted, measured);
  EXPECT_LE(counted, measured * 3 / 2);
}

TEST_F(JobMemoryTest, AJobWhosePlansExceedTheLimitIsRefusedNamingTheFlag) {
  AdmissionLimits limits;
  // Before planning: 2^18 tiles need at least their 32 KiB of bits.
  limits.max_planned_bytes = 16 << 10;
  absl::Status refused = PlanJobLights(Plates(2048, 4), "scene", *assets_, &limits).status();
  EXPECT_EQ(refused.code(), absl::StatusCode::kResourceExhausted) << refused;
  EXPECT_NE(refused.message().find("would hold at least"), std::string::npos) << refused;
  EXPECT_NE(refused.message().find("--max-planned-mib"), std::string::npos) << refused;

  // As planned: a limit between the lower bound and what the plan holds (a group per tile,
  // which the lower bound leaves out).
  const pdsm::v1::Scene scene = Plates(1024, 4, /*surfaces_only=*/false, /*group_side=*/1);
  absl::StatusOr<std::vector<PlannedLight>> plans =
      PlanJobLights(scene, "scene", *assets_, nullptr);
  ASSERT_TRUE(plans.ok()) << plans.status();
  limits.max_planned_bytes = JobHeldBytes(*plans, scene) - 1;
  refused = PlanJobLights(scene, "scene", *assets_, &limits).status();
  EXPECT_EQ(refused.code(), absl::StatusCode::kResourceExhausted) << refused;
  EXPECT_NE(refused.message().find("hold"), std::string::npos) << refused;
  EXPECT_EQ(refused.message().find("at least"), std::string::npos) << refused;
  limits.max_planned_bytes += 1;
  EXPECT_TRUE(PlanJobLights(scene, "scene", *assets_, &limits).ok());
}

}  // namespace
}  // namespace pdsm
