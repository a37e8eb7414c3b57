#include "server/job_store.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

using ::pdsm::testing::TempDir;
using ::pdsm::testing::WriteText;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

std::unique_ptr<JobStore> OpenOrDie(const std::string& dir) {
  absl::StatusOr<std::unique_ptr<JobStore>> store = JobStore::Open(dir);
  EXPECT_TRUE(store.ok()) << store.status();
  return store.ok() ? *std::move(store) : nullptr;
}

// A job whose fields all differ from their defaults; its scene holds NUL and high bytes.
JobRecord SampleJob(int n) {
  JobRecord job;
  job.job_id = absl::StrFormat("%016x", 0xabcdef0000000000ull + n);
  job.idempotency_key = absl::StrCat("key-", n);
  job.scene_name = absl::StrCat("scene ", n);
  job.state = pdsm::v1::QUEUED;
  job.priority = 10 - n;
  job.error = "";
  job.tiles_total = 16;
  job.samples_total = 16 * 4096;
  job.created_unix_ms = 1'700'000'000'000 + n;
  job.updated_unix_ms = 1'700'000'000'000 + n;
  job.pdsm_bytes = 0;
  job.width = 512;
  job.height = 256;
  job.samples = 4096;
  job.scene = std::string("\x0a\x05plate\x00\x00\xff\x80 end", 16) + std::to_string(n);
  return job;
}

JobRecord CreateOrDie(JobStore& store, const JobRecord& job) {
  bool created = false;
  absl::StatusOr<JobRecord> result = store.CreateJob(job, &created);
  EXPECT_TRUE(result.ok()) << result.status();
  EXPECT_TRUE(created);
  return result.ok() ? *result : JobRecord();
}

void ExpectSameJob(const JobRecord& a, const JobRecord& b) {
  EXPECT_EQ(a.job_id, b.job_id);
  EXPECT_EQ(a.idempotency_key, b.idempotency_key);
  EXPECT_EQ(a.scene_name, b.scene_name);
  EXPECT_EQ(a.state, b.state);
  EXPECT_EQ(a.priority, b.priority);
  EXPECT_EQ(a.sequence, b.sequence);
  EXPECT_EQ(a.error, b.error);
  EXPECT_EQ(a.tiles_total, b.tiles_total);
  EXPECT_EQ(a.samples_total, b.samples_total);
  EXPECT_EQ(a.tile_assemblies, b.tile_assemblies);
  EXPECT_EQ(a.tiles_done, b.tiles_done);
  EXPECT_EQ(a.created_unix_ms, b.created_unix_ms);
  EXPECT_EQ(a.updated_unix_ms, b.updated_unix_ms);
  EXPECT_EQ(a.pdsm_bytes, b.pdsm_bytes);
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.samples, b.samples);
  EXPECT_EQ(a.scene, b.scene);
}

std::vector<std::string> Ids(const std::vector<JobRecord>& jobs) {
  std::vector<std::string> ids;
  for (const JobRecord& job : jobs) ids.push_back(job.job_id);
  return ids;
}

TEST(JobStoreTest, CreateThenGetRoundTrips) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  const JobRecord job = SampleJob(1);
  ASSERT_EQ(job.scene.size(), 17u);  // the NUL bytes are in it
  const JobRecord created = CreateOrDie(*store, job);
  EXPECT_GT(created.sequence, 0);
  absl::StatusOr<JobRecord> read = store->GetJob(job.job_id);
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectSameJob(*read, created);
  JobRecord expected = job;
  expected.sequence = created.sequence;
  ExpectSameJob(*read, expected);
}

TEST(JobStoreTest, EmptySceneAndExtremeValuesRoundTrip) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  JobRecord job = SampleJob(2);
  job.scene.clear();
  job.samples_total = int64_t{1} << 50;
  job.priority = -1000;
  const JobRecord created = CreateOrDie(*store, job);
  ASSERT_TRUE(store->SetSucceeded(job.job_id, ~uint64_t{0} - 5, 42).ok());
  absl::StatusOr<JobRecord> read = store->GetJob(job.job_id);
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->scene, "");
  EXPECT_EQ(read->samples_total, int64_t{1} << 50);
  EXPECT_EQ(read->priority, -1000);
  EXPECT_EQ(read->pdsm_bytes, ~uint64_t{0} - 5);
  EXPECT_EQ(read->state, pdsm::v1::SUCCEEDED);
  EXPECT_EQ(read->updated_unix_ms, 42);
  EXPECT_EQ(read->sequence, created.sequence);
}

TEST(JobStoreTest, SameIdempotencyKeyReturnsTheFirstJob) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  const JobRecord first = CreateOrDie(*store, SampleJob(1));
  ASSERT_TRUE(store->MarkTileDone(first.job_id, 3, 5).ok());

  JobRecord retry = SampleJob(7);  // another id and scene, the same key
  retry.idempotency_key = first.idempotency_key;
  bool created = true;
  absl::StatusOr<JobRecord> again = store->CreateJob(retry, &created);
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_FALSE(created);
  JobRecord expected = first;
  expected.tile_assemblies = 1;
  expected.tiles_done = 1;
  expected.updated_unix_ms = 5;
  ExpectSameJob(*again, expected);
  EXPECT_EQ(store->GetJob(retry.job_id).status().code(), absl::StatusCode::kNotFound);
  absl::StatusOr<std::vector<JobRecord>> all = store->ListJobs(0);
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(all->size(), 1u);
}

TEST(JobStoreTest, SameJobIdWithAnotherKeyIsAlreadyExists) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  CreateOrDie(*store, SampleJob(1));
  JobRecord clash = SampleJob(1);
  clash.idempotency_key = "another key";
  EXPECT_EQ(store->CreateJob(clash, nullptr).status().code(), absl::StatusCode::kAlreadyExists);
}

TEST(JobStoreTest, EmptyIdsAreInvalid) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  JobRecord no_id = SampleJob(1);
  no_id.job_id.clear();
  JobRecord no_key = SampleJob(1);
  no_key.idempotency_key.clear();
  EXPECT_EQ(store->CreateJob(no_id, nullptr).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(store->CreateJob(no_key, nullptr).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(JobStoreTest, SequenceIsMonotonicAcrossReopen) {
  TempDir dir;
  std::vector<int64_t> sequences;
  {
    std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
    ASSERT_NE(store, nullptr);
    for (int n = 0; n < 5; ++n) sequences.push_back(CreateOrDie(*store, SampleJob(n)).sequence);
  }
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  for (int n = 5; n < 8; ++n) sequences.push_back(CreateOrDie(*store, SampleJob(n)).sequence);
  for (size_t i = 1; i < sequences.size(); ++i) {
    EXPECT_GT(sequences[i], sequences[i - 1]) << i;
  }
}

TEST(JobStoreTest, ListIsNewestFirstAndLimited) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  for (int n = 0; n < 5; ++n) CreateOrDie(*store, SampleJob(n));
  absl::StatusOr<std::vector<JobRecord>> three = store->ListJobs(3);
  ASSERT_TRUE(three.ok()) << three.status();
  EXPECT_THAT(Ids(*three),
              ElementsAre(SampleJob(4).job_id, SampleJob(3).job_id, SampleJob(2).job_id));
  for (const JobRecord& job : *three) EXPECT_THAT(job.scene, IsEmpty());
  EXPECT_EQ((*three)[0].scene_name, SampleJob(4).scene_name);

  absl::StatusOr<std::vector<JobRecord>> all = store->ListJobs(0);
  ASSERT_TRUE(all.ok()) << all.status();
  EXPECT_EQ(all->size(), 5u);
  absl::StatusOr<std::vector<JobRecord>> many = store->ListJobs(100);
  ASSERT_TRUE(many.ok()) << many.status();
  EXPECT_EQ(many->size(), 5u);
  EXPECT_EQ(many->back().job_id, SampleJob(0).job_id);
}

TEST(JobStoreTest, UnfinishedJobsAreQueuedOrRunningInSubmissionOrder) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  for (int n = 0; n < 6; ++n) CreateOrDie(*store, SampleJob(n));
  ASSERT_TRUE(store->SetState(SampleJob(0).job_id, pdsm::v1::RUNNING, "", 1).ok());
  ASSERT_TRUE(store->SetSucceeded(SampleJob(1).job_id, 1234, 2).ok());
  ASSERT_TRUE(store->SetState(SampleJob(2).job_id, pdsm::v1::FAILED, "tile 3 failed", 3).ok());
  ASSERT_TRUE(store->SetState(SampleJob(3).job_id, pdsm::v1::CANCELLED, "", 4).ok());
  ASSERT_TRUE(store->SetState(SampleJob(5).job_id, pdsm::v1::RUNNING, "", 5).ok());

  absl::StatusOr<std::vector<JobRecord>> unfinished = store->UnfinishedJobs();
  ASSERT_TRUE(unfinished.ok()) << unfinished.status();
  EXPECT_THAT(Ids(*unfinished),
              ElementsAre(SampleJob(0).job_id, SampleJob(4).job_id, SampleJob(5).job_id));
  for (const JobRecord& job : *unfinished) EXPECT_FALSE(job.scene.empty());
  EXPECT_EQ((*unfinished)[0].scene, SampleJob(0).scene);

  absl::StatusOr<JobRecord> failed = store->GetJob(SampleJob(2).job_id);
  ASSERT_TRUE(failed.ok());
  EXPECT_EQ(failed->state, pdsm::v1::FAILED);
  EXPECT_EQ(failed->error, "tile 3 failed");
  EXPECT_EQ(failed->updated_unix_ms, 3);
  absl::StatusOr<JobRecord> succeeded = store->GetJob(SampleJob(1).job_id);
  ASSERT_TRUE(succeeded.ok());
  EXPECT_EQ(succeeded->state, pdsm::v1::SUCCEEDED);
  EXPECT_EQ(succeeded->pdsm_bytes, 1234u);
}

TEST(JobStoreTest, MarkTileDoneCountsAssembliesIncludingRepeats) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  const std::string id = CreateOrDie(*store, SampleJob(1)).job_id;
  absl::StatusOr<std::vector<int>> none = store->DoneTiles(id);
  ASSERT_TRUE(none.ok()) << none.status();
  EXPECT_THAT(*none, IsEmpty());

  for (const int tile : {7, 0, 15, 7}) ASSERT_TRUE(store->MarkTileDone(id, tile, 100 + tile).ok());
  absl::StatusOr<std::vector<int>> done = store->DoneTiles(id);
  ASSERT_TRUE(done.ok()) << done.status();
  EXPECT_THAT(*done, ElementsAre(0, 7, 15));
  absl::StatusOr<JobRecord> job = store->GetJob(id);
  ASSERT_TRUE(job.ok());
  EXPECT_EQ(job->tiles_done, 3);
  EXPECT_EQ(job->tile_assemblies, 4);  // tile 7 twice: a recomputation
  EXPECT_EQ(job->updated_unix_ms, 107);
  absl::StatusOr<std::vector<JobRecord>> listed = store->ListJobs(1);
  ASSERT_TRUE(listed.ok());
  EXPECT_EQ((*listed)[0].tiles_done, 3);
  EXPECT_EQ((*listed)[0].tile_assemblies, 4);
}

TEST(JobStoreTest, AllLitTilesAreDoneAndTheLastMarkDecides) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  const std::string id = CreateOrDie(*store, SampleJob(1)).job_id;
  ASSERT_TRUE(store->MarkTilesDone(id, {3, 4, 5}, 10, /*all_lit=*/true).ok());
  ASSERT_TRUE(store->MarkTileDone(id, 6, 11).ok());
  ASSERT_TRUE(store->MarkTileDone(id, 4, 12).ok());  // computed again, with a shadow now
  EXPECT_THAT(*store->DoneTiles(id), ElementsAre(3, 4, 5, 6));
  EXPECT_THAT(*store->AllLitTiles(id), ElementsAre(3, 5));
  EXPECT_EQ(store->GetJob(id)->tiles_done, 4);
  EXPECT_EQ(store->AllLitTiles("ffffffffffffffff").status().code(), absl::StatusCode::kNotFound);
}

// A database of schema 1 (before all-lit tiles) is upgraded in place when opened: its done
// tiles stay done, none of them all lit.
TEST(JobStoreTest, ASchemaOneDatabaseIsUpgraded) {
  TempDir dir;
  std::string id;
  {
    std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
    ASSERT_NE(store, nullptr);
    id = CreateOrDie(*store, SampleJob(1)).job_id;
    ASSERT_TRUE(store->MarkTileDone(id, 2, 10).ok());
  }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((dir.path() / "jobs.db").string().c_str(), &db), SQLITE_OK);
  EXPECT_EQ(sqlite3_exec(db,
                         "ALTER TABLE done_tiles DROP COLUMN all_lit; "
                         "ALTER TABLE jobs DROP COLUMN tiles_done; PRAGMA user_version = 1;",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);

  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  EXPECT_THAT(*store->DoneTiles(id), ElementsAre(2));
  EXPECT_THAT(*store->AllLitTiles(id), IsEmpty());
  EXPECT_EQ(store->GetJob(id)->tiles_done, 1);
  ASSERT_TRUE(store->MarkTileDone(id, 3, 11, /*all_lit=*/true).ok());
  EXPECT_THAT(*store->AllLitTiles(id), ElementsAre(3));
  EXPECT_EQ(store->GetJob(id)->tiles_done, 2);
}

// A database of schema 2 (before jobs counted their done tiles) is upgraded in place when
// opened: each job's count is its done tiles', and counting goes on from there.
TEST(JobStoreTest, ASchemaTwoDatabaseIsUpgradedWithItsCounts) {
  TempDir dir;
  std::string first, second;
  {
    std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
    ASSERT_NE(store, nullptr);
    first = CreateOrDie(*store, SampleJob(1)).job_id;
    second = CreateOrDie(*store, SampleJob(2)).job_id;
    ASSERT_TRUE(store->MarkTilesDone(first, {1, 2, 3}, 10).ok());
    ASSERT_TRUE(store->MarkTileDone(second, 4, 10, /*all_lit=*/true).ok());
  }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((dir.path() / "jobs.db").string().c_str(), &db), SQLITE_OK);
  EXPECT_EQ(sqlite3_exec(db, "ALTER TABLE jobs DROP COLUMN tiles_done; PRAGMA user_version = 2;",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);

  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  EXPECT_EQ(store->GetJob(first)->tiles_done, 3);
  EXPECT_EQ(store->GetJob(second)->tiles_done, 1);
  EXPECT_THAT(*store->AllLitTiles(second), ElementsAre(4));
  ASSERT_TRUE(store->MarkTileDone(first, 2, 11).ok());  // again: no new tile
  ASSERT_TRUE(store->MarkTileUndone(first, 1).ok());
  EXPECT_EQ(store->GetJob(first)->tiles_done, 2);
  EXPECT_EQ((*store->ListJobs(0))[1].tiles_done, 2);  // newest first: `first` is second
}

// The count each job keeps equals its done tiles after any mix of marks, repeats, all-lit
// batches and withdrawals, in both directions across a reopen.
TEST(JobStoreTest, TheDoneCountFollowsEveryMarkAndWithdrawal) {
  TempDir dir;
  std::string id;
  std::mt19937 random(11);
  for (int round = 0; round < 2; ++round) {
    std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
    ASSERT_NE(store, nullptr);
    if (round == 0) id = CreateOrDie(*store, SampleJob(1)).job_id;  // 16 tiles
    for (int step = 0; step < 200; ++step) {
      const int tile = static_cast<int>(random() % 16);
      switch (random() % 3) {
        case 0:
          ASSERT_TRUE(store->MarkTileDone(id, tile, step, random() % 2 == 0).ok());
          break;
        case 1:
          ASSERT_TRUE(store->MarkTilesDone(id, {tile, (tile + 5) % 16}, step, true).ok());
          break;
        default:
          ASSERT_TRUE(store->MarkTileUndone(id, tile).ok());
      }
      ASSERT_EQ(store->GetJob(id)->tiles_done, static_cast<int>(store->DoneTiles(id)->size()))
          << "round " << round << " step " << step;
    }
  }
}

TEST(JobStoreTest, AWithdrawnTileIsNoLongerDoneUntilMarkedAgain) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  const std::string id = CreateOrDie(*store, SampleJob(1)).job_id;
  for (const int tile : {2, 5}) ASSERT_TRUE(store->MarkTileDone(id, tile, 10).ok());
  ASSERT_TRUE(store->MarkTileUndone(id, 5).ok());
  ASSERT_TRUE(store->MarkTileUndone(id, 9).ok());  // never done: no-op
  EXPECT_THAT(*store->DoneTiles(id), ElementsAre(2));
  ASSERT_TRUE(store->MarkTileDone(id, 5, 11).ok());  // recomputed
  EXPECT_THAT(*store->DoneTiles(id), ElementsAre(2, 5));
  absl::StatusOr<JobRecord> job = store->GetJob(id);
  ASSERT_TRUE(job.ok());
  EXPECT_EQ(job->tiles_done, 2);
  EXPECT_EQ(job->tile_assemblies, 3);  // the recomputation counts
  EXPECT_EQ(store->MarkTileUndone("no-such-job", 0).code(), absl::StatusCode::kNotFound);
}

TEST(JobStoreTest, MarkTilesDoneMarksABatchOrNothing) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  const std::string id = CreateOrDie(*store, SampleJob(1)).job_id;  // 16 tiles
  EXPECT_EQ(store->MarkTilesDone(id, {1, 2, 16}, 5).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(*store->DoneTiles(id), IsEmpty());  // nothing of a refused batch
  ASSERT_TRUE(store->MarkTilesDone(id, {9, 3, 4}, 6).ok());
  EXPECT_THAT(*store->DoneTiles(id), ElementsAre(3, 4, 9));
  absl::StatusOr<JobRecord> job = store->GetJob(id);
  ASSERT_TRUE(job.ok());
  EXPECT_EQ(job->tiles_done, 3);
  EXPECT_EQ(job->tile_assemblies, 3);
}

TEST(JobStoreTest, MarkTileDoneRejectsTilesOutsideTheJob) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  const std::string id = CreateOrDie(*store, SampleJob(1)).job_id;  // 16 tiles
  EXPECT_EQ(store->MarkTileDone(id, -1, 1).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(store->MarkTileDone(id, 16, 1).code(), absl::StatusCode::kInvalidArgument);
  absl::StatusOr<JobRecord> job = store->GetJob(id);
  ASSERT_TRUE(job.ok());
  EXPECT_EQ(job->tile_assemblies, 0);  // rolled back
  EXPECT_EQ(job->tiles_done, 0);
}

TEST(JobStoreTest, MissingJobIsNotFound) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  CreateOrDie(*store, SampleJob(1));
  const std::string missing = "0123456789abcdef";
  EXPECT_EQ(store->GetJob(missing).status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(store->GetJob(missing).status().message(), HasSubstr(missing));
  EXPECT_EQ(store->SetState(missing, pdsm::v1::FAILED, "x", 1).code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(store->SetSucceeded(missing, 1, 1).code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(store->MarkTileDone(missing, 0, 1).code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(store->DoneTiles(missing).status().code(), absl::StatusCode::kNotFound);
}

TEST(JobStoreTest, InvalidStateIsRejected) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  const std::string id = CreateOrDie(*store, SampleJob(1)).job_id;
  EXPECT_EQ(store->SetState(id, pdsm::v1::JOB_STATE_UNSPECIFIED, "", 1).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(store->SetState(id, static_cast<pdsm::v1::JobState>(99), "", 1).code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(JobStoreTest, StateSurvivesCloseAndReopen) {
  TempDir dir;
  const std::string data_dir = (dir.path() / "nested" / "data").string();  // created by Open
  JobRecord running, succeeded;
  {
    std::unique_ptr<JobStore> store = OpenOrDie(data_dir);
    ASSERT_NE(store, nullptr);
    running = CreateOrDie(*store, SampleJob(1));
    succeeded = CreateOrDie(*store, SampleJob(2));
    ASSERT_TRUE(store->SetState(running.job_id, pdsm::v1::RUNNING, "", 10).ok());
    ASSERT_TRUE(store->MarkTileDone(running.job_id, 2, 11).ok());
    ASSERT_TRUE(store->MarkTileDone(running.job_id, 5, 12).ok());
    ASSERT_TRUE(store->SetSucceeded(succeeded.job_id, 99, 13).ok());
  }
  std::unique_ptr<JobStore> store = OpenOrDie(data_dir);
  ASSERT_NE(store, nullptr);
  absl::StatusOr<std::vector<JobRecord>> unfinished = store->UnfinishedJobs();
  ASSERT_TRUE(unfinished.ok()) << unfinished.status();
  ASSERT_EQ(unfinished->size(), 1u);
  running.state = pdsm::v1::RUNNING;
  running.tiles_done = 2;
  running.tile_assemblies = 2;
  running.updated_unix_ms = 12;
  ExpectSameJob((*unfinished)[0], running);
  absl::StatusOr<std::vector<int>> done = store->DoneTiles(running.job_id);
  ASSERT_TRUE(done.ok());
  EXPECT_THAT(*done, ElementsAre(2, 5));
  absl::StatusOr<JobRecord> finished = store->GetJob(succeeded.job_id);
  ASSERT_TRUE(finished.ok());
  EXPECT_EQ(finished->state, pdsm::v1::SUCCEEDED);
  EXPECT_EQ(finished->pdsm_bytes, 99u);
}

TEST(JobStoreTest, ConcurrentWritersLoseNoUpdates) {
  TempDir dir;
  std::unique_ptr<JobStore> store = OpenOrDie(dir.path().string());
  ASSERT_NE(store, nullptr);
  constexpr int kThreads = 4;
  constexpr int kJobsPerThread = 5;
  JobRecord shared = SampleJob(100);
  shared.tiles_total = kThreads * 10;
  const std::string shared_id = CreateOrDie(*store, shared).job_id;

  std::vector<std::thread> threads;
  std::vector<absl::Status> errors(kThreads);
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < 10; ++i) {
        // Each thread finishes its own 10 tiles of the shared job, each twice.
        for (int repeat = 0; repeat < 2; ++repeat) {
          absl::Status s = store->MarkTileDone(shared_id, t * 10 + i, i);
          if (!s.ok() && errors[t].ok()) errors[t] = s;
        }
      }
      for (int j = 0; j < kJobsPerThread; ++j) {
        bool created = false;
        absl::StatusOr<JobRecord> job =
            store->CreateJob(SampleJob(t * kJobsPerThread + j), &created);
        if (!job.ok() && errors[t].ok()) errors[t] = job.status();
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (const absl::Status& s : errors) EXPECT_TRUE(s.ok()) << s;

  absl::StatusOr<JobRecord> job = store->GetJob(shared_id);
  ASSERT_TRUE(job.ok());
  EXPECT_EQ(job->tiles_done, kThreads * 10);
  EXPECT_EQ(job->tile_assemblies, kThreads * 10 * 2);
  absl::StatusOr<std::vector<JobRecord>> all = store->ListJobs(0);
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(all->size(), 1u + kThreads * kJobsPerThread);
}

// Two stores on one folder (as two processes would have): the busy timeout serializes them.
TEST(JobStoreTest, TwoConnectionsShareTheDatabase) {
  TempDir dir;
  std::unique_ptr<JobStore> a = OpenOrDie(dir.path().string());
  std::unique_ptr<JobStore> b = OpenOrDie(dir.path().string());
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  const std::string id = CreateOrDie(*a, SampleJob(1)).job_id;
  std::thread ta([&] {
    for (int i = 0; i < 8; ++i) EXPECT_TRUE(a->MarkTileDone(id, i, i).ok());
  });
  std::thread tb([&] {
    for (int i = 8; i < 16; ++i) EXPECT_TRUE(b->MarkTileDone(id, i, i).ok());
  });
  ta.join();
  tb.join();
  absl::StatusOr<JobRecord> job = b->GetJob(id);
  ASSERT_TRUE(job.ok());
  EXPECT_EQ(job->tiles_done, 16);
  EXPECT_EQ(job->tile_assemblies, 16);
}

TEST(JobStoreTest, NewerSchemaIsFailedPrecondition) {
  TempDir dir;
  ASSERT_NE(OpenOrDie(dir.path().string()), nullptr);
  const std::string db_path = (dir.path() / "jobs.db").string();
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(db_path.c_str(), &db), SQLITE_OK);
  const std::string pragma = absl::StrCat("PRAGMA user_version = ", JobStore::kSchemaVersion + 1);
  EXPECT_EQ(sqlite3_exec(db, pragma.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(db);

  absl::StatusOr<std::unique_ptr<JobStore>> store = JobStore::Open(dir.path().string());
  EXPECT_EQ(store.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(store.status().message(), HasSubstr(db_path));
}

TEST(JobStoreTest, NotADatabaseIsDataLoss) {
  TempDir dir;
  WriteText(dir.File("jobs.db"), std::string(4096, 'x'));
  absl::StatusOr<std::unique_ptr<JobStore>> store = JobStore::Open(dir.path().string());
  EXPECT_EQ(store.status().code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(store.status().message(), HasSubstr(dir.File("jobs.db")));
}

}  // namespace
}  // namespace pdsm
