// Verification by redundancy in the scheduler (scheduler.h): which tasks are drawn, who may
// vote, how votes decide, quarantine, and the recomputation hooks the engine calls.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <vector>

#include "core/pipeline/scheduler.h"

namespace pdsm {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

// `groups` groups of one tile each (group i holds tile i), `batches` one-sample tasks per group.
JobSpec Job(int groups, int batches) {
  JobSpec job;
  job.job_id = "j";
  for (int g = 0; g < groups; ++g) job.groups.push_back(GroupWork{g, {g}});
  job.samples = batches;
  job.samples_per_task = 1;
  return job;
}

SchedulerOptions Verifying(double fraction) {
  SchedulerOptions options;
  options.lease_ms = 1000;
  options.worker_active_ms = 30'000;
  options.verify_fraction = fraction;
  options.verify_seed = 42;
  return options;
}

TaskLease MustLease(Scheduler& scheduler, const std::string& worker, int64_t now_ms) {
  const std::optional<TaskLease> lease = scheduler.Lease(worker, now_ms);
  EXPECT_TRUE(lease) << worker << " got no task";
  return lease.value_or(TaskLease{});
}

TEST(SchedulerVerification, TheDrawFollowsTheFraction) {
  for (const double fraction : {0.0, 0.25, 1.0}) {
    Scheduler scheduler(Verifying(fraction));
    scheduler.AddJob(Job(1, 400));
    int verified = 0, tasks = 0;
    while (std::optional<TaskLease> lease = scheduler.Lease("w", 0)) {
      verified += lease->verify ? 1 : 0;
      ++tasks;
    }
    ASSERT_EQ(tasks, 400);
    if (fraction == 0.0) EXPECT_EQ(verified, 0);
    if (fraction == 1.0) EXPECT_EQ(verified, 400);
    if (fraction == 0.25) {
      EXPECT_GT(verified, 60);  // 100 expected; sd 8.7
      EXPECT_LT(verified, 140);
    }
  }
}

TEST(SchedulerVerification, ASecondWorkerVotesAndAgreementCompletesTheTask) {
  Scheduler scheduler(Verifying(1.0));
  scheduler.AddJob(Job(1, 2));
  const TaskLease a = MustLease(scheduler, "a", 0);
  const TaskLease b = MustLease(scheduler, "b", 0);
  // First results: merged, the tasks wait for a vote from the other worker.
  ResultOutcome first = scheduler.Complete("a", a.lease_id, 1, "x");
  EXPECT_EQ(first.kind, ResultOutcome::kAccepted);
  EXPECT_TRUE(first.merge);
  EXPECT_TRUE(scheduler.Complete("b", b.lease_id, 1, "y").merge);
  EXPECT_EQ(scheduler.Stats(1).tasks_awaiting_verification, 2);
  // Each worker now gets the other's task, never its own.
  const TaskLease a2 = MustLease(scheduler, "a", 2);
  const TaskLease b2 = MustLease(scheduler, "b", 2);
  EXPECT_EQ(a2.sample_begin, b.sample_begin);
  EXPECT_EQ(b2.sample_begin, a.sample_begin);
  EXPECT_FALSE(scheduler.Lease("a", 2));
  const ResultOutcome vote = scheduler.Complete("a", a2.lease_id, 3, "y");
  EXPECT_EQ(vote.kind, ResultOutcome::kAccepted);
  EXPECT_FALSE(vote.merge);  // compared, not merged twice
  const ResultOutcome last = scheduler.Complete("b", b2.lease_id, 3, "x");
  EXPECT_EQ(last.kind, ResultOutcome::kStageComplete);
  EXPECT_FALSE(last.merge);
  EXPECT_TRUE(last.quarantined.empty());
  const SchedulerStats stats = scheduler.Stats(3);
  EXPECT_EQ(stats.tasks_verified, 2);
  EXPECT_EQ(stats.verification_mismatches, 0);
  EXPECT_EQ(stats.tasks_awaiting_verification, 0);
}

TEST(SchedulerVerification, AThirdWorkerDecidesAndTheOutvotedOneIsQuarantined) {
  Scheduler scheduler(Verifying(1.0));
  scheduler.AddJob(Job(2, 1));
  scheduler.Lease("b", 0);  // b and c are active (and hold group 0 and 1's tasks)
  scheduler.Lease("c", 0);
  // Both tasks are leased; the liar gets one once b hands its back.
  scheduler.Fail("b", 1, "", /*handed_back=*/true, 0);
  const TaskLease liar = MustLease(scheduler, "liar", 0);
  const TaskLease liar_other = [&] {
    scheduler.Fail("c", 2, "", /*handed_back=*/true, 0);
    return MustLease(scheduler, "liar", 0);
  }();
  EXPECT_TRUE(scheduler.Complete("liar", liar.lease_id, 1, "bad").merge);
  // b disagrees with the liar: neither is trusted yet, a third worker decides.
  const TaskLease b = MustLease(scheduler, "b", 2);
  EXPECT_EQ(b.group_index, liar.group_index);
  const ResultOutcome undecided = scheduler.Complete("b", b.lease_id, 3, "good");
  EXPECT_EQ(undecided.kind, ResultOutcome::kAccepted);
  EXPECT_TRUE(undecided.quarantined.empty());
  const TaskLease c = MustLease(scheduler, "c", 4);
  EXPECT_EQ(c.group_index, liar.group_index);
  const ResultOutcome decided = scheduler.Complete("c", c.lease_id, 5, "good");
  EXPECT_EQ(decided.kind, ResultOutcome::kStageComplete);
  EXPECT_FALSE(decided.merge);
  EXPECT_THAT(decided.quarantined, ElementsAre("liar"));
  EXPECT_TRUE(scheduler.Quarantined("liar"));
  // Quarantined: its other lease is taken back, its result dropped, it gets nothing more and
  // no longer counts as active.
  EXPECT_EQ(scheduler.Complete("liar", liar_other.lease_id, 6, "bad").kind,
            ResultOutcome::kDropped);
  EXPECT_FALSE(scheduler.Lease("liar", 6));
  const SchedulerStats stats = scheduler.Stats(6);
  EXPECT_EQ(stats.workers_quarantined, 1);
  EXPECT_EQ(stats.verification_mismatches, 1);
  EXPECT_EQ(stats.workers_active, 2);
  const TaskLease redo = MustLease(scheduler, "b", 7);
  EXPECT_EQ(redo.group_index, liar_other.group_index);
}

TEST(SchedulerVerification, AQuarantinedWorkersVotesNoLongerCount) {
  Scheduler scheduler(Verifying(1.0));
  scheduler.AddJob(Job(2, 1));
  scheduler.Lease("b", 0);
  scheduler.Lease("c", 0);
  scheduler.Fail("b", 1, "", true, 0);
  scheduler.Fail("c", 2, "", true, 0);
  const TaskLease t0 = MustLease(scheduler, "liar", 0);
  const TaskLease t1 = MustLease(scheduler, "liar", 0);
  scheduler.Complete("liar", t0.lease_id, 1, "bad0");
  scheduler.Complete("liar", t1.lease_id, 1, "bad1");
  // Task 0 convicts the liar; task 1 holds only its vote, which is then dropped: one honest
  // vote is not yet agreement, a second one is needed.
  const TaskLease b0 = MustLease(scheduler, "b", 2);
  ASSERT_EQ(b0.group_index, t0.group_index);
  scheduler.Complete("b", b0.lease_id, 2, "good0");
  const TaskLease c0 = MustLease(scheduler, "c", 2);
  ASSERT_EQ(c0.group_index, t0.group_index);
  EXPECT_THAT(scheduler.Complete("c", c0.lease_id, 2, "good0").quarantined, ElementsAre("liar"));
  const TaskLease b1 = MustLease(scheduler, "b", 3);
  ASSERT_EQ(b1.group_index, t1.group_index);
  const ResultOutcome one = scheduler.Complete("b", b1.lease_id, 3, "good1");
  EXPECT_EQ(one.kind, ResultOutcome::kAccepted);  // not decided on b's vote alone
  const TaskLease c1 = MustLease(scheduler, "c", 4);
  const ResultOutcome two = scheduler.Complete("c", c1.lease_id, 4, "good1");
  EXPECT_EQ(two.kind, ResultOutcome::kStageComplete);
  EXPECT_TRUE(two.quarantined.empty());
}

TEST(SchedulerVerification, ALoneWorkersResultIsAcceptedUnverified) {
  Scheduler scheduler(Verifying(1.0));
  scheduler.AddJob(Job(1, 1));
  const TaskLease only = MustLease(scheduler, "a", 0);
  const ResultOutcome outcome = scheduler.Complete("a", only.lease_id, 1, "x");
  EXPECT_EQ(outcome.kind, ResultOutcome::kStageComplete);
  EXPECT_TRUE(outcome.merge);
  EXPECT_EQ(scheduler.Stats(1).tasks_unverified, 1);
}

TEST(SchedulerVerification, AVoteNoActiveWorkerCanGiveIsAcceptedAtTheTick) {
  Scheduler scheduler(Verifying(1.0));
  scheduler.AddJob(Job(1, 1));
  scheduler.Lease("b", 0);  // b is seen, then holds the only task...
  scheduler.Fail("b", 1, "", true, 0);
  const TaskLease a = MustLease(scheduler, "a", 0);  // ...which a takes
  EXPECT_EQ(scheduler.Complete("a", a.lease_id, 1, "x").kind, ResultOutcome::kAccepted);
  EXPECT_TRUE(scheduler.AcceptUnverifiable(1).empty());  // b could still vote
  // b goes silent; past worker_active_ms only a is active, and a cannot verify itself.
  scheduler.Lease("a", 40'000);
  scheduler.Tick(40'000);
  const std::vector<ResultOutcome> accepted = scheduler.AcceptUnverifiable(40'000);
  ASSERT_EQ(accepted.size(), 1u);
  EXPECT_EQ(accepted[0].kind, ResultOutcome::kStageComplete);
  EXPECT_FALSE(accepted[0].merge);
  EXPECT_EQ(scheduler.Stats(40'000).tasks_unverified, 1);
}

TEST(SchedulerVerification, VotesThatNeverAgreeFailTheJob) {
  SchedulerOptions options = Verifying(1.0);
  options.max_task_failures = 1;  // at most 2 votes without agreement, then the job fails
  Scheduler scheduler(options);
  scheduler.AddJob(Job(1, 1));
  for (const char* w : {"b", "c"}) scheduler.Lease(w, 0);
  scheduler.Fail("b", 1, "", true, 0);
  const TaskLease a = MustLease(scheduler, "a", 0);
  scheduler.Complete("a", a.lease_id, 1, "x");
  const TaskLease b = MustLease(scheduler, "b", 1);
  scheduler.Complete("b", b.lease_id, 1, "y");
  const TaskLease c = MustLease(scheduler, "c", 1);
  const ResultOutcome outcome = scheduler.Complete("c", c.lease_id, 1, "z");
  ASSERT_TRUE(outcome.failure);
  EXPECT_THAT(outcome.failure->reason, HasSubstr("3 workers returned 3 different results"));
  EXPECT_FALSE(scheduler.HasJob("j"));
}

TEST(SchedulerVerification, AnAssembledGroupIsQueuedAgainAndAnOpenOneRestarts) {
  Scheduler scheduler(Verifying(0.0));
  JobSpec job = Job(2, 2);
  scheduler.AddJob(job);
  // Group 0: both batches done and assembled.
  for (int i = 0; i < 2; ++i) {
    const TaskLease lease = MustLease(scheduler, "a", 0);
    ASSERT_EQ(lease.group_index, 0);
    scheduler.Complete("a", lease.lease_id, 0);
  }
  scheduler.GroupAssembled("j", 0);
  // Group 1: open, one batch out.
  const TaskLease open = MustLease(scheduler, "a", 0);
  ASSERT_EQ(open.group_index, 1);
  EXPECT_FALSE(scheduler.RequeueGroup("j", 1));  // open: restarted at its stage's end instead
  EXPECT_FALSE(scheduler.RestartGroup("j", 1));  // work outstanding
  const std::optional<std::vector<int>> again = scheduler.RequeueGroup("j", 0);
  ASSERT_TRUE(again);
  EXPECT_THAT(*again, ElementsAre(0));
  EXPECT_FALSE(scheduler.RequeueGroup("j", 0));  // queued already
  EXPECT_EQ(*scheduler.TasksLeft("j"), 4);       // group 1's two, group 0's two again
  // Group 1 completes, then starts over.
  scheduler.Complete("a", open.lease_id, 0);
  const TaskLease second = MustLease(scheduler, "a", 0);
  ASSERT_EQ(second.group_index, 1);
  EXPECT_EQ(scheduler.Complete("a", second.lease_id, 0).kind, ResultOutcome::kStageComplete);
  const std::optional<std::vector<int>> restarted = scheduler.RestartGroup("j", 1);
  ASSERT_TRUE(restarted);
  EXPECT_THAT(*restarted, ElementsAre(1));
  // Every batch of both groups is handed out again, and the job completes only after them.
  int tasks = 0;
  while (std::optional<TaskLease> lease = scheduler.Lease("a", 0)) {
    const ResultOutcome outcome = scheduler.Complete("a", lease->lease_id, 0);
    if (outcome.kind == ResultOutcome::kStageComplete) {
      scheduler.GroupAssembled("j", outcome.group_index);
    }
    ++tasks;
  }
  EXPECT_EQ(tasks, 4);
  EXPECT_TRUE(scheduler.JobComplete("j"));
}

}  // namespace
}  // namespace pdsm
