#include "server/plan_budget.h"

#include <gtest/gtest.h>

namespace pdsm {
namespace {

using Verdict = PlanBudget::Verdict;
using CancelOutcome = PlanBudget::CancelOutcome;

PlanBudget::Entry Job(const std::string& id, int64_t bytes, int64_t sequence, int priority = 0) {
  return {.job_id = id, .priority = priority, .sequence = sequence, .bytes = bytes};
}

TEST(PlanBudget, AJobThatFitsActivatesOneThatDoesNotWaitsUntilMemoryIsReleased) {
  PlanBudget budget(100);
  EXPECT_TRUE(budget.Admit(Job("a", 60, 1)));
  EXPECT_FALSE(budget.Activated("a"));
  EXPECT_FALSE(budget.Admit(Job("b", 60, 2)));  // 120 > 100
  EXPECT_EQ(budget.usage().held_bytes, 60);
  EXPECT_EQ(budget.usage().jobs_waiting, 1);
  EXPECT_NE(budget.WaitingReason("b").find("waiting for coordinator memory"), std::string::npos);
  EXPECT_EQ(budget.WaitingReason("a"), "");
  EXPECT_FALSE(budget.TakeNext().has_value()) << "b does not fit beside a";

  budget.Release("a");
  const std::optional<PlanBudget::Entry> next = budget.TakeNext();
  ASSERT_TRUE(next.has_value());
  EXPECT_EQ(next->job_id, "b");
  EXPECT_EQ(budget.Planned("b", 60), Verdict::kActivate);
  EXPECT_FALSE(budget.Activated("b"));
  EXPECT_EQ(budget.usage().held_bytes, 60);
  EXPECT_EQ(budget.usage().jobs_waiting, 0);
}

TEST(PlanBudget, TurnsGoByPriorityThenSubmissionAndNoJobPassesOneWaitingAheadOfIt) {
  PlanBudget budget(100);
  ASSERT_TRUE(budget.Admit(Job("running", 90, 1)));
  EXPECT_FALSE(budget.Admit(Job("big", 50, 2)));
  // It would fit beside "running", but "big" waits ahead of it.
  EXPECT_FALSE(budget.Admit(Job("small", 5, 3)));
  EXPECT_FALSE(budget.Admit(Job("urgent", 50, 4, /*priority=*/10)));
  EXPECT_NE(budget.WaitingReason("small").find("2 jobs wait ahead of it"), std::string::npos)
      << budget.WaitingReason("small");
  EXPECT_FALSE(budget.TakeNext().has_value()) << "the first turn (urgent, 50) does not fit";

  budget.Release("running");
  std::optional<PlanBudget::Entry> next = budget.TakeNext();
  ASSERT_TRUE(next.has_value());
  EXPECT_EQ(next->job_id, "urgent");
  ASSERT_EQ(budget.Planned("urgent", 50), Verdict::kActivate);
  next = budget.TakeNext();
  ASSERT_TRUE(next.has_value());
  EXPECT_EQ(next->job_id, "big");
  ASSERT_EQ(budget.Planned("big", 50), Verdict::kActivate);
  EXPECT_FALSE(budget.TakeNext().has_value()) << "100 held: small waits";
  budget.Release("urgent");
  next = budget.TakeNext();
  ASSERT_TRUE(next.has_value());
  EXPECT_EQ(next->job_id, "small");
}

TEST(PlanBudget, AHigherPriorityJobDoesNotWaitBehindLowerOnes) {
  PlanBudget budget(100);
  ASSERT_TRUE(budget.Admit(Job("running", 50, 1)));
  EXPECT_FALSE(budget.Admit(Job("low", 80, 2)));
  EXPECT_TRUE(budget.Admit(Job("high", 40, 3, /*priority=*/1)));
}

TEST(PlanBudget, AJobAloneAlwaysFitsSoALoweredLimitCannotStallTheQueue) {
  PlanBudget budget(10);
  EXPECT_TRUE(budget.Admit(Job("huge", 1000, 1)));
  EXPECT_FALSE(budget.Admit(Job("next", 1, 2)));
  budget.Release("huge");
  budget.Enqueue(Job("resumed", -1, 0));  // bytes unknown: planned on its turn
  std::optional<PlanBudget::Entry> next = budget.TakeNext();
  ASSERT_TRUE(next.has_value());
  EXPECT_EQ(next->job_id, "resumed");
  EXPECT_EQ(budget.Planned("resumed", 500), Verdict::kActivate) << "nothing else held";
}

TEST(PlanBudget, AJobWhoseBytesTurnOutTooManyGoesBackToTheHeadOfTheQueue) {
  constexpr int64_t kMiB = 1 << 20;
  PlanBudget budget(100 * kMiB);
  ASSERT_TRUE(budget.Admit(Job("running", 50 * kMiB, 1)));
  budget.Enqueue(Job("resumed", -1, 2));
  budget.Enqueue(Job("later", 10 * kMiB, 3));
  std::optional<PlanBudget::Entry> next = budget.TakeNext();
  ASSERT_TRUE(next.has_value());
  ASSERT_EQ(next->job_id, "resumed");
  EXPECT_EQ(budget.Planned("resumed", 80 * kMiB), Verdict::kWait);
  EXPECT_EQ(budget.usage().held_bytes, 50 * kMiB);
  EXPECT_NE(budget.WaitingReason("resumed").find("0 jobs wait ahead"), std::string::npos);
  EXPECT_NE(budget.WaitingReason("resumed").find("80.0 MiB"), std::string::npos)
      << "its bytes are known now: " << budget.WaitingReason("resumed");
  EXPECT_FALSE(budget.TakeNext().has_value()) << "80 does not fit; later must not pass it";
}

TEST(PlanBudget, CancelsReachWaitingAndActivatingJobsAndNoneOther) {
  PlanBudget budget(100);
  ASSERT_TRUE(budget.Admit(Job("a", 60, 1)));
  EXPECT_EQ(budget.Cancel("a"), CancelOutcome::kActivating);
  EXPECT_TRUE(budget.Activated("a")) << "the activator must cancel it";
  EXPECT_EQ(budget.Cancel("a"), CancelOutcome::kNotHere) << "running: the engine cancels it";

  EXPECT_FALSE(budget.Admit(Job("b", 60, 2)));
  EXPECT_EQ(budget.Cancel("b"), CancelOutcome::kWasWaiting);
  EXPECT_EQ(budget.usage().jobs_waiting, 0);

  budget.Enqueue(Job("c", -1, 3));
  budget.Release("a");
  ASSERT_TRUE(budget.TakeNext().has_value());
  EXPECT_EQ(budget.Cancel("c"), CancelOutcome::kActivating);
  EXPECT_EQ(budget.Planned("c", 10), Verdict::kCancelled);
  EXPECT_EQ(budget.usage().held_bytes, 0);
  EXPECT_EQ(budget.usage().jobs_held, 0);
  EXPECT_EQ(budget.Cancel("unknown"), CancelOutcome::kNotHere);
}

TEST(PlanBudget, ReleaseForgetsHeldAndWaitingJobsAndIgnoresOthers) {
  PlanBudget budget(100);
  ASSERT_TRUE(budget.Admit(Job("a", 60, 1)));
  EXPECT_FALSE(budget.Admit(Job("b", 60, 2)));
  budget.Release("b");
  budget.Release("unknown");
  EXPECT_FALSE(budget.HasWaiting());
  budget.Release("a");
  EXPECT_EQ(budget.usage().held_bytes, 0);
  EXPECT_EQ(budget.usage().jobs_held, 0);
}

// A refinement level's bytes join its running job's: later jobs wait for them, the job is
// never stopped for them (held may pass the limit), and they leave with the job.
TEST(PlanBudget, ALevelsBytesJoinItsJobsUntilTheJobEnds) {
  constexpr int64_t kMiB = 1 << 20;
  PlanBudget budget(100 * kMiB);
  ASSERT_TRUE(budget.Admit(Job("a", 30 * kMiB, 1)));
  EXPECT_FALSE(budget.Activated("a"));
  budget.Grow("a", 40 * kMiB);  // its level's plan
  EXPECT_EQ(budget.usage().held_bytes, 70 * kMiB);
  EXPECT_FALSE(budget.Admit(Job("b", 40 * kMiB, 2))) << "110 > 100 with the level counted";
  budget.Grow("a", 50 * kMiB);  // its spliced tiles: past the limit, and nothing refuses it
  EXPECT_EQ(budget.usage().held_bytes, 120 * kMiB);
  EXPECT_NE(budget.WaitingReason("b").find("beside 120.0 MiB held by 1 running job"),
            std::string::npos)
      << budget.WaitingReason("b");
  budget.Grow("b", 10);        // waiting, holds nothing: ignored
  budget.Grow("unknown", 10);  // ignored
  budget.Grow("a", -500);      // never shrinks what a job holds
  EXPECT_EQ(budget.usage().held_bytes, 120 * kMiB);
  EXPECT_FALSE(budget.TakeNext().has_value());
  budget.Release("a");
  EXPECT_EQ(budget.usage().held_bytes, 0);
  const std::optional<PlanBudget::Entry> next = budget.TakeNext();
  ASSERT_TRUE(next.has_value());
  EXPECT_EQ(next->job_id, "b");
}

}  // namespace
}  // namespace pdsm
