#include "core/pipeline/bake_engine.h"

#include <algorithm>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "absl/synchronization/notification.h"
#include "core/pdsm/attenuation_function.h"
#include "core/pipeline/engine_test_support.h"
#include "core/util/fault_injecting_file_system.h"
#include "core/util/work_queue.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

using testing::BatchEvents;
using testing::InlineOptions;
using testing::Job;
using testing::LeaseEvents;
using testing::One;
using testing::RecordingOutput;
using testing::SmallPlan;

// Leases every task the engine hands out to one worker and reports it, in a shuffled order
// when `seed` is set. Returns the number of tasks run.
int RunAll(BakeEngine& engine, const BakePlan& plan, std::optional<unsigned> seed = {}) {
  int tasks = 0;
  std::mt19937 rng(seed.value_or(0));
  for (;;) {
    std::vector<TaskLease> leases;
    while (std::optional<TaskLease> lease = engine.Lease("w")) leases.push_back(*lease);
    if (leases.empty()) return tasks;
    if (seed) std::shuffle(leases.begin(), leases.end(), rng);
    for (const TaskLease& l : leases) {
      EXPECT_TRUE(engine.Report("w", l.lease_id, LeaseEvents(plan, l)));
      ++tasks;
    }
  }
}

TEST(BakeEngine, FixedCountJobStoresEveryTileFinishesAndEndsOnce) {
  const auto plan = SmallPlan(3, 8);
  auto output = std::make_shared<RecordingOutput>();
  BakeEngine engine(InlineOptions());
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 3)).ok());
  EXPECT_EQ(engine.Progress("j")->tasks_total, 9);  // 3 tiles x batches [0,3) [3,6) [6,8)
  EXPECT_EQ(RunAll(engine, *plan), 9);
  EXPECT_EQ(output->started(), 1);
  EXPECT_EQ(output->finished(), 1);
  EXPECT_EQ(output->ended(), 1);
  EXPECT_EQ(output->end(), JobEnd::kSucceeded);
  EXPECT_EQ(output->tiles().size(), 3u);
  const JobProgress p = output->progress();
  EXPECT_EQ(p.tiles_done, 3);
  EXPECT_EQ(p.tasks_done, 9);
  EXPECT_EQ(p.samples_done, p.samples_total);
  EXPECT_EQ(p.tile_samples_total, 24);
  EXPECT_FALSE(engine.Progress("j"));  // left the engine
  // Pixel 0 of tile 0: samples 0..7 enter at 2 + k % 3 and leave at 8. Between 4 and 8 all
  // eight are in shadow; between 2 and 3, the three with k % 3 == 0.
  const PdsmTile tile = output->tiles().at(0);
  EXPECT_FLOAT_EQ(EvaluateAttenuation(tile.Function(0, 0), 2.5), 3.0f / 8);
  EXPECT_FLOAT_EQ(EvaluateAttenuation(tile.Function(0, 0), 5.0), 1.0f);
  EXPECT_FLOAT_EQ(EvaluateAttenuation(tile.Function(0, 0), 9.0), 0.0f);
  EXPECT_TRUE(tile.Function(1, 0).empty());
}

TEST(BakeEngine, TilesDoNotDependOnBatchesOrArrivalOrder) {
  const auto plan = SmallPlan(2, 7);
  std::vector<std::map<int, PdsmTile>> results;
  for (const auto& [batch, seed] : std::vector<std::pair<int, std::optional<unsigned>>>{
           {0, std::nullopt}, {1, 5u}, {2, 9u}, {4, 1u}}) {
    auto output = std::make_shared<RecordingOutput>();
    BakeEngine engine(InlineOptions());
    ASSERT_TRUE(engine.AddJob(Job(plan, output, batch)).ok());
    RunAll(engine, *plan, seed);
    ASSERT_EQ(output->end(), JobEnd::kSucceeded);
    results.push_back(output->tiles());
  }
  for (size_t r = 1; r < results.size(); ++r) {
    for (int t = 0; t < 2; ++t) {
      EXPECT_EQ(results[r].at(t).vertices, results[0].at(t).vertices) << "run " << r;
      EXPECT_EQ(results[r].at(t).offsets, results[0].at(t).offsets) << "run " << r;
    }
  }
}

TEST(BakeEngine, SpillingPastTheBudgetChangesNoTileWhateverTheThreads) {
  // Groups of 3 tiles, 48 samples in batches of 2: with a budget of 1 byte every result
  // spills its group's lists, so each tile is merged back from up to 24 runs. Four threads
  // report at once (merges run outside the engine's lock) and the stage completes on the pool.
  const auto plan = SmallPlan(6, 48, 0, 0, /*group_size=*/3);
  std::map<int, PdsmTile> in_memory;
  {
    auto output = std::make_shared<RecordingOutput>();
    BakeEngine engine(InlineOptions());
    ASSERT_TRUE(engine.AddJob(Job(plan, output, 2)).ok());
    RunAll(engine, *plan, 7u);
    ASSERT_EQ(output->end(), JobEnd::kSucceeded);
    EXPECT_EQ(output->progress().spilled_bytes, 0);
    in_memory = output->tiles();
  }
  for (int round = 0; round < 3; ++round) {
    auto output = std::make_shared<RecordingOutput>();
    WorkQueue pool(2);
    EngineOptions options = InlineOptions();
    options.executor = [&pool](std::function<void()> work) { pool.Post(std::move(work)); };
    options.spill_dir = ::testing::TempDir();
    options.event_memory_budget_bytes = 1;
    BakeEngine engine(std::move(options));
    ASSERT_TRUE(engine.AddJob(Job(plan, output, 2)).ok());
    std::vector<std::thread> workers;
    for (int w = 0; w < 4; ++w) {
      workers.emplace_back([&, w] {
        const std::string id = "w" + std::to_string(w);
        // Until the job ends, however slow the machine: a group opens only once the one
        // before is assembled on the pool, which under load can take longer than one wait.
        while (output->ended() == 0) {
          if (std::optional<TaskLease> lease = engine.Lease(id, absl::Milliseconds(200))) {
            engine.Report(id, lease->lease_id, LeaseEvents(*plan, *lease));
          }
        }
      });
    }
    for (std::thread& t : workers) t.join();
    pool.Wait();
    ASSERT_EQ(output->ended(), 1);
    ASSERT_EQ(output->end(), JobEnd::kSucceeded) << output->status();
    EXPECT_GT(output->progress().spilled_bytes, 0);
    const std::map<int, PdsmTile> tiles = output->tiles();
    ASSERT_EQ(tiles.size(), in_memory.size());
    for (const auto& [t, tile] : in_memory) {
      EXPECT_EQ(tiles.at(t).vertices, tile.vertices) << "round " << round << " tile " << t;
      EXPECT_EQ(tiles.at(t).offsets, tile.offsets) << "round " << round << " tile " << t;
    }
  }
}

TEST(BakeEngine, AFailedSpillFailsTheJobNamingTheScratchFile) {
  const auto plan = SmallPlan(2, 8, 0, 0, /*group_size=*/2);
  auto output = std::make_shared<RecordingOutput>();
  FaultInjectingFileSystem fs;
  fs.SetDiskFullAfter(0);
  EngineOptions options = InlineOptions();
  options.spill_dir = ::testing::TempDir();
  options.event_memory_budget_bytes = 1;
  options.fs = &fs;
  BakeEngine engine(std::move(options));
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 2)).ok());
  const std::optional<TaskLease> first = engine.Lease("w");
  ASSERT_TRUE(first);
  EXPECT_TRUE(engine.Report("w", first->lease_id, LeaseEvents(*plan, *first)))
      << "taken, then the spill fails";
  EXPECT_FALSE(engine.Lease("w")) << "the job ended";
  ASSERT_EQ(output->ended(), 1);
  EXPECT_EQ(output->end(), JobEnd::kFailed);
  EXPECT_EQ(output->status().code(), absl::StatusCode::kResourceExhausted) << output->status();
  EXPECT_NE(output->status().message().find("moving event lists out of memory"), std::string::npos)
      << output->status();
  EXPECT_NE(output->status().message().find("scratch file"), std::string::npos) << output->status();
  EXPECT_EQ(output->finished(), 0);
}

TEST(BakeEngine, AdaptiveTileTakesStagesUntilItConverges) {
  // Tolerance 0: only the last stage ends a tile whose halves differ, so all 16 samples run.
  const auto plan = SmallPlan(1, 16, /*adaptive_tolerance=*/1e-9, /*adaptive_min_samples=*/2);
  auto output = std::make_shared<RecordingOutput>();
  BakeEngine engine(InlineOptions());
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 0)).ok());
  // Pilot: [0,1) and [1,2); the next stage is not out before the pilot is judged.
  std::vector<TaskLease> pilot;
  while (std::optional<TaskLease> lease = engine.Lease("w")) pilot.push_back(*lease);
  ASSERT_EQ(pilot.size(), 2u);
  for (const TaskLease& l : pilot) {
    engine.Report("w", l.lease_id, LeaseEvents(*plan, l));
  }
  std::vector<std::pair<int, int>> ranges;
  while (std::optional<TaskLease> lease = engine.Lease("w")) {
    ranges.emplace_back(lease->sample_begin, lease->sample_end);
    engine.Report("w", lease->lease_id, LeaseEvents(*plan, *lease));
  }
  EXPECT_EQ(ranges, (std::vector<std::pair<int, int>>{{2, 4}, {4, 8}, {8, 16}}));
  ASSERT_EQ(output->end(), JobEnd::kSucceeded);
  EXPECT_EQ(output->tiles().at(0).samples, 16);
  EXPECT_EQ(output->progress().samples_done, 16);
}

TEST(BakeEngine, ConvergedAdaptiveTileStopsEarlyAndCountsItsSkippedSamples) {
  // Every sample alike (the lit pixel, and a tile offset that makes the shadow identical):
  // the pilot's halves agree, so the tile is done after 2 of 64 samples.
  const auto plan = SmallPlan(1, 64, /*adaptive_tolerance=*/0.01, /*adaptive_min_samples=*/2);
  auto output = std::make_shared<RecordingOutput>();
  BakeEngine engine(InlineOptions());
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 0)).ok());
  while (std::optional<TaskLease> lease = engine.Lease("w")) {
    // Samples 0 and 1 both in shadow over [2, 8).
    engine.Report("w", lease->lease_id, One(BatchEvents(*plan, 0, 0, 1)));
  }
  ASSERT_EQ(output->end(), JobEnd::kSucceeded);
  EXPECT_EQ(output->tiles().at(0).samples, 2);
  const JobProgress p = output->progress();
  EXPECT_EQ(p.tile_samples_total, 2);
  EXPECT_EQ(p.samples_done, p.samples_total);  // the skipped 62 count as done
}

TEST(BakeEngine, CancelWhileATileIsStoredEndsOnlyAfterTheStoreReturns) {
  const auto plan = SmallPlan(2, 2);
  auto output = std::make_shared<RecordingOutput>();
  output->hold_store_ = true;
  WorkQueue pool(2);
  EngineOptions options = InlineOptions();
  options.executor = [&pool](std::function<void()> work) { pool.Post(std::move(work)); };
  BakeEngine engine(std::move(options));
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 0)).ok());
  const std::optional<TaskLease> lease = engine.Lease("w");
  ASSERT_TRUE(lease);
  ASSERT_TRUE(engine.Report("w", lease->lease_id, LeaseEvents(*plan, *lease)));
  output->store_entered_.WaitForNotification();
  EXPECT_TRUE(engine.Cancel("j", absl::CancelledError("by request")));
  EXPECT_FALSE(engine.Cancel("j", absl::CancelledError("twice")));
  EXPECT_FALSE(engine.Lease("w"));  // its other tile's task is gone
  EXPECT_EQ(output->ended(), 0);    // the store is still running
  output->release_store_.Notify();
  output->ended_note_.WaitForNotification();
  pool.Wait();
  EXPECT_EQ(output->ended(), 1);
  EXPECT_EQ(output->end(), JobEnd::kCancelled);
  EXPECT_EQ(output->status().message(), "by request");
  EXPECT_EQ(output->finished(), 0);
}

TEST(BakeEngine, StoreErrorFailsTheJobNamingTheTile) {
  const auto plan = SmallPlan(2, 1);
  auto output = std::make_shared<RecordingOutput>();
  output->store_error_ = absl::ResourceExhaustedError("disk full");
  BakeEngine engine(InlineOptions());
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 0)).ok());
  const std::optional<TaskLease> first = engine.Lease("w");
  const std::optional<TaskLease> second = engine.Lease("w");
  ASSERT_TRUE(first && second);
  EXPECT_TRUE(engine.Report("w", first->lease_id, LeaseEvents(*plan, *first)));
  EXPECT_FALSE(engine.Report("w", second->lease_id, LeaseEvents(*plan, *second)))
      << "a failed job takes no more results";
  EXPECT_EQ(output->end(), JobEnd::kFailed);
  EXPECT_EQ(output->status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_EQ(output->status().message(), "storing tile 0: disk full");
  EXPECT_EQ(output->finished(), 0);
  EXPECT_EQ(output->ended(), 1);
}

// Each finished stage's tiles are committed before the group counts as assembled: one commit
// per group here (RecordingOutput checks at Finish that none is left uncommitted), and a
// commit that fails fails the job.
TEST(BakeEngine, StoredTilesAreCommittedAStageAtATimeAndACommitErrorFailsTheJob) {
  const auto plan = SmallPlan(3, 4);
  {
    auto output = std::make_shared<RecordingOutput>();
    BakeEngine engine(InlineOptions());
    ASSERT_TRUE(engine.AddJob(Job(plan, output, 2)).ok());
    RunAll(engine, *plan);
    EXPECT_EQ(output->end(), JobEnd::kSucceeded);
    EXPECT_EQ(output->tiles().size(), 3u);
    EXPECT_EQ(output->commits(), plan->group_count());
  }
  auto output = std::make_shared<RecordingOutput>();
  output->commit_error_ = absl::ResourceExhaustedError("disk full");
  BakeEngine engine(InlineOptions());
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 0)).ok());
  while (std::optional<TaskLease> lease = engine.Lease("w")) {
    engine.Report("w", lease->lease_id, LeaseEvents(*plan, *lease));  // false once it failed
  }
  EXPECT_EQ(output->end(), JobEnd::kFailed);
  EXPECT_EQ(output->status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_EQ(output->status().message(), "storing tiles: disk full");
  EXPECT_EQ(output->finished(), 0);
  EXPECT_EQ(output->commits(), 1);  // the first commit ended the job
}

TEST(BakeEngine, TaskFailureEndsTheJobWithItsOwnStatusWhenAsked) {
  const auto plan = SmallPlan(2, 4);
  auto output = std::make_shared<RecordingOutput>();
  EngineOptions options = InlineOptions();
  options.task_failure_ends_job = true;
  BakeEngine engine(std::move(options));
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 0)).ok());
  const std::optional<TaskLease> lease = engine.Lease("w");
  ASSERT_TRUE(lease);
  engine.ReportFailure("w", lease->lease_id, absl::ResourceExhaustedError("map too large"),
                       /*handed_back=*/false);
  EXPECT_EQ(output->end(), JobEnd::kFailed);
  EXPECT_EQ(output->status(), absl::ResourceExhaustedError("map too large"));
}

TEST(BakeEngine, TaskFailuresOnDistinctWorkersFailTheJobOtherwise) {
  const auto plan = SmallPlan(1, 4);
  auto output = std::make_shared<RecordingOutput>();
  EngineOptions options = InlineOptions();
  options.scheduler.max_task_failures = 2;
  BakeEngine engine(std::move(options));
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 0)).ok());
  std::optional<TaskLease> lease = engine.Lease("a");
  ASSERT_TRUE(lease);
  engine.ReportFailure("a", lease->lease_id, absl::InternalError("gl"), false);
  EXPECT_EQ(output->ended(), 0);  // re-queued for another worker
  EXPECT_FALSE(engine.Lease("a"));
  lease = engine.Lease("b");
  ASSERT_TRUE(lease);
  engine.ReportFailure("b", lease->lease_id, absl::InternalError("gl"), false);
  EXPECT_EQ(output->end(), JobEnd::kFailed);
  EXPECT_EQ(output->status().code(), absl::StatusCode::kAborted);
  EXPECT_NE(output->status().message().find("failed on 2 workers"), std::string::npos)
      << output->status();
}

TEST(BakeEngine, HandedBackTaskGoesToTheNextWorker) {
  const auto plan = SmallPlan(1, 4);
  auto output = std::make_shared<RecordingOutput>();
  EngineOptions options = InlineOptions();
  options.task_failure_ends_job = true;
  BakeEngine engine(std::move(options));
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 0)).ok());
  std::optional<TaskLease> lease = engine.Lease("a");
  engine.ReportFailure("a", lease->lease_id, absl::CancelledError("stopping"), true);
  EXPECT_EQ(output->ended(), 0);
  EXPECT_EQ(RunAll(engine, *plan), 1);
  EXPECT_EQ(output->end(), JobEnd::kSucceeded);
}

TEST(BakeEngine, ResumedJobRunsOnlyItsMissingTiles) {
  const auto plan = SmallPlan(3, 2);
  auto output = std::make_shared<RecordingOutput>();
  BakeEngine engine(InlineOptions());
  EngineJob job = Job(plan, output, 0);
  job.done_tiles = {0, 2};
  job.started = true;
  ASSERT_TRUE(engine.AddJob(std::move(job)).ok());
  EXPECT_EQ(engine.Progress("j")->tiles_done, 2);
  const std::optional<TaskLease> lease = engine.Lease("w");
  ASSERT_TRUE(lease);
  EXPECT_EQ(lease->tiles, std::vector<int>{1});
  engine.Report("w", lease->lease_id, LeaseEvents(*plan, *lease));
  EXPECT_EQ(output->started(), 0);  // it had started before the restart
  EXPECT_EQ(output->end(), JobEnd::kSucceeded);
  EXPECT_EQ(output->tiles().size(), 1u);
}

TEST(BakeEngine, JobWithEveryTileDoneFinishesAtOnce) {
  const auto plan = SmallPlan(2, 2);
  auto output = std::make_shared<RecordingOutput>();
  BakeEngine engine(InlineOptions());
  EngineJob job = Job(plan, output, 0);
  job.done_tiles = {0, 1};
  ASSERT_TRUE(engine.AddJob(std::move(job)).ok());
  EXPECT_EQ(output->finished(), 1);
  EXPECT_EQ(output->end(), JobEnd::kSucceeded);
}

TEST(BakeEngine, RefusesADuplicateJobAndOneWithoutPlanOrOutput) {
  const auto plan = SmallPlan(1, 2);
  BakeEngine engine(InlineOptions());
  ASSERT_TRUE(engine.AddJob(Job(plan, std::make_shared<RecordingOutput>(), 0)).ok());
  EXPECT_EQ(engine.AddJob(Job(plan, std::make_shared<RecordingOutput>(), 0)).code(),
            absl::StatusCode::kAlreadyExists);
  EXPECT_EQ(engine.AddJob(Job(nullptr, std::make_shared<RecordingOutput>(), 0)).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(engine.AddJob(Job(plan, nullptr, 0)).code(), absl::StatusCode::kInvalidArgument);
}

TEST(BakeEngine, WaitingLeaseReturnsWhenTheJobEnds) {
  const auto plan = SmallPlan(1, 2);
  auto output = std::make_shared<RecordingOutput>();
  BakeEngine engine(InlineOptions());
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 0)).ok());
  const std::optional<TaskLease> only = engine.Lease("a");
  ASSERT_TRUE(only);
  std::optional<TaskLease> got;
  absl::Notification returned;
  std::thread waiter([&] {
    got = engine.Lease("b", absl::Seconds(60));
    returned.Notify();
  });
  EXPECT_FALSE(returned.WaitForNotificationWithTimeout(absl::Milliseconds(50)));
  engine.Fail("j", absl::InternalError("runner could not start"));
  EXPECT_TRUE(returned.WaitForNotificationWithTimeout(absl::Seconds(10)));
  waiter.join();
  EXPECT_FALSE(got);
  EXPECT_EQ(output->end(), JobEnd::kFailed);
  EXPECT_FALSE(engine.Report("a", only->lease_id, LeaseEvents(*plan, *only)));  // stale
}

TEST(BakeEngine, ManyThreadsBakeTheSameTilesAsOne) {
  const auto plan = SmallPlan(16, 12, 0, 0, /*group_size=*/4);
  std::map<int, PdsmTile> single;
  {
    auto output = std::make_shared<RecordingOutput>();
    BakeEngine engine(InlineOptions());
    ASSERT_TRUE(engine.AddJob(Job(plan, output, 5)).ok());
    RunAll(engine, *plan);
    single = output->tiles();
  }
  auto output = std::make_shared<RecordingOutput>();
  EngineOptions options = InlineOptions();
  options.scheduler.max_open_tiles = 3;
  BakeEngine engine(std::move(options));
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 5)).ok());
  WorkQueue threads(4);
  for (int t = 0; t < 4; ++t) {
    threads.Post([&, t] {
      const std::string id = "w" + std::to_string(t);
      while (std::optional<TaskLease> l = engine.Lease(id, absl::Seconds(5))) {
        engine.Report(id, l->lease_id, LeaseEvents(*plan, *l));
      }
    });
  }
  threads.Wait();
  ASSERT_EQ(output->end(), JobEnd::kSucceeded);
  ASSERT_EQ(output->tiles().size(), single.size());
  for (const auto& [t, tile] : single) EXPECT_EQ(output->tiles().at(t).vertices, tile.vertices);
}

TEST(BakeEngine, ATaskCoversItsGroupAndEveryTileOfItIsStored) {
  const auto plan = SmallPlan(6, 4, 0, 0, /*group_size=*/3);
  auto output = std::make_shared<RecordingOutput>();
  BakeEngine engine(InlineOptions());
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 2)).ok());
  std::vector<TaskLease> leases;
  while (std::optional<TaskLease> lease = engine.Lease("w")) leases.push_back(*lease);
  ASSERT_EQ(leases.size(), 4u);  // 2 groups x 2 batches
  EXPECT_EQ(leases[0].group_index, 0);
  EXPECT_EQ(leases[0].tiles, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(leases[3].tiles, (std::vector<int>{3, 4, 5}));
  for (const TaskLease& l : leases)
    EXPECT_TRUE(engine.Report("w", l.lease_id, LeaseEvents(*plan, l)));
  EXPECT_EQ(output->end(), JobEnd::kSucceeded);
  EXPECT_EQ(output->tiles().size(), 6u);
  EXPECT_EQ(output->progress().samples_done, output->progress().samples_total);
  // The same tiles as with one tile per group.
  const auto single = SmallPlan(6, 4);
  auto reference = std::make_shared<RecordingOutput>();
  BakeEngine other(InlineOptions());
  ASSERT_TRUE(other.AddJob(Job(single, reference, 0)).ok());
  RunAll(other, *single);
  for (int t = 0; t < 6; ++t)
    EXPECT_EQ(output->tiles().at(t).vertices, reference->tiles().at(t).vertices);
}

TEST(BakeEngine, ResumedGroupLeasesOnlyItsMissingTiles) {
  const auto plan = SmallPlan(4, 2, 0, 0, /*group_size=*/4);
  auto output = std::make_shared<RecordingOutput>();
  BakeEngine engine(InlineOptions());
  EngineJob job = Job(plan, output, 0);
  job.done_tiles = {1, 2};
  ASSERT_TRUE(engine.AddJob(std::move(job)).ok());
  const std::optional<TaskLease> lease = engine.Lease("w");
  ASSERT_TRUE(lease);
  EXPECT_EQ(lease->tiles, (std::vector<int>{0, 3}));
  EXPECT_TRUE(engine.Report("w", lease->lease_id, LeaseEvents(*plan, *lease)));
  EXPECT_EQ(output->end(), JobEnd::kSucceeded);
  EXPECT_EQ(output->tiles().size(), 2u);
}

TEST(BakeEngine, AResultWithTheWrongNumberOfTilesIsTheTasksFailure) {
  const auto plan = SmallPlan(2, 2, 0, 0, /*group_size=*/2);
  auto output = std::make_shared<RecordingOutput>();
  EngineOptions options = InlineOptions();
  options.scheduler.max_task_failures = 1;
  BakeEngine engine(std::move(options));
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 0)).ok());
  const std::optional<TaskLease> lease = engine.Lease("w");
  ASSERT_TRUE(lease);
  EXPECT_FALSE(engine.Report("w", lease->lease_id, One(BatchEvents(*plan, 0, 0, 2))));
  EXPECT_EQ(output->end(), JobEnd::kFailed);
  EXPECT_NE(output->status().message().find("1 tiles' events for a task of 2"), std::string::npos)
      << output->status();
}

TEST(BakeEngine, AdaptiveGroupGoesOnWithOnlyTheTilesThatNeedIt) {
  // Tile 0 sees every sample alike (converges at the pilot); tile 1 sees them differ.
  const auto plan = SmallPlan(2, 16, /*adaptive_tolerance=*/0.01, /*adaptive_min_samples=*/2,
                              /*group_size=*/2);
  auto output = std::make_shared<RecordingOutput>();
  BakeEngine engine(InlineOptions());
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 0)).ok());
  std::vector<std::vector<int>> tiles_per_task;
  while (std::optional<TaskLease> lease = engine.Lease("w")) {
    tiles_per_task.push_back(lease->tiles);
    std::vector<TileEvents> events;
    for (int tile : lease->tiles) {
      events.push_back(tile == 0 ? BatchEvents(*plan, 0, 0, lease->sample_end - lease->sample_begin)
                                 : BatchEvents(*plan, 1, lease->sample_begin, lease->sample_end));
    }
    engine.Report("w", lease->lease_id, std::move(events));
  }
  ASSERT_EQ(output->end(), JobEnd::kSucceeded);
  ASSERT_GE(tiles_per_task.size(), 3u);
  EXPECT_EQ(tiles_per_task[0], (std::vector<int>{0, 1}));  // the pilot's two halves
  EXPECT_EQ(tiles_per_task[1], (std::vector<int>{0, 1}));
  for (size_t k = 2; k < tiles_per_task.size(); ++k) {
    EXPECT_EQ(tiles_per_task[k], std::vector<int>{1}) << "task " << k;
  }
  EXPECT_EQ(output->tiles().at(0).samples, 2);
  EXPECT_EQ(output->tiles().at(1).samples, 16);
}

TEST(BakeEngine, TilesNoCasterReachesAreStoredWithoutATask) {
  for (const bool adaptive : {false, true}) {
    auto plan = std::make_shared<BakePlan>(*SmallPlan(3, 16, adaptive ? 0.01 : 0, adaptive ? 4 : 0,
                                                      /*group_size=*/3));
    plan->tile_has_casters = {true, false, true};
    auto output = std::make_shared<RecordingOutput>();
    BakeEngine engine(InlineOptions());
    ASSERT_TRUE(engine.AddJob(Job(plan, output, 0)).ok());
    EXPECT_EQ(output->tiles().size(), 1u) << "stored at once";
    while (std::optional<TaskLease> lease = engine.Lease("w")) {
      EXPECT_EQ(lease->tiles, (std::vector<int>{0, 2}));
      engine.Report("w", lease->lease_id, LeaseEvents(*plan, *lease));
    }
    ASSERT_EQ(output->end(), JobEnd::kSucceeded);
    const PdsmTile unreached = output->tiles().at(1);  // tiles() returns a copy
    EXPECT_TRUE(unreached.vertices.empty());
    // What a task would have given it: all samples (fixed), or its pilot's (adaptive).
    EXPECT_EQ(unreached.samples, adaptive ? 4 : 0);
    const JobProgress p = output->progress();
    EXPECT_EQ(p.tiles_without_task, 1);
    EXPECT_EQ(p.samples_done, p.samples_total);
  }
}

TEST(BakeEngine, StatsCountJobsAndRecentResults) {
  const auto plan = SmallPlan(2, 2);
  int64_t now = 1'000'000;
  EngineOptions options = InlineOptions();
  options.now_ms = [&now] { return now; };
  BakeEngine engine(std::move(options));
  ASSERT_TRUE(engine.AddJob(Job(plan, std::make_shared<RecordingOutput>(), 0)).ok());
  EXPECT_EQ(engine.Stats().jobs_waiting, 1);
  now += 10'000;
  const std::optional<TaskLease> lease = engine.Lease("w");
  ASSERT_TRUE(lease);
  engine.Report("w", lease->lease_id, LeaseEvents(*plan, *lease));
  EngineStats stats = engine.Stats();
  EXPECT_EQ(stats.jobs_started, 1);
  EXPECT_EQ(stats.scheduler.results_accepted, 1);
  EXPECT_DOUBLE_EQ(stats.tasks_per_second, 1 / 10.0);   // one result in the 10 s so far
  EXPECT_DOUBLE_EQ(stats.events_per_second, 3 / 10.0);  // two entries and their shared exit
}

}  // namespace
}  // namespace pdsm
