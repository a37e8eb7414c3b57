#include "core/util/backoff.h"

#include <set>

#include <gtest/gtest.h>

namespace pdsm {
namespace {

using std::chrono::milliseconds;

TEST(BackoffTest, DoublesWithinEqualJitterUpToTheCapAndResets) {
  Backoff backoff(milliseconds(100), milliseconds(5000), /*seed=*/7);
  int64_t schedule = 100;
  for (int i = 0; i < 12; ++i) {
    const int64_t wait = backoff.Next().count();
    EXPECT_GE(wait, schedule / 2) << i;
    EXPECT_LE(wait, schedule) << i;
    schedule = std::min<int64_t>(5000, schedule * 2);
  }
  EXPECT_EQ(schedule, 5000);  // the loop reached the cap
  backoff.Reset();
  const int64_t wait = backoff.Next().count();
  EXPECT_GE(wait, 50);
  EXPECT_LE(wait, 100);
}

// Two workers that failed together wait different times: the jitter is real.
TEST(BackoffTest, DifferentSeedsSpreadTheRetries) {
  std::set<int64_t> waits;
  for (uint64_t seed = 1; seed <= 16; ++seed) {
    Backoff backoff(milliseconds(1000), milliseconds(5000), seed);
    waits.insert(backoff.Next().count());
  }
  EXPECT_GT(waits.size(), 8u);
}

}  // namespace
}  // namespace pdsm
