#include "server/job_eta.h"

#include <vector>

#include <gtest/gtest.h>

namespace pdsm {
namespace {

JobProgress Progress(int64_t total, int64_t done, int64_t at_add, int64_t added_ms) {
  JobProgress p;
  p.samples_total = total;
  p.samples_done = done;
  p.samples_at_add = at_add;
  p.added_ms = added_ms;
  return p;
}

TEST(JobEta, AnEngineJobsRateSinceItWasAddedGivesItsSecondsLeft) {
  // 300 samples gained in 3 s since it was added (resumed at 100): 600 left take 6 s.
  EXPECT_DOUBLE_EQ(RateEtaSeconds(Progress(1000, 400, 100, 1000), 4000), 6.0);
  EXPECT_LT(RateEtaSeconds(Progress(1000, 100, 100, 1000), 4000), 0) << "nothing gained yet";
  EXPECT_LT(RateEtaSeconds(Progress(1000, 400, 100, 4000), 4000), 0) << "no time elapsed";
  EXPECT_EQ(RateEtaSeconds(Progress(1000, 1000, 1000, 1000), 1000), 0) << "none left";
}

TEST(JobEta, ARunningLevelKeepsTheJobsEtaFromReadingZero) {
  // Base maps done, one level running: the job's ETA is the level's, not 0.
  const std::vector<double> one{12.5};
  EXPECT_DOUBLE_EQ(JobEtaSeconds(0, /*base_done=*/true, one), 12.5);
  // A level that has no rate yet: unknown, not "done".
  const std::vector<double> unknown{-1};
  EXPECT_LT(JobEtaSeconds(0, true, unknown), 0);
  // The longest part: a base still running beside another light's level.
  const std::vector<double> two{3, 7};
  EXPECT_DOUBLE_EQ(JobEtaSeconds(20, false, two), 20);
  EXPECT_DOUBLE_EQ(JobEtaSeconds(5, false, two), 7);
  EXPECT_LT(JobEtaSeconds(-1, false, two), 0) << "the base has no rate yet";
  // Without levels: the base's, as before levels existed.
  EXPECT_DOUBLE_EQ(JobEtaSeconds(9, false, {}), 9);
  EXPECT_EQ(JobEtaSeconds(0, true, {}), 0);
}

}  // namespace
}  // namespace pdsm
