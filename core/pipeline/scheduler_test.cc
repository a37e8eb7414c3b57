#include "core/pipeline/scheduler.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace pdsm {
namespace {

using ::testing::HasSubstr;

JobSpec MakeJob(const std::string& id, std::vector<int> tiles, int samples = 1,
                int samples_per_task = 1, int priority = 0, int64_t sequence = 0) {
  JobSpec job;
  job.job_id = id;
  job.priority = priority;
  job.sequence = sequence;
  // One tile per group, the group named after its tile: the scheduler's unit is the group.
  for (int tile : tiles) job.groups.push_back(GroupWork{tile, {tile}});
  job.samples = samples;
  job.samples_per_task = samples_per_task;
  return job;
}

// The task the scheduler must hand out: a failed expectation, not a crash, when there is none.
TaskLease MustLease(Scheduler& scheduler, const std::string& worker_id, int64_t now_ms) {
  const std::optional<TaskLease> lease = scheduler.Lease(worker_id, now_ms);
  EXPECT_TRUE(lease) << worker_id << " got no task at " << now_ms;
  return lease.value_or(TaskLease{});
}

SchedulerOptions SmallOptions() {
  SchedulerOptions options;
  options.lease_ms = 1000;
  options.worker_active_ms = 30'000;
  return options;
}

// ---------------------------------------------------------------------------------------------
// Order and shape of the work.

TEST(SchedulerTest, LeasesJobsByPriorityThenSequence) {
  Scheduler scheduler(SmallOptions());
  scheduler.AddJob(MakeJob("low", {0}, 1, 1, /*priority=*/0, /*sequence=*/1));
  scheduler.AddJob(MakeJob("high_late", {0}, 1, 1, /*priority=*/5, /*sequence=*/3));
  scheduler.AddJob(MakeJob("high_early", {0}, 1, 1, /*priority=*/5, /*sequence=*/2));
  scheduler.AddJob(MakeJob("middle", {0}, 1, 1, /*priority=*/2, /*sequence=*/0));
  std::vector<std::string> order;
  while (std::optional<TaskLease> lease = scheduler.Lease("w", 0)) order.push_back(lease->job_id);
  EXPECT_EQ(order, (std::vector<std::string>{"high_early", "high_late", "middle", "low"}));
}

TEST(SchedulerTest, BatchesCoverSamplesExactlyOnceInTileThenBatchOrder) {
  Scheduler scheduler(SmallOptions());
  scheduler.AddJob(MakeJob("j", {4, 2}, /*samples=*/10, /*samples_per_task=*/3));
  std::vector<std::tuple<int, int, int>> got;
  while (std::optional<TaskLease> lease = scheduler.Lease("w", 0)) {
    got.emplace_back(lease->group_index, lease->sample_begin, lease->sample_end);
  }
  const std::vector<std::tuple<int, int, int>> want = {{4, 0, 3}, {4, 3, 6}, {4, 6, 9}, {4, 9, 10},
                                                       {2, 0, 3}, {2, 3, 6}, {2, 6, 9}, {2, 9, 10}};
  EXPECT_EQ(got, want);
}

// Adaptive jobs: a tile's pilot (two halves) goes out first; its next stage only when the
// service asks for it after the stage completed, and the tile stays open until assembled.
TEST(SchedulerTest, AdaptiveStagesGoOutOnlyWhenAsked) {
  Scheduler scheduler(SmallOptions());
  JobSpec job = MakeJob("a", {3}, /*samples=*/40, /*samples_per_task=*/6);
  job.adaptive_min_samples = 8;
  scheduler.AddJob(job);
  auto drain = [&]() {
    std::vector<std::tuple<int, int, int>> got;
    ResultOutcome last;
    while (std::optional<TaskLease> lease = scheduler.Lease("w", 0)) {
      got.emplace_back(lease->group_index, lease->sample_begin, lease->sample_end);
      last = scheduler.Complete("w", lease->lease_id, 0);
    }
    EXPECT_EQ(last.kind, ResultOutcome::kStageComplete);
    return got;
  };
  // Pilot [0, 4) and [4, 8), batches of at most 6 within each range.
  EXPECT_EQ(drain(), (std::vector<std::tuple<int, int, int>>{{3, 0, 4}, {3, 4, 8}}));
  EXPECT_FALSE(scheduler.JobComplete("a"));
  ASSERT_TRUE(scheduler.AddStage("a", 3, {3}));
  EXPECT_EQ(drain(), (std::vector<std::tuple<int, int, int>>{{3, 8, 14}, {3, 14, 16}}));
  ASSERT_TRUE(scheduler.AddStage("a", 3, {3}));
  EXPECT_EQ(drain(),
            (std::vector<std::tuple<int, int, int>>{{3, 16, 22}, {3, 22, 28}, {3, 28, 32}}));
  ASSERT_TRUE(scheduler.AddStage("a", 3, {3}));
  EXPECT_EQ(drain(), (std::vector<std::tuple<int, int, int>>{{3, 32, 38}, {3, 38, 40}}));
  EXPECT_FALSE(scheduler.AddStage("a", 3, {3}));  // past the last stage
  scheduler.GroupAssembled("a", 3);
  EXPECT_TRUE(scheduler.JobComplete("a"));
}

TEST(SchedulerTest, AddStageRefusesFixedJobsAndBusyTiles) {
  Scheduler scheduler(SmallOptions());
  scheduler.AddJob(MakeJob("fixed", {0}, 4, 2));
  const TaskLease lease = MustLease(scheduler, "w", 0);
  EXPECT_FALSE(scheduler.AddStage("fixed", 0, {0}));
  JobSpec job = MakeJob("a", {0}, 16, 16);
  job.adaptive_min_samples = 4;
  scheduler.AddJob(job);
  scheduler.Complete("w", lease.lease_id, 0);
  MustLease(scheduler, "w", 0);  // fixed's second batch
  const TaskLease adaptive = MustLease(scheduler, "w", 0);
  ASSERT_EQ(adaptive.job_id, "a");
  EXPECT_FALSE(scheduler.AddStage("a", 0, {0}));  // its pilot is still out
  EXPECT_FALSE(scheduler.AddStage("missing", 0, {0}));
}

TEST(SchedulerTest, PendingTasksOfOpenTilesGoBeforeANewTile) {
  Scheduler scheduler(SmallOptions());
  scheduler.AddJob(MakeJob("j", {0, 1}, /*samples=*/2, /*samples_per_task=*/1));
  const TaskLease first = MustLease(scheduler, "a", 0);
  const TaskLease second = MustLease(scheduler, "b", 0);
  ASSERT_EQ(second.group_index, 0);
  // Tile 0 batch 0 comes back to the queue; it must go out before tile 1 opens.
  EXPECT_FALSE(scheduler.Fail("a", first.lease_id, "busy", /*handed_back=*/true, 0));
  const TaskLease third = MustLease(scheduler, "c", 0);
  EXPECT_EQ(third.group_index, 0);
  EXPECT_EQ(third.sample_begin, 0);
  EXPECT_EQ(MustLease(scheduler, "c", 0).group_index, 1);
  EXPECT_TRUE(scheduler.Stats(0).tasks_failed_by_code.empty());  // a hand-back is no failure
}

TEST(SchedulerTest, HonoursTheOpenTileBoundOverAllJobs) {
  SchedulerOptions options = SmallOptions();
  options.max_open_tiles = 2;
  Scheduler scheduler(options);
  scheduler.AddJob(MakeJob("a", {0, 1, 2}, 1, 1, /*priority=*/1));
  scheduler.AddJob(MakeJob("b", {0, 1}, 1, 1, /*priority=*/0));
  const TaskLease t0 = MustLease(scheduler, "w", 0);
  const TaskLease t1 = MustLease(scheduler, "w", 0);
  EXPECT_FALSE(scheduler.Lease("w", 0));  // neither job may open a third tile
  EXPECT_EQ(scheduler.Stats(0).tiles_open, 2);

  const ResultOutcome done = scheduler.Complete("w", t0.lease_id, 0);
  EXPECT_EQ(done.kind, ResultOutcome::kStageComplete);
  EXPECT_FALSE(scheduler.Lease("w", 0));  // a complete tile holds its slot until assembled
  scheduler.GroupAssembled("a", t0.group_index);
  EXPECT_EQ(scheduler.Stats(0).tiles_open, 1);
  const std::optional<TaskLease> t2 = scheduler.Lease("w", 0);
  ASSERT_TRUE(t2);
  EXPECT_EQ(t2->job_id, "a");
  EXPECT_EQ(t2->group_index, 2);
  EXPECT_FALSE(scheduler.Lease("w", 0));
  EXPECT_EQ(scheduler.Complete("w", t1.lease_id, 0).kind, ResultOutcome::kStageComplete);
  scheduler.GroupAssembled("a", t1.group_index);
  EXPECT_EQ(MustLease(scheduler, "w", 0).job_id, "b");
}

TEST(SchedulerTest, ResumedJobIssuesOnlyItsListedTiles) {
  Scheduler scheduler(SmallOptions());
  scheduler.AddJob(MakeJob("j", {8, 3}, /*samples=*/4, /*samples_per_task=*/2));
  std::multiset<int> tiles;
  while (std::optional<TaskLease> lease = scheduler.Lease("w", 0)) {
    tiles.insert(lease->group_index);
  }
  EXPECT_EQ(tiles, (std::multiset<int>{3, 3, 8, 8}));
}

TEST(SchedulerTest, JobWithoutTilesIsCompleteAtOnce) {
  Scheduler scheduler(SmallOptions());
  scheduler.AddJob(MakeJob("empty", {}));
  EXPECT_TRUE(scheduler.HasJob("empty"));
  EXPECT_TRUE(scheduler.JobComplete("empty"));
  EXPECT_FALSE(scheduler.Lease("w", 0));
  EXPECT_TRUE(scheduler.Tick(100'000).empty());
  EXPECT_FALSE(scheduler.JobComplete("unknown"));
}

TEST(SchedulerTest, JobCompletesAfterEveryTileIsAssembled) {
  Scheduler scheduler(SmallOptions());
  scheduler.AddJob(MakeJob("j", {0, 1}, 2, 1));
  std::vector<TaskLease> leases;
  while (std::optional<TaskLease> lease = scheduler.Lease("w", 0)) leases.push_back(*lease);
  ASSERT_EQ(leases.size(), 4u);
  EXPECT_EQ(scheduler.Complete("w", leases[0].lease_id, 0).kind, ResultOutcome::kAccepted);
  EXPECT_EQ(scheduler.Complete("w", leases[1].lease_id, 0).kind, ResultOutcome::kStageComplete);
  EXPECT_EQ(scheduler.Complete("w", leases[2].lease_id, 0).kind, ResultOutcome::kAccepted);
  const ResultOutcome last = scheduler.Complete("w", leases[3].lease_id, 0);
  EXPECT_EQ(last.kind, ResultOutcome::kStageComplete);
  EXPECT_EQ(last.job_id, "j");
  EXPECT_EQ(last.group_index, 1);
  EXPECT_EQ(last.sample_begin, 1);
  EXPECT_EQ(last.sample_end, 2);
  scheduler.GroupAssembled("j", 0);
  EXPECT_FALSE(scheduler.JobComplete("j"));
  scheduler.GroupAssembled("j", 1);
  EXPECT_TRUE(scheduler.JobComplete("j"));
  EXPECT_EQ(scheduler.Stats(0).results_accepted, 4);
}

TEST(SchedulerTest, LeaseIdsStartAtTheBase) {
  SchedulerOptions options = SmallOptions();
  options.lease_id_base = 7'000'000;
  Scheduler scheduler(options);
  scheduler.AddJob(MakeJob("j", {0, 1}));
  EXPECT_EQ(MustLease(scheduler, "w", 0).lease_id, 7'000'000u);
  EXPECT_EQ(MustLease(scheduler, "w", 0).lease_id, 7'000'001u);
  // A predecessor's lease id (from base 1) is unknown here.
  EXPECT_EQ(scheduler.Complete("w", 1, 0).kind, ResultOutcome::kDropped);
}

// ---------------------------------------------------------------------------------------------
// Leases: expiry, late and duplicate results, extension.

TEST(SchedulerTest, ExpiredLeaseIsReissued) {
  Scheduler scheduler(SmallOptions());  // lease_ms 1000
  scheduler.AddJob(MakeJob("j", {0}));
  const TaskLease first = MustLease(scheduler, "a", 0);
  EXPECT_EQ(first.deadline_ms, 1000);
  EXPECT_FALSE(scheduler.Lease("b", 500));  // leased, not re-issued
  EXPECT_TRUE(scheduler.Tick(999).empty());
  EXPECT_FALSE(scheduler.Lease("b", 999));
  EXPECT_TRUE(scheduler.Tick(1000).empty());
  EXPECT_EQ(scheduler.Stats(1000).leases_expired, 1);
  const std::optional<TaskLease> second = scheduler.Lease("b", 1000);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->group_index, 0);
  EXPECT_NE(second->lease_id, first.lease_id);
  // An expiry is not a failure of "a": it may take the task again.
  EXPECT_EQ(scheduler.Fail("b", second->lease_id, "x", /*handed_back=*/true, 1000), std::nullopt);
  EXPECT_TRUE(scheduler.Lease("a", 1000));
}

// Issue #17: one worker whose leases kept expiring (a machine that pauses) was excluded, and
// with no other worker active the job failed ("no worker can run the job").
TEST(SchedulerTest, ALoneWorkerWhoseLeasesKeepExpiringStillFinishesTheJob) {
  Scheduler scheduler(SmallOptions());  // lease_ms 1000, 3 failures per task and per worker
  scheduler.AddJob(MakeJob("j", {0, 1, 2, 3}));
  int64_t now = 0;
  for (int i = 0; i < 6; ++i) {  // twice each of three tasks, and the first one more often
    ASSERT_TRUE(scheduler.Lease("a", now)) << i;
    now += 1000;
    EXPECT_TRUE(scheduler.Tick(now).empty()) << "expiry " << i << " failed the job";
  }
  EXPECT_EQ(scheduler.Stats(now).leases_expired, 6);
  int done = 0;
  while (std::optional<TaskLease> lease = scheduler.Lease("a", now)) {
    if (scheduler.Complete("a", lease->lease_id, now).kind == ResultOutcome::kStageComplete) {
      scheduler.GroupAssembled("j", lease->group_index);
      ++done;
    }
  }
  EXPECT_EQ(done, 4);
  EXPECT_TRUE(scheduler.Tick(now).empty());
  EXPECT_TRUE(scheduler.JobComplete("j"));
}

// What expiries still catch: a task whose every holder goes quiet, each a new process (a task
// that crashes its worker), fails its job after max_task_failures of them.
TEST(SchedulerTest, ATaskWhoseLeaseExpiresOnThreeWorkersFailsTheJob) {
  Scheduler scheduler(SmallOptions());
  scheduler.AddJob(MakeJob("j", {7}));
  int64_t now = 0;
  for (const char* worker : {"a", "b"}) {
    ASSERT_TRUE(scheduler.Lease(worker, now));
    now += 1000;
    EXPECT_TRUE(scheduler.Tick(now).empty());
  }
  // "a" again counts once.
  ASSERT_TRUE(scheduler.Lease("a", now));
  now += 1000;
  EXPECT_TRUE(scheduler.Tick(now).empty());
  ASSERT_TRUE(scheduler.Lease("c", now));
  now += 1000;
  const std::vector<JobFailure> failures = scheduler.Tick(now);
  ASSERT_EQ(failures.size(), 1u);
  EXPECT_THAT(failures[0].reason, HasSubstr("tile group 7"));
  EXPECT_THAT(failures[0].reason, HasSubstr("failed on 3 workers"));
  EXPECT_THAT(failures[0].reason, HasSubstr("lease expired on worker c"));
  EXPECT_FALSE(scheduler.HasJob("j"));
}

TEST(SchedulerTest, LateResultIsDroppedAndTheReissuedOneAccepted) {
  Scheduler scheduler(SmallOptions());
  scheduler.AddJob(MakeJob("j", {0}));
  const TaskLease first = MustLease(scheduler, "a", 0);
  // "b" is about, so the job can go on after "a" loses its lease.
  EXPECT_FALSE(scheduler.Lease("b", 1500));
  EXPECT_TRUE(scheduler.Tick(2000).empty());
  const TaskLease second = MustLease(scheduler, "b", 2000);
  EXPECT_EQ(scheduler.Complete("a", first.lease_id, 2100).kind, ResultOutcome::kDropped);
  EXPECT_EQ(scheduler.Stats(2100).results_dropped, 1);
  const ResultOutcome outcome = scheduler.Complete("b", second.lease_id, 2200);
  EXPECT_EQ(outcome.kind, ResultOutcome::kStageComplete);
  EXPECT_EQ(outcome.job_id, "j");
  EXPECT_EQ(scheduler.Stats(2200).results_accepted, 1);
}

TEST(SchedulerTest, DuplicateResultIsDropped) {
  Scheduler scheduler(SmallOptions());
  scheduler.AddJob(MakeJob("j", {0}, 2, 1));
  const TaskLease lease = MustLease(scheduler, "a", 0);
  EXPECT_EQ(scheduler.Complete("a", lease.lease_id, 10).kind, ResultOutcome::kAccepted);
  EXPECT_EQ(scheduler.Complete("a", lease.lease_id, 20).kind, ResultOutcome::kDropped);
  const SchedulerStats stats = scheduler.Stats(20);
  EXPECT_EQ(stats.results_accepted, 1);
  EXPECT_EQ(stats.results_dropped, 1);
}

TEST(SchedulerTest, ResultFromAnotherWorkerIsDroppedAndLeavesTheLease) {
  Scheduler scheduler(SmallOptions());
  scheduler.AddJob(MakeJob("j", {0}));
  const TaskLease lease = MustLease(scheduler, "a", 0);
  EXPECT_EQ(scheduler.Complete("b", lease.lease_id, 10).kind, ResultOutcome::kDropped);
  EXPECT_FALSE(scheduler.Fail("b", lease.lease_id, "x", false, 10));
  EXPECT_FALSE(scheduler.Extend("b", lease.lease_id, 10).ok());
  EXPECT_EQ(scheduler.Complete("a", lease.lease_id, 20).kind, ResultOutcome::kStageComplete);
}

TEST(SchedulerTest, ExtendMovesTheDeadlineAndIsRefusedAfterExpiry) {
  Scheduler scheduler(SmallOptions());
  scheduler.AddJob(MakeJob("j", {0}));
  const TaskLease lease = MustLease(scheduler, "a", 0);
  const absl::StatusOr<int64_t> deadline = scheduler.Extend("a", lease.lease_id, 500);
  ASSERT_TRUE(deadline.ok()) << deadline.status();
  EXPECT_EQ(*deadline, 1500);
  EXPECT_TRUE(scheduler.Tick(1400).empty());
  EXPECT_EQ(scheduler.Stats(1400).leases_expired, 0);
  scheduler.Tick(1500);
  EXPECT_EQ(scheduler.Stats(1500).leases_expired, 1);
  const absl::StatusOr<int64_t> late = scheduler.Extend("a", lease.lease_id, 1600);
  EXPECT_EQ(late.status().code(), absl::StatusCode::kFailedPrecondition);
}

// ---------------------------------------------------------------------------------------------
// Failures and exclusions.

TEST(SchedulerTest, TaskFailingOnThreeWorkersFailsTheJob) {
  SchedulerOptions options = SmallOptions();
  options.max_task_failures = 3;
  Scheduler scheduler(options);
  scheduler.AddJob(MakeJob("j", {7}, /*samples=*/8, /*samples_per_task=*/4));
  std::optional<JobFailure> failure;
  for (const std::string worker : {"a", "b", "c"}) {
    ASSERT_FALSE(failure) << "failed early: " << failure->reason;
    const TaskLease lease = MustLease(scheduler, worker, 0);
    ASSERT_EQ(lease.sample_begin, 0);
    failure = scheduler.Fail(
        worker, lease.lease_id, "out of memory on " + worker, false, 0,
        worker == "c" ? absl::StatusCode::kInternal : absl::StatusCode::kResourceExhausted);
  }
  ASSERT_TRUE(failure);
  // Counted by the code each worker reported (the coordinator's failures-by-code metric).
  const std::map<absl::StatusCode, int64_t> by_code = scheduler.Stats(0).tasks_failed_by_code;
  EXPECT_EQ(by_code, (std::map<absl::StatusCode, int64_t>{{absl::StatusCode::kResourceExhausted, 2},
                                                          {absl::StatusCode::kInternal, 1}}));
  EXPECT_EQ(failure->job_id, "j");
  EXPECT_THAT(failure->reason, HasSubstr("tile group 7"));
  EXPECT_THAT(failure->reason, HasSubstr("[0, 4)"));
  EXPECT_THAT(failure->reason, HasSubstr("out of memory on a"));
  EXPECT_THAT(failure->reason, HasSubstr("out of memory on c"));
  EXPECT_FALSE(scheduler.HasJob("j"));
  EXPECT_EQ(scheduler.Stats(0).tiles_open, 0);
}

TEST(SchedulerTest, ExpiryCountsTowardsTheTaskFailures) {
  SchedulerOptions options = SmallOptions();
  options.max_task_failures = 2;
  Scheduler scheduler(options);
  scheduler.AddJob(MakeJob("j", {3}));
  const TaskLease a = MustLease(scheduler, "a", 0);
  EXPECT_FALSE(scheduler.Fail("a", a.lease_id, "crashed", false, 0));
  MustLease(scheduler, "b", 0);
  const std::vector<JobFailure> failures = scheduler.Tick(1000);
  ASSERT_EQ(failures.size(), 1u);
  EXPECT_THAT(failures[0].reason, HasSubstr("tile group 3"));
  EXPECT_THAT(failures[0].reason, HasSubstr("lease expired on worker b"));
  EXPECT_FALSE(scheduler.HasJob("j"));
}

TEST(SchedulerTest, WorkerFailingRepeatedlyIsExcludedAndTheJobGoesOn) {
  SchedulerOptions options = SmallOptions();
  options.max_worker_failures_per_job = 3;
  Scheduler scheduler(options);
  scheduler.AddJob(MakeJob("j", {0, 1, 2, 3}));
  scheduler.AddJob(MakeJob("other", {0}, 1, 1, /*priority=*/-1));
  std::set<int> failed_tiles;
  for (int i = 0; i < 3; ++i) {
    const TaskLease lease = MustLease(scheduler, "bad", 0);
    ASSERT_EQ(lease.job_id, "j");
    EXPECT_TRUE(failed_tiles.insert(lease.group_index).second) << "task re-issued to its failer";
    EXPECT_FALSE(scheduler.Fail("bad", lease.lease_id, "driver crash", false, 0));
  }
  // Tile 3 is still to do but "bad" is out of "j"; it may still run other jobs.
  const std::optional<TaskLease> elsewhere = scheduler.Lease("bad", 0);
  ASSERT_TRUE(elsewhere);
  EXPECT_EQ(elsewhere->job_id, "other");
  EXPECT_FALSE(scheduler.Lease("bad", 0));
  int done = 0;
  while (std::optional<TaskLease> lease = scheduler.Lease("good", 0)) {
    if (lease->job_id != "j") continue;
    if (scheduler.Complete("good", lease->lease_id, 0).kind == ResultOutcome::kStageComplete) {
      scheduler.GroupAssembled("j", lease->group_index);
      ++done;
    }
  }
  EXPECT_TRUE(scheduler.Tick(0).empty());
  EXPECT_EQ(done, 4);
  EXPECT_TRUE(scheduler.JobComplete("j"));
}

TEST(SchedulerTest, JobFailsWhenEveryActiveWorkerIsExcluded) {
  SchedulerOptions options = SmallOptions();
  options.max_worker_failures_per_job = 3;
  options.worker_active_ms = 30'000;
  Scheduler scheduler(options);
  scheduler.AddJob(MakeJob("j", {0, 1, 2, 3, 4, 5, 6, 7}));
  // "idle" is seen at 0 and then holds nothing.
  const TaskLease idle = MustLease(scheduler, "idle", 0);
  EXPECT_FALSE(scheduler.Fail("idle", idle.lease_id, "busy", /*handed_back=*/true, 0));
  for (const std::string worker : {"a", "b"}) {
    for (int i = 0; i < 3; ++i) {
      const TaskLease lease = MustLease(scheduler, worker, 1000);
      EXPECT_FALSE(scheduler.Fail(worker, lease.lease_id, "bad GPU", false, 1000));
    }
    EXPECT_FALSE(scheduler.Lease(worker, 1000));
  }
  // "idle" is still active and not excluded: the job can go on.
  EXPECT_TRUE(scheduler.Tick(1000).empty());
  ASSERT_TRUE(scheduler.HasJob("j"));
  // Later only "a" and "b" are about; "idle" has not been seen for over worker_active_ms.
  EXPECT_FALSE(scheduler.Lease("a", 40'000));
  EXPECT_FALSE(scheduler.Lease("b", 40'000));
  const std::vector<JobFailure> failures = scheduler.Tick(40'001);
  ASSERT_EQ(failures.size(), 1u);
  EXPECT_EQ(failures[0].job_id, "j");
  EXPECT_THAT(failures[0].reason, HasSubstr("excluded"));
  EXPECT_THAT(failures[0].reason, HasSubstr("bad GPU"));
  EXPECT_FALSE(scheduler.HasJob("j"));
}

TEST(SchedulerTest, JobFailsWhenActiveWorkersFailedEveryRemainingTask) {
  SchedulerOptions options = SmallOptions();
  options.max_task_failures = 3;
  Scheduler scheduler(options);
  scheduler.AddJob(MakeJob("j", {0}));
  for (const std::string worker : {"a", "b"}) {
    const TaskLease lease = MustLease(scheduler, worker, 0);
    EXPECT_FALSE(scheduler.Fail(worker, lease.lease_id, "bad input", false, 0));
  }
  const std::vector<JobFailure> failures = scheduler.Tick(10);
  ASSERT_EQ(failures.size(), 1u);
  EXPECT_THAT(failures[0].reason, HasSubstr("failed all its remaining tasks"));
}

TEST(SchedulerTest, StuckJobFailsOnlyWhileSomeWorkerIsActive) {
  SchedulerOptions options = SmallOptions();
  options.max_task_failures = 3;
  Scheduler scheduler(options);
  scheduler.AddJob(MakeJob("j", {0}));
  const TaskLease lease = MustLease(scheduler, "a", 0);
  EXPECT_FALSE(scheduler.Fail("a", lease.lease_id, "bad input", false, 0));
  EXPECT_FALSE(scheduler.Tick(0).empty());  // "a" alone, active, failed the only task
  Scheduler quiet(options);
  quiet.AddJob(MakeJob("j", {0}));
  const TaskLease other = MustLease(quiet, "a", 0);
  EXPECT_FALSE(quiet.Fail("a", other.lease_id, "bad input", false, 0));
  EXPECT_TRUE(quiet.Tick(100'000).empty());  // "a" gone quiet: wait for workers
  EXPECT_TRUE(quiet.HasJob("j"));
  EXPECT_EQ(quiet.Stats(100'000).workers_active, 0);
}

TEST(SchedulerTest, WorkerExtendingALongTaskCountsAsActive) {
  SchedulerOptions options = SmallOptions();  // lease_ms 1000, worker_active_ms 30'000
  options.max_worker_failures_per_job = 1;
  Scheduler scheduler(options);
  scheduler.AddJob(MakeJob("j", {0, 1}));
  const TaskLease busy = MustLease(scheduler, "busy", 0);
  const TaskLease bad = MustLease(scheduler, "bad", 0);
  EXPECT_FALSE(scheduler.Fail("bad", bad.lease_id, "bad GPU", false, 0));
  for (int64_t t = 500; t <= 40'000; t += 500) {
    ASSERT_TRUE(scheduler.Extend("busy", busy.lease_id, t).ok()) << t;
    EXPECT_FALSE(scheduler.Lease("bad", t));  // excluded
    // "busy" has not asked for work since 0, yet it is about: the job must not fail.
    ASSERT_TRUE(scheduler.Tick(t).empty()) << t;
  }
  EXPECT_EQ(scheduler.Stats(40'000).workers_active, 2);
}

TEST(SchedulerTest, HandedBackIsNotAFailure) {
  SchedulerOptions options = SmallOptions();
  options.max_task_failures = 2;
  options.max_worker_failures_per_job = 2;
  Scheduler scheduler(options);
  scheduler.AddJob(MakeJob("j", {0}));
  for (int i = 0; i < 10; ++i) {
    const std::optional<TaskLease> lease = scheduler.Lease("a", i);
    ASSERT_TRUE(lease) << "attempt " << i;
    EXPECT_FALSE(scheduler.Fail("a", lease->lease_id, "shutting down", true, i));
  }
  EXPECT_TRUE(scheduler.Tick(10).empty());
  const TaskLease lease = MustLease(scheduler, "a", 10);
  EXPECT_EQ(scheduler.Complete("a", lease.lease_id, 11).kind, ResultOutcome::kStageComplete);
}

// A rolling upgrade: a worker of another build plans the job differently. Its reports are
// no failures (however many, on however many tasks), it gets none of the job's tasks again
// but still gets other jobs', the job waits while only incompatible workers are about, and a
// compatible worker finishes it.
TEST(SchedulerTest, IncompatibleWorkerNeverFailsTheJobAndGetsNoMoreOfIt) {
  SchedulerOptions options = SmallOptions();
  options.max_task_failures = 1;  // a single real failure would end the job
  options.max_worker_failures_per_job = 1;
  Scheduler scheduler(options);
  scheduler.AddJob(MakeJob("old", {0, 1}, 1, 1, /*priority=*/1, 0));
  scheduler.AddJob(MakeJob("other", {0}, 1, 1, /*priority=*/0, 1));
  const TaskLease first = MustLease(scheduler, "new-build", 0);
  const TaskLease second = MustLease(scheduler, "new-build", 0);  // another thread's
  ASSERT_EQ(first.job_id, "old");
  ASSERT_EQ(second.job_id, "old");
  EXPECT_TRUE(scheduler.Incompatible("new-build", first.lease_id, 1));
  EXPECT_FALSE(scheduler.Incompatible("new-build", second.lease_id, 1));  // marked already
  EXPECT_FALSE(scheduler.Incompatible("new-build", second.lease_id, 1));  // not current now
  EXPECT_EQ(scheduler.Stats(1).workers_incompatible, 1);
  EXPECT_EQ(scheduler.Stats(1).tasks_leased, 0);
  // Only the other job's task for it.
  const TaskLease other = MustLease(scheduler, "new-build", 2);
  EXPECT_EQ(other.job_id, "other");
  EXPECT_EQ(scheduler.Complete("new-build", other.lease_id, 3).kind, ResultOutcome::kStageComplete);
  EXPECT_FALSE(scheduler.Lease("new-build", 4));
  // Only the incompatible worker is active for a long while: "old" waits.
  for (int64_t t = 1000; t <= 100'000; t += 1000) {
    EXPECT_FALSE(scheduler.Lease("new-build", t));
    ASSERT_TRUE(scheduler.Tick(t).empty()) << t;
  }
  ASSERT_TRUE(scheduler.HasJob("old"));
  // A compatible worker arrives and does both tasks.
  for (int i = 0; i < 2; ++i) {
    const TaskLease lease = MustLease(scheduler, "old-build", 100'000);
    EXPECT_EQ(lease.job_id, "old");
    scheduler.Complete("old-build", lease.lease_id, 100'001);
    scheduler.GroupAssembled("old", lease.group_index);
  }
  EXPECT_TRUE(scheduler.JobComplete("old"));
}

// Incompatible workers do not keep a job alive that every compatible worker has failed.
TEST(SchedulerTest, IncompatibleWorkersDoNotHideAStuckJob) {
  SchedulerOptions options = SmallOptions();
  options.max_task_failures = 3;
  Scheduler scheduler(options);
  scheduler.AddJob(MakeJob("j", {0}));
  const TaskLease incompatible = MustLease(scheduler, "new-build", 0);
  EXPECT_TRUE(scheduler.Incompatible("new-build", incompatible.lease_id, 0));
  const TaskLease failed = MustLease(scheduler, "a", 0);
  EXPECT_FALSE(scheduler.Fail("a", failed.lease_id, "bad input", false, 0));
  const std::vector<JobFailure> failures = scheduler.Tick(10);
  ASSERT_EQ(failures.size(), 1u);
  EXPECT_THAT(failures[0].reason, HasSubstr("bad input"));
}

TEST(SchedulerTest, SignedOffWorkerIsNoLongerActive) {
  Scheduler scheduler(SmallOptions());
  scheduler.AddJob(MakeJob("j", {0, 1}));
  const TaskLease lease = MustLease(scheduler, "a", 0);
  MustLease(scheduler, "b", 0);
  EXPECT_EQ(scheduler.Stats(0).workers_active, 2);
  EXPECT_FALSE(scheduler.Fail("a", lease.lease_id, "stopping", /*handed_back=*/true, 1));
  scheduler.SignOff("a");
  scheduler.SignOff("never-seen");  // nothing to forget
  EXPECT_EQ(scheduler.Stats(1).workers_active, 1);
  EXPECT_EQ(scheduler.Stats(1).tasks_pending, 1);  // its task is back in the queue
}

TEST(SchedulerTest, RemoveJobMakesLeasesStaleAndFreesSlots) {
  SchedulerOptions options = SmallOptions();
  options.max_open_tiles = 1;
  Scheduler scheduler(options);
  scheduler.AddJob(MakeJob("x", {0, 1}, 2, 1, /*priority=*/1));
  scheduler.AddJob(MakeJob("y", {0}, 1, 1, /*priority=*/0));
  const TaskLease x0 = MustLease(scheduler, "a", 0);
  const TaskLease x1 = MustLease(scheduler, "a", 0);
  EXPECT_EQ(x0.job_id, "x");
  EXPECT_EQ(x1.job_id, "x");
  EXPECT_FALSE(scheduler.Lease("b", 0));  // "y" waits for the only slot
  EXPECT_EQ(scheduler.Complete("a", x0.lease_id, 0).kind, ResultOutcome::kAccepted);

  scheduler.RemoveJob("x");
  EXPECT_FALSE(scheduler.HasJob("x"));
  EXPECT_EQ(scheduler.Complete("a", x1.lease_id, 10).kind, ResultOutcome::kDropped);
  EXPECT_FALSE(scheduler.Extend("a", x1.lease_id, 10).ok());
  EXPECT_FALSE(scheduler.Fail("a", x1.lease_id, "x", false, 10));
  const SchedulerStats stats = scheduler.Stats(10);
  EXPECT_EQ(stats.tiles_open, 0);
  EXPECT_EQ(stats.tasks_leased, 0);
  EXPECT_TRUE(scheduler.Tick(5000).empty());  // no expiry of a forgotten lease
  EXPECT_EQ(scheduler.Stats(5000).leases_expired, 0);
  const std::optional<TaskLease> y = scheduler.Lease("b", 5000);
  ASSERT_TRUE(y);
  EXPECT_EQ(y->job_id, "y");
}

TEST(SchedulerTest, StatsCountPendingAndLeasedTasks) {
  Scheduler scheduler(SmallOptions());
  scheduler.AddJob(MakeJob("j", {0, 1, 2}, 4, 2));
  MustLease(scheduler, "a", 0);
  MustLease(scheduler, "b", 0);
  const SchedulerStats stats = scheduler.Stats(0);
  EXPECT_EQ(stats.tasks_leased, 2);
  EXPECT_EQ(stats.tasks_pending, 4);
  EXPECT_EQ(stats.tiles_open, 1);
  EXPECT_EQ(stats.workers_active, 2);
  EXPECT_EQ(scheduler.Stats(31'000).workers_active, 0);
}

// ---------------------------------------------------------------------------------------------
// A simulated farm: 1,000 workers that complete, fail, crash (never report) or stall past
// their lease, over several jobs, with a fake clock. A mirror of what the scheduler should
// know checks it from outside.

struct FarmConfig {
  int workers = 1000;
  int jobs = 5;
  int tiles_per_job = 200;
  int samples = 64;
  int samples_per_task = 9;  // 8 batches, the last of 1 sample
  std::string poison_job;    // its tile `poison_tile` fails on every worker
  int poison_tile = -1;
  uint64_t seed = 0x5eed'f00d;
};

struct FarmResult {
  std::set<std::string> completed;
  std::map<std::string, std::string> failed;  // job id -> reason
  int64_t late_reports = 0, late_dropped = 0;
  int64_t expired = 0;  // by the mirror's reckoning
  int exclusions = 0;   // (worker, job) pairs that reached the exclusion threshold
  int max_tiles_open = 0;
  int64_t sim_ms = 0;
  SchedulerStats stats;
  int64_t violations = 0;
  std::string first_violation;
};

class Farm {
 public:
  explicit Farm(const FarmConfig& config) : config_(config), rng_(config.seed) {
    options_.lease_ms = 5000;
    // Four distinct workers per task: with the failure rates below a task that fails on that
    // many workers by chance is very unlikely (~1e-3 over the farm), so the expected outcome
    // is that every healthy job completes.
    options_.max_task_failures = 4;
    options_.max_worker_failures_per_job = 3;
    options_.max_open_tiles = 128;  // up to 1024 tasks at once: the whole farm is busy
    options_.worker_active_ms = 30'000;
    options_.lease_id_base = 1'000'000;
    scheduler_.emplace(options_);
  }

  FarmResult Run() {
    const int priorities[] = {1, 3, 3, 0, 2};
    for (int j = 0; j < config_.jobs; ++j) {
      JobSpec spec;
      spec.job_id = absl::StrCat("job", j);
      spec.priority = priorities[j % 5];
      spec.sequence = j;
      for (int t = 0; t < config_.tiles_per_job; ++t) {
        spec.groups.push_back(GroupWork{1000 + 3 * t, {1000 + 3 * t}});
      }
      spec.samples = config_.samples;
      spec.samples_per_task = config_.samples_per_task;
      specs_[spec.job_id] = spec;
      scheduler_->AddJob(spec);
      jobs_[spec.job_id].unopened = config_.tiles_per_job;
    }
    for (int w = 0; w < config_.workers; ++w) {
      Worker worker;
      worker.id = absl::StrCat("w", w);
      worker.flaky = w % 200 == 7;  // 5 workers that fail most tasks: they get excluded
      worker.next_ms = Uniform(0, 1000);
      workers_.push_back(worker);
    }
    constexpr int64_t kStepMs = 100, kLimitMs = 4 * 3600 * 1000;
    for (now_ = 0; !jobs_.empty() && now_ < kLimitMs; now_ += kStepMs) {
      for (Worker& worker : workers_) Step(worker);
      Tick();
      Assemble();
      const SchedulerStats stats = scheduler_->Stats(now_);
      Check(stats.tiles_open <= options_.max_open_tiles, "stats: too many open tiles");
      result_.max_tiles_open = std::max(result_.max_tiles_open, stats.tiles_open);
    }
    result_.sim_ms = now_;
    result_.stats = scheduler_->Stats(now_);
    for (const auto& [key, count] : failures_) {
      if (count >= options_.max_worker_failures_per_job) ++result_.exclusions;
    }
    CheckAcceptedOnce();
    return result_;
  }

 private:
  struct Worker {
    std::string id;
    bool flaky = false;
    enum State { kIdle, kWorking, kDown } state = kIdle;
    enum Plan { kComplete, kFail, kCrash, kStall } plan = kComplete;
    int64_t next_ms = 0;  // next poll, report, crash or restart
    int64_t next_extend_ms = std::numeric_limits<int64_t>::max();
    TaskLease lease;
  };
  struct MirrorLease {
    std::string job_id, worker_id;
    int tile = 0, batch = 0;
    int64_t deadline_ms = 0;
  };
  struct MirrorJob {
    int unopened = 0;
    std::set<int> open;  // tiles with work issued, not yet assembled
  };
  using TaskKey = std::tuple<std::string, int, int>;  // job, tile, batch

  int64_t Uniform(int64_t lo, int64_t hi) {
    return std::uniform_int_distribution<int64_t>(lo, hi)(rng_);
  }
  double Unit() { return std::uniform_real_distribution<double>(0.0, 1.0)(rng_); }

  void Check(bool ok, const std::string& what) {
    if (ok) return;
    if (result_.violations++ == 0) result_.first_violation = absl::StrCat(what, " at ", now_);
  }

  void Step(Worker& worker) {
    if (now_ < worker.next_ms &&
        !(worker.state == Worker::kWorking && now_ >= worker.next_extend_ms)) {
      return;
    }
    switch (worker.state) {
      case Worker::kDown:
        worker.state = Worker::kIdle;  // restarted; polls at once
        [[fallthrough]];
      case Worker::kIdle:
        Poll(worker);
        return;
      case Worker::kWorking:
        if (now_ >= worker.next_ms) {
          Report(worker);
        } else {
          Extend(worker);
        }
        return;
    }
  }

  void Poll(Worker& worker) {
    const std::optional<TaskLease> lease = scheduler_->Lease(worker.id, now_);
    if (!lease) {
      worker.next_ms = now_ + 1000;
      return;
    }
    OnLease(worker.id, *lease);
    worker.state = Worker::kWorking;
    worker.lease = *lease;
    worker.next_extend_ms = std::numeric_limits<int64_t>::max();
    const double u = Unit();
    const bool poisoned =
        lease->job_id == config_.poison_job && lease->group_index == config_.poison_tile;
    if (poisoned || (worker.flaky && u < 0.6) || (!worker.flaky && u < 0.003)) {
      worker.plan = Worker::kFail;
      worker.next_ms = now_ + Uniform(200, 2000);
    } else if (u > 0.997) {
      worker.plan = Worker::kCrash;
      worker.next_ms = now_ + Uniform(500, 4000);
    } else if (u > 0.994) {
      worker.plan = Worker::kStall;  // no extensions; reports well after the deadline
      worker.next_ms = now_ + options_.lease_ms + Uniform(1000, 6000);
    } else {
      worker.plan = Worker::kComplete;
      const int64_t duration = Uniform(300, 8000);
      worker.next_ms = now_ + duration;
      if (duration > 3000) worker.next_extend_ms = now_ + 2000;  // long task: keep it alive
    }
  }

  void Extend(Worker& worker) {
    worker.next_extend_ms += 2000;
    const absl::StatusOr<int64_t> deadline =
        scheduler_->Extend(worker.id, worker.lease.lease_id, now_);
    const auto it = live_.find(worker.lease.lease_id);
    Check(deadline.ok() == (it != live_.end()),
          "extension of a current lease refused or "
          "of a stale one granted");
    if (deadline.ok() && it != live_.end()) {
      Check(*deadline == now_ + options_.lease_ms, "wrong extended deadline");
      it->second.deadline_ms = *deadline;
    }
  }

  void Report(Worker& worker) {
    const uint64_t lease_id = worker.lease.lease_id;
    const auto live = live_.find(lease_id);
    const bool current = live != live_.end();
    worker.state = Worker::kIdle;
    worker.next_ms = now_ + 100;
    switch (worker.plan) {
      case Worker::kCrash:
        worker.state = Worker::kDown;  // never reports; the lease must expire
        worker.next_ms = now_ + Uniform(20'000, 60'000);
        return;
      case Worker::kFail: {
        std::optional<JobFailure> failure =
            scheduler_->Fail(worker.id, lease_id, "render error", false, now_);
        if (!current) {
          Check(!failure, "a stale lease's failure failed a job");
          return;
        }
        CountFailure(live->second);
        live_.erase(live);
        if (failure) OnJobFailure(*failure);
        return;
      }
      case Worker::kStall:
      case Worker::kComplete: {
        const ResultOutcome outcome = scheduler_->Complete(worker.id, lease_id, now_);
        if (worker.plan == Worker::kStall) {
          ++result_.late_reports;
          if (outcome.kind == ResultOutcome::kDropped) ++result_.late_dropped;
        }
        Check((outcome.kind != ResultOutcome::kDropped) == current,
              "result accepted for a stale lease or dropped for a current one");
        if (outcome.kind == ResultOutcome::kDropped || !current) return;
        OnAccepted(live->second, outcome);
        live_.erase(live);
        return;
      }
    }
  }

  void OnLease(const std::string& worker_id, const TaskLease& lease) {
    Check(lease.lease_id >= options_.lease_id_base && lease.lease_id > last_lease_id_,
          "lease ids not increasing from the base");
    last_lease_id_ = lease.lease_id;
    const auto job = jobs_.find(lease.job_id);
    if (job == jobs_.end()) {
      Check(false, "lease of a removed job");
      return;
    }
    const int batch = lease.sample_begin / config_.samples_per_task;
    Check(lease.sample_begin == batch * config_.samples_per_task &&
              lease.sample_end ==
                  std::min(config_.samples, lease.sample_begin + config_.samples_per_task),
          "wrong batch bounds");
    Check(failures_[{lease.job_id, worker_id}] < options_.max_worker_failures_per_job,
          "a worker got a task of a job it is excluded from");
    const TaskKey task{lease.job_id, lease.group_index, batch};
    Check(!failed_on_[task].contains(worker_id), "a worker got back a task it failed");
    Check(!accepted_.contains(task), "an accepted task was issued again");
    for (const auto& [id, other] : live_) {
      (void)id;  // cheap enough: at most a few hundred leases are live
      if (std::tie(other.job_id, other.tile, other.batch) == task) {
        Check(false, "a task was issued twice at once");
        break;
      }
    }
    if (!job->second.open.contains(lease.group_index)) OpenTile(worker_id, lease, job->second);
    live_[lease.lease_id] = {lease.job_id, worker_id, lease.group_index, batch, lease.deadline_ms};
  }

  void OpenTile(const std::string& worker_id, const TaskLease& lease, MirrorJob& job) {
    job.open.insert(lease.group_index);
    --job.unopened;
    ++open_tiles_;
    Check(open_tiles_ <= options_.max_open_tiles, "mirror: too many open tiles");
    // A new tile of this job opened, so every job ahead of it that this worker may run had
    // no tile left to open.
    const JobSpec& spec = specs_.at(lease.job_id);
    for (const auto& [other_id, other] : jobs_) {
      const JobSpec& other_spec = specs_.at(other_id);
      const bool ahead =
          other_spec.priority > spec.priority ||
          (other_spec.priority == spec.priority && other_spec.sequence < spec.sequence);
      if (ahead && other.unopened > 0 &&
          failures_[{other_id, worker_id}] < options_.max_worker_failures_per_job) {
        Check(false, "a tile opened while a job ahead had tiles to open");
      }
    }
  }

  void OnAccepted(const MirrorLease& lease, const ResultOutcome& outcome) {
    const TaskKey task{lease.job_id, lease.tile, lease.batch};
    Check(outcome.job_id == lease.job_id && outcome.group_index == lease.tile &&
              outcome.sample_begin == lease.batch * config_.samples_per_task,
          "outcome does not match its lease");
    Check(accepted_.insert(task).second, "a task accepted twice");
    const int batches = (config_.samples + config_.samples_per_task - 1) / config_.samples_per_task;
    const bool tile_done = ++tile_accepted_[{lease.job_id, lease.tile}] == batches;
    Check(tile_done == (outcome.kind == ResultOutcome::kStageComplete),
          "kStageComplete not exactly when the tile's last batch is in");
    if (tile_done) assembly_.emplace_back(now_ + 200, lease.job_id, lease.tile);
  }

  void CountFailure(const MirrorLease& lease) {
    ++failures_[{lease.job_id, lease.worker_id}];
    failed_on_[{lease.job_id, lease.tile, lease.batch}].insert(lease.worker_id);
  }

  void Tick() {
    for (const JobFailure& failure : scheduler_->Tick(now_)) OnJobFailure(failure);
    for (auto it = live_.begin(); it != live_.end();) {
      if (it->second.deadline_ms > now_) {
        ++it;
        continue;
      }
      ++result_.expired;
      CountFailure(it->second);
      it = live_.erase(it);
    }
  }

  void Assemble() {
    // The service stores a tile a little after its last result, as a real one would.
    while (!assembly_.empty() && std::get<0>(assembly_.front()) <= now_) {
      const auto [ready_ms, job_id, tile] = assembly_.front();
      assembly_.erase(assembly_.begin());
      const auto job = jobs_.find(job_id);
      if (job == jobs_.end()) continue;
      scheduler_->GroupAssembled(job_id, tile);
      job->second.open.erase(tile);
      --open_tiles_;
      if (scheduler_->JobComplete(job_id)) {
        scheduler_->RemoveJob(job_id);
        result_.completed.insert(job_id);
        ForgetJob(job_id);
      }
    }
  }

  void OnJobFailure(const JobFailure& failure) {
    Check(jobs_.contains(failure.job_id), "failure of an unknown job");
    Check(!scheduler_->HasJob(failure.job_id), "a failed job is still scheduled");
    result_.failed[failure.job_id] = failure.reason;
    ForgetJob(failure.job_id);
  }

  void ForgetJob(const std::string& job_id) {
    const auto job = jobs_.find(job_id);
    if (job == jobs_.end()) return;
    open_tiles_ -= static_cast<int>(job->second.open.size());
    jobs_.erase(job);
    std::erase_if(live_, [&](const auto& entry) { return entry.second.job_id == job_id; });
  }

  void CheckAcceptedOnce() {
    for (const std::string& job_id : result_.completed) {
      const JobSpec& spec = specs_.at(job_id);
      for (const GroupWork& group : spec.groups) {
        const int tile = group.group_index;
        for (int begin = 0; begin < spec.samples; begin += spec.samples_per_task) {
          Check(accepted_.contains({job_id, tile, begin / spec.samples_per_task}),
                absl::StrCat(job_id, " completed without tile ", tile, " samples ", begin));
        }
      }
    }
  }

  const FarmConfig config_;
  std::mt19937_64 rng_;
  SchedulerOptions options_;
  std::optional<Scheduler> scheduler_;
  int64_t now_ = 0;
  std::vector<Worker> workers_;
  std::map<std::string, JobSpec> specs_;
  std::map<std::string, MirrorJob> jobs_;                        // still scheduled
  std::map<uint64_t, MirrorLease> live_;                         // current leases
  std::map<std::pair<std::string, std::string>, int> failures_;  // (job, worker)
  std::map<TaskKey, std::set<std::string>> failed_on_;
  std::set<TaskKey> accepted_;
  std::map<std::pair<std::string, int>, int> tile_accepted_;
  std::vector<std::tuple<int64_t, std::string, int>> assembly_;  // (when, job, tile)
  int open_tiles_ = 0;
  uint64_t last_lease_id_ = 0;
  FarmResult result_;
};

TEST(SchedulerFarmTest, EveryJobCompletesDespiteFailuresCrashesAndStalls) {
  const auto start = std::chrono::steady_clock::now();
  const FarmResult result = Farm(FarmConfig{}).Run();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "farm: %.0f s simulated in %.2f s; %lld accepted, %lld expired, %lld dropped, "
      "%d exclusions, at most %d open tiles\n",
      result.sim_ms / 1000.0, seconds, static_cast<long long>(result.stats.results_accepted),
      static_cast<long long>(result.stats.leases_expired),
      static_cast<long long>(result.stats.results_dropped), result.exclusions,
      result.max_tiles_open);

  EXPECT_EQ(result.violations, 0) << result.first_violation;
  EXPECT_TRUE(result.failed.empty())
      << result.failed.begin()->first << ": " << result.failed.begin()->second;
  EXPECT_EQ(result.completed.size(), 5u);
  EXPECT_EQ(result.stats.results_accepted, 5 * 200 * 8);
  // The failure modes all happened, and the scheduler saw them as the mirror did.
  EXPECT_GT(result.late_reports, 0);
  EXPECT_EQ(result.late_dropped, result.late_reports);
  EXPECT_GT(result.expired, result.late_reports);  // crashes expire too
  EXPECT_EQ(result.stats.leases_expired, result.expired);
  EXPECT_GT(result.exclusions, 0);
  EXPECT_EQ(result.max_tiles_open, 128);
  EXPECT_EQ(result.stats.tiles_open, 0);
  EXPECT_EQ(result.stats.tasks_leased, 0);
}

TEST(SchedulerFarmTest, PoisonTileFailsItsJobOnly) {
  FarmConfig config;
  config.poison_job = "job2";
  config.poison_tile = 1000 + 3 * 42;
  const FarmResult result = Farm(config).Run();
  EXPECT_EQ(result.violations, 0) << result.first_violation;
  ASSERT_EQ(result.failed.size(), 1u);
  EXPECT_EQ(result.failed.begin()->first, "job2");
  EXPECT_THAT(result.failed.begin()->second, HasSubstr(absl::StrCat("tile group ", 1000 + 3 * 42)));
  EXPECT_THAT(result.failed.begin()->second, HasSubstr("render error"));
  EXPECT_EQ(result.completed, (std::set<std::string>{"job0", "job1", "job3", "job4"}));
  EXPECT_EQ(result.late_dropped, result.late_reports);
}

}  // namespace
}  // namespace pdsm
