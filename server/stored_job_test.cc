#include "server/stored_job.h"

#include <filesystem>

#include <gtest/gtest.h>

#include "core/bake/bake_plan.h"
#include "core/scene/scene_loader.h"
#include "tests/test_support.h"
#include "tests/write_faults.h"

namespace pdsm {
namespace {

using testing::TempDir;

std::shared_ptr<const BakePlan> TinyPlan() {
  pdsm::v1::BakeParams overrides;
  overrides.add_resolution(16);
  overrides.add_resolution(8);
  overrides.set_samples(2);
  overrides.set_tile_size(8);
  absl::StatusOr<Scene> scene = LoadSceneFile(testing::ExamplePath("plates"), overrides);
  EXPECT_TRUE(scene.ok()) << scene.status();
  absl::StatusOr<BakePlan> plan = PlanBake(*scene);
  EXPECT_TRUE(plan.ok()) << plan.status();
  return std::make_shared<const BakePlan>(*std::move(plan));
}

// A tile of the plan whose every pixel holds one step to `a` at depth 5.
PdsmTile Tile(const BakePlan& plan, int index, float a) {
  const TileRect r = plan.tile(index);
  PdsmTile tile{.x0 = r.x0, .y0 = r.y0, .width = r.width, .height = r.height};
  tile.offsets.push_back(0);
  for (int p = 0; p < r.width * r.height; ++p) {
    tile.vertices.push_back({5.0f, 0.0f});
    tile.vertices.push_back({5.0f, a});
    tile.offsets.push_back(tile.vertices.size());
  }
  return tile;
}

class StoredJobTest : public ::testing::Test {
 protected:
  void SetUp() override {
    absl::StatusOr<std::unique_ptr<JobStore>> store = JobStore::Open(dir_.path().string());
    ASSERT_TRUE(store.ok()) << store.status();
    store_ = *std::move(store);
    plan_ = TinyPlan();
    JobRecord record;
    record.job_id = "0123456789abcdef";
    record.idempotency_key = "k";
    record.tiles_total = plan_->tile_count();
    ASSERT_TRUE(store_->CreateJob(record, nullptr).ok());
    record_ = record;
  }
  std::shared_ptr<StoredJob> Job(FileSystem* fs) {
    return std::make_shared<StoredJob>(
        store_.get(), dir_.path().string(), record_, pdsm::v1::Scene(),
        std::vector<PlannedLight>{PlannedLight{plan_, "fingerprint"}}, nullptr, nullptr, fs);
  }

  TempDir dir_;
  std::unique_ptr<JobStore> store_;
  std::shared_ptr<const BakePlan> plan_;
  JobRecord record_;
};

TEST_F(StoredJobTest, TileFileIsWholeOrAsBefore) {
  const JobPaths paths(dir_.path().string(), record_.job_id);
  std::filesystem::create_directories(paths.tiles);
  ASSERT_TRUE(Job(nullptr)->LightOutput(0)->StoreTile(Tile(*plan_, 1, 0.25f)).ok());
  testing::ExpectWriteFailuresLeaveTargetIntact(paths.Tile(1), paths.tiles, [&](FileSystem* fs) {
    return Job(fs)->LightOutput(0)->StoreTile(Tile(*plan_, 1, 0.75f));
  });
  absl::StatusOr<std::vector<int>> done = store_->DoneTiles(record_.job_id);
  ASSERT_TRUE(done.ok());
  EXPECT_EQ(*done, std::vector<int>{1});
}

TEST_F(StoredJobTest, PdsmIsWholeOrAsBefore) {
  const JobPaths paths(dir_.path().string(), record_.job_id);
  for (const TileRect& r : AllTiles(*plan_)) {
    ASSERT_TRUE(Job(nullptr)->LightOutput(0)->StoreTile(Tile(*plan_, r.index, 0.5f)).ok());
  }
  testing::WriteText(paths.pdsm, "a PDSM of an earlier run");
  testing::ExpectWriteFailuresLeaveTargetIntact(
      paths.pdsm, paths.dir, [&](FileSystem* fs) { return Job(fs)->LightOutput(0)->Finish(); });
}

TEST_F(StoredJobTest, EndStatesReachTheStoreAndTheTilesGo) {
  const JobPaths paths(dir_.path().string(), record_.job_id);
  std::shared_ptr<StoredJob> job = Job(nullptr);
  job->LightOutput(0)->Started();
  EXPECT_EQ(store_->GetJob(record_.job_id)->state, pdsm::v1::RUNNING);
  ASSERT_TRUE(job->LightOutput(0)->StoreTile(Tile(*plan_, 0, 1.0f)).ok());
  EXPECT_EQ(job->FinishedTiles(0), std::vector<int>{0});
  job->LightOutput(0)->Ended(JobEnd::kFailed, absl::InternalError("gl broke"), JobProgress{});
  absl::StatusOr<JobRecord> record = store_->GetJob(record_.job_id);
  EXPECT_EQ(record->state, pdsm::v1::FAILED);
  EXPECT_EQ(record->error, "gl broke");
  EXPECT_FALSE(std::filesystem::exists(paths.tiles));
  EXPECT_TRUE(job->ended());
  // A tile finishing after the end is not recorded as done.
  ASSERT_TRUE(job->LightOutput(0)->StoreTile(Tile(*plan_, 1, 1.0f)).ok());
  EXPECT_EQ(*store_->DoneTiles(record_.job_id), std::vector<int>{0});
}

}  // namespace
}  // namespace pdsm
