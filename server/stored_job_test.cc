#include "server/stored_job.h"

#include <filesystem>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "core/bake/bake_plan.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pipeline/tile_file.h"
#include "core/pipeline/unreached_tile.h"
#include "core/scene/scene_loader.h"
#include "core/util/fault_injecting_file_system.h"
#include "tests/test_support.h"
#include "tests/write_faults.h"

namespace pdsm {
namespace {

using testing::TempDir;

std::shared_ptr<const BakePlan> TinyPlan(int width = 16, int height = 8) {
  pdsm::v1::BakeParams overrides;
  overrides.add_resolution(width);
  overrides.add_resolution(height);
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
  void SetUp() override { Init(TinyPlan()); }
  void Init(std::shared_ptr<const BakePlan> plan) {
    absl::StatusOr<std::unique_ptr<JobStore>> store = JobStore::Open(dir_.path().string());
    ASSERT_TRUE(store.ok()) << store.status();
    store_ = *std::move(store);
    plan_ = std::move(plan);
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

// Every failure of the log's writes and syncs, at every call of a store and its commit, fails
// the job's call, and leaves a log that reopens with every committed tile as it was: the tile
// being stored is done only if its commit returned OK.
TEST_F(StoredJobTest, AFailedStoreOrCommitLosesNoCommittedTile) {
  const JobPaths paths(dir_.path().string(), record_.job_id);
  {
    std::shared_ptr<StoredJob> job = Job(nullptr);
    ASSERT_TRUE(job->LightOutput(0)->StoreTile(Tile(*plan_, 0, 0.25f)).ok());
    ASSERT_TRUE(job->LightOutput(0)->CommitTiles().ok());
  }
  const std::string committed = testing::ReadBytes(paths.log);
  const auto store_and_commit = [&](FileSystem* fs) {
    std::shared_ptr<StoredJob> job = Job(fs);
    absl::StatusOr<std::vector<int>> resumed = job->ResumeTiles(*store_->DoneTiles(record_.job_id));
    if (!resumed.ok()) return resumed.status();
    if (absl::Status s = job->LightOutput(0)->StoreTile(Tile(*plan_, 1, 0.75f)); !s.ok()) return s;
    return job->LightOutput(0)->CommitTiles();
  };
  FaultInjectingFileSystem counting;
  ASSERT_TRUE(store_and_commit(&counting).ok());
  const int writes = counting.op_count(FileOp::kWrite), syncs = counting.op_count(FileOp::kSync);
  ASSERT_GT(writes, 0);
  ASSERT_GT(syncs, 0);
  for (const FileOp op : {FileOp::kCreate, FileOp::kWrite, FileOp::kSync}) {
    const int calls = op == FileOp::kWrite ? writes : op == FileOp::kSync ? syncs : 1;
    for (int n = 1; n <= calls; ++n) {
      SCOPED_TRACE(absl::StrCat(FileOpName(op), " ", n));
      ASSERT_TRUE(store_->MarkTileUndone(record_.job_id, 1).ok());
      testing::WriteText(paths.log, committed);
      FaultInjectingFileSystem fs;
      fs.FailNth(op, n);
      const absl::Status s = store_and_commit(&fs);
      EXPECT_FALSE(s.ok());
      EXPECT_EQ(*store_->DoneTiles(record_.job_id), std::vector<int>{0});
      std::shared_ptr<StoredJob> reopened = Job(nullptr);
      ASSERT_TRUE(reopened->ResumeTiles(*store_->DoneTiles(record_.job_id)).ok());
      EXPECT_EQ(reopened->FinishedTiles(0), std::vector<int>{0});
      absl::StatusOr<std::string> bytes = reopened->FinishedTileBytes(0, 0);
      ASSERT_TRUE(bytes.ok()) << bytes.status();
      EXPECT_EQ(DecodeTileFile(*bytes, "tile 0")->vertices, Tile(*plan_, 0, 0.25f).vertices);
    }
  }
  // A full disk in the middle of the append.
  ASSERT_TRUE(store_->MarkTileUndone(record_.job_id, 1).ok());
  testing::WriteText(paths.log, committed);
  FaultInjectingFileSystem full;
  full.SetDiskFullAfter(100);
  EXPECT_EQ(store_and_commit(&full).code(), absl::StatusCode::kResourceExhausted);
  EXPECT_EQ(testing::ReadBytes(paths.log), committed);  // the torn record was cut off again
  EXPECT_TRUE(store_and_commit(nullptr).ok());
  EXPECT_EQ(*store_->DoneTiles(record_.job_id), (std::vector<int>{0, 1}));
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
  EXPECT_EQ(job->FinishedTiles(0), std::vector<int>{0});  // stored, not yet committed
  EXPECT_TRUE(store_->DoneTiles(record_.job_id)->empty());
  ASSERT_TRUE(job->LightOutput(0)->CommitTiles().ok());
  EXPECT_EQ(*store_->DoneTiles(record_.job_id), std::vector<int>{0});
  EXPECT_TRUE(std::filesystem::exists(paths.log));
  job->LightOutput(0)->Ended(JobEnd::kFailed, absl::InternalError("gl broke"), JobProgress{});
  absl::StatusOr<JobRecord> record = store_->GetJob(record_.job_id);
  EXPECT_EQ(record->state, pdsm::v1::FAILED);
  EXPECT_EQ(record->error, "gl broke");
  EXPECT_FALSE(std::filesystem::exists(paths.log));
  EXPECT_TRUE(job->ended());
  // A tile finishing after the end is not recorded as done.
  ASSERT_TRUE(job->LightOutput(0)->StoreTile(Tile(*plan_, 1, 1.0f)).ok());
  ASSERT_TRUE(job->LightOutput(0)->CommitTiles().ok());
  EXPECT_EQ(*store_->DoneTiles(record_.job_id), std::vector<int>{0});
}

// A tile a task found all lit (what the plan alone makes again) is its row alone: no file, yet
// finished, served and written into the PDSM as the plan makes it, also after a restart (a new
// StoredJob on the same store); the file is the one its tiles written directly give.
TEST_F(StoredJobTest, AnAllLitTileIsARowNotAFile) {
  const JobPaths paths(dir_.path().string(), record_.job_id);
  ASSERT_EQ(plan_->tile_count(), 2);
  ASSERT_FALSE(IsUnreachedTile(*plan_, 1));  // else the plan alone would say so
  const PdsmTile lit = MakeUnreachedTile(*plan_, 1).tile;
  const PdsmTile shadowed = Tile(*plan_, 0, 0.5f);
  {
    std::shared_ptr<StoredJob> job = Job(nullptr);
    ASSERT_TRUE(job->LightOutput(0)->StoreTile(lit).ok());
    ASSERT_TRUE(job->LightOutput(0)->CommitTiles().ok());
  }
  EXPECT_EQ(*store_->AllLitTiles(record_.job_id), std::vector<int>{1});
  EXPECT_EQ(*store_->DoneTiles(record_.job_id), std::vector<int>{1});

  std::shared_ptr<StoredJob> restarted = Job(nullptr);
  ASSERT_EQ(*restarted->ResumeTiles({1}), std::vector<int>{1});
  EXPECT_EQ(std::filesystem::file_size(paths.log), 16u) << "an all-lit tile got a record";
  EXPECT_EQ(restarted->FinishedTiles(0), std::vector<int>{1});
  absl::StatusOr<std::string> served = restarted->FinishedTileBytes(0, 1);
  ASSERT_TRUE(served.ok()) << served.status();
  absl::StatusOr<PdsmTile> read = DecodeTileFile(*served, "served");
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->offsets, lit.offsets);
  EXPECT_TRUE(read->vertices.empty());
  EXPECT_EQ(restarted->FinishedTileBytes(0, 0).status().code(), absl::StatusCode::kNotFound);

  ASSERT_TRUE(restarted->LightOutput(0)->StoreTile(shadowed).ok());
  ASSERT_TRUE(restarted->LightOutput(0)->Finish().ok());
  const std::string direct = dir_.File("direct.exr");
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer = PdsmWriter::Create(direct, plan_->header);
  ASSERT_TRUE(writer.ok()) << writer.status();
  ASSERT_TRUE((*writer)->WriteTile(shadowed).ok());
  ASSERT_TRUE((*writer)->WriteTile(lit).ok());
  ASSERT_TRUE((*writer)->Finish().ok());
  EXPECT_TRUE(testing::ReadBytes(paths.pdsm) == testing::ReadBytes(direct));
}

// A tile stored all lit and then with a shadow (a withdrawn tile computed again) is a file
// again, and the other way round: the row's flag follows the last store.
TEST_F(StoredJobTest, TheLastStoreOfATileDecidesWhetherItIsAFile) {
  const JobPaths paths(dir_.path().string(), record_.job_id);
  std::shared_ptr<StoredJob> job = Job(nullptr);
  const std::shared_ptr<JobOutput> output = job->LightOutput(0);
  ASSERT_TRUE(output->StoreTile(MakeUnreachedTile(*plan_, 1).tile).ok());
  ASSERT_TRUE(output->CommitTiles().ok());
  ASSERT_TRUE(output->WithdrawTiles({1}).ok());
  EXPECT_TRUE(job->FinishedTiles(0).empty());
  EXPECT_TRUE(store_->DoneTiles(record_.job_id)->empty());
  ASSERT_TRUE(output->StoreTile(Tile(*plan_, 1, 0.25f)).ok());
  ASSERT_TRUE(output->CommitTiles().ok());
  EXPECT_TRUE(store_->AllLitTiles(record_.job_id)->empty());
  EXPECT_EQ(DecodeTileFile(*job->FinishedTileBytes(0, 1), "tile 1")->vertices,
            Tile(*plan_, 1, 0.25f).vertices);
  ASSERT_TRUE(output->StoreTile(MakeUnreachedTile(*plan_, 1).tile).ok());
  ASSERT_TRUE(output->CommitTiles().ok());
  EXPECT_TRUE(DecodeTileFile(*job->FinishedTileBytes(0, 1), "tile 1")->vertices.empty());
  EXPECT_EQ(*store_->AllLitTiles(record_.job_id), std::vector<int>{1});
  std::shared_ptr<StoredJob> restarted = Job(nullptr);
  ASSERT_EQ(*restarted->ResumeTiles({1}), std::vector<int>{1});
  EXPECT_EQ(restarted->FinishedTiles(0), std::vector<int>{1});
  EXPECT_TRUE(DecodeTileFile(*restarted->FinishedTileBytes(0, 1), "tile 1")->vertices.empty());
}

// A withdrawn tile still pending (stored, its stage not committed) is not marked done by the
// commit that follows.
TEST_F(StoredJobTest, AWithdrawnTileIsNotCommitted) {
  std::shared_ptr<StoredJob> job = Job(nullptr);
  const std::shared_ptr<JobOutput> output = job->LightOutput(0);
  ASSERT_TRUE(output->StoreTile(Tile(*plan_, 0, 0.5f)).ok());
  ASSERT_TRUE(output->StoreTile(Tile(*plan_, 1, 0.5f)).ok());
  ASSERT_TRUE(output->WithdrawTiles({1}).ok());
  ASSERT_TRUE(output->CommitTiles().ok());
  EXPECT_EQ(*store_->DoneTiles(record_.job_id), std::vector<int>{0});
  EXPECT_EQ(job->FinishedTiles(0), std::vector<int>{0});
}

// A restart keeps what the store and the log agree on: a record without a row (its stage never
// committed: the coordinator died first) is not a finished tile, and a done tile whose record
// is gone (a log cut short) loses its row, to be computed again.
TEST_F(StoredJobTest, AResumedJobKeepsWhatTheStoreAndTheLogAgreeOn) {
  const JobPaths paths(dir_.path().string(), record_.job_id);
  uint64_t committed_size = 0;
  {
    std::shared_ptr<StoredJob> job = Job(nullptr);
    ASSERT_TRUE(job->LightOutput(0)->StoreTile(Tile(*plan_, 0, 0.5f)).ok());
    ASSERT_TRUE(job->LightOutput(0)->CommitTiles().ok());
    committed_size = std::filesystem::file_size(paths.log);
    ASSERT_TRUE(job->LightOutput(0)->StoreTile(Tile(*plan_, 1, 0.5f)).ok());  // never committed
  }
  {
    std::shared_ptr<StoredJob> restarted = Job(nullptr);
    EXPECT_EQ(*restarted->ResumeTiles(*store_->DoneTiles(record_.job_id)), std::vector<int>{0});
    EXPECT_EQ(restarted->FinishedTiles(0), std::vector<int>{0});
    EXPECT_EQ(restarted->FinishedTileBytes(0, 1).status().code(), absl::StatusCode::kNotFound);
  }
  std::filesystem::resize_file(paths.log, committed_size - 5);  // tile 0's record torn
  std::shared_ptr<StoredJob> restarted = Job(nullptr);
  EXPECT_TRUE(restarted->ResumeTiles(*store_->DoneTiles(record_.job_id))->empty());
  EXPECT_TRUE(store_->DoneTiles(record_.job_id)->empty());
  EXPECT_TRUE(restarted->FinishedTiles(0).empty());
}

// A job an earlier build ran keeps the tile files it stored: they go into the log, and the
// PDSM is the one its tiles give.
TEST_F(StoredJobTest, TheTileFilesOfAnEarlierBuildAreTakenIn) {
  const JobPaths paths(dir_.path().string(), record_.job_id);
  std::filesystem::create_directories(paths.tiles);
  const PdsmTile first = Tile(*plan_, 0, 0.5f), second = Tile(*plan_, 1, 0.25f);
  testing::WriteText(paths.Tile(0), *EncodeTileFile(first, plan_->header.tile_size, "first"));
  testing::WriteText(paths.Tile(1), EncodeEarlierTileFile(second));  // version 1
  testing::WriteText(paths.Tile(1) + ".tmp-abcdef", "a writer that died");
  ASSERT_TRUE(store_->MarkTilesDone(record_.job_id, {0, 1}, 1).ok());

  std::shared_ptr<StoredJob> job = Job(nullptr);
  ASSERT_EQ(*job->ResumeTiles({0, 1}), (std::vector<int>{0, 1}));
  EXPECT_FALSE(std::filesystem::exists(paths.tiles));
  EXPECT_EQ(job->FinishedTiles(0), (std::vector<int>{0, 1}));
  ASSERT_TRUE(job->LightOutput(0)->Finish().ok());
  const std::string direct = dir_.File("direct.exr");
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer = PdsmWriter::Create(direct, plan_->header);
  ASSERT_TRUE(writer.ok()) << writer.status();
  ASSERT_TRUE((*writer)->WriteTile(first).ok());
  ASSERT_TRUE((*writer)->WriteTile(second).ok());
  ASSERT_TRUE((*writer)->Finish().ok());
  EXPECT_TRUE(testing::ReadBytes(paths.pdsm) == testing::ReadBytes(direct));
}

// Stores, commits and withdrawals from several threads at once, as the coordinator's executor
// and its verification make them: every tile ends done exactly when its last word was a store
// followed by a commit, and a restart finds the same tiles with the same bytes.
class StoredJobThreadsTest : public StoredJobTest {
 protected:
  void SetUp() override {}
};

TEST_F(StoredJobThreadsTest, ConcurrentStoresCommitsAndWithdrawalsKeepTheStoreAndLogInStep) {
  Init(TinyPlan(64, 64));  // 64 tiles of 8 x 8
  const int tiles = plan_->tile_count();
  // Every third tile is all lit (a row without a record), and so is every tile no caster
  // reaches (the plan makes those, whatever was stored).
  const auto tile_of = [&](int tile) {
    return tile % 3 == 0 || IsUnreachedTile(*plan_, tile)
               ? MakeUnreachedTile(*plan_, tile).tile
               : Tile(*plan_, tile, 0.25f + 0.01f * tile);
  };
  int shadowed = 0;
  for (int tile = 0; tile < tiles; ++tile) shadowed += tile_of(tile).vertices.empty() ? 0 : 1;
  ASSERT_GE(shadowed, 16) << "the test needs tiles stored as records";
  ASSERT_EQ(tiles, 64);
  std::shared_ptr<StoredJob> job = Job(nullptr);
  ASSERT_TRUE(job->ResumeTiles({}).ok());
  const std::shared_ptr<JobOutput> output = job->LightOutput(0);
  constexpr int kThreads = 4;
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int tile = t; tile < tiles; tile += kThreads) {
        EXPECT_TRUE(output->StoreTile(tile_of(tile)).ok());
        if (tile % 2 == 0) EXPECT_TRUE(output->CommitTiles().ok());
      }
      EXPECT_TRUE(output->CommitTiles().ok());
    });
  }
  // Verification taking tiles back meanwhile: those of 5 mod 8, whenever it gets to them.
  threads.emplace_back([&] {
    for (int tile = 5; tile < tiles; tile += 8) EXPECT_TRUE(output->WithdrawTiles({tile}).ok());
  });
  for (std::thread& thread : threads) thread.join();
  // A withdrawal can come before or after its tile's store and commit; the withdrawn tiles are
  // stored and committed once more, as the engine would recompute them.
  for (int tile = 5; tile < tiles; tile += 8) {
    ASSERT_TRUE(output->StoreTile(tile_of(tile)).ok());
  }
  ASSERT_TRUE(output->CommitTiles().ok());
  std::vector<int> all(tiles);
  for (int tile = 0; tile < tiles; ++tile) all[tile] = tile;
  EXPECT_EQ(*store_->DoneTiles(record_.job_id), all);
  EXPECT_EQ(store_->GetJob(record_.job_id)->tiles_done, tiles);

  std::shared_ptr<StoredJob> restarted = Job(nullptr);
  ASSERT_EQ(*restarted->ResumeTiles(all), all);
  EXPECT_EQ(restarted->FinishedTiles(0), all);
  for (int tile = 0; tile < tiles; ++tile) {
    absl::StatusOr<std::string> bytes = restarted->FinishedTileBytes(0, tile);
    ASSERT_TRUE(bytes.ok()) << bytes.status();
    absl::StatusOr<PdsmTile> read = DecodeTileFile(*bytes, "tile");
    ASSERT_TRUE(read.ok()) << read.status();
    EXPECT_EQ(read->vertices, tile_of(tile).vertices) << "tile " << tile;
  }
}

}  // namespace
}  // namespace pdsm
