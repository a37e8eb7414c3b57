#include "core/pipeline/stage_rule.h"

#include <gtest/gtest.h>

#include "core/bake/adaptive_sampling.h"

namespace pdsm {
namespace {

// A one-pixel tile whose samples [begin, end) are in shadow over [z_in, 8).
TileEvents Shadowed(int begin, int end, float z_in) {
  TileEvents out{.tile_index = 0, .x0 = 0, .y0 = 0, .width = 1, .height = 1};
  if (end > begin) out.events = {{z_in, end - begin}, {8.0f, begin - end}};
  out.offsets = {0, out.events.size()};
  return out;
}

PdsmHeader Header(int samples, double tolerance = 0, int min_samples = 0) {
  PdsmHeader h;
  h.samples = samples;
  h.geometry.z_near = 1;
  h.geometry.z_far = 10;
  h.adaptive_tolerance = tolerance;
  h.adaptive_min_samples = min_samples;
  return h;
}

TEST(JudgeStage, FixedCountStageIsTheTileInSampleOrder) {
  std::vector<StageBatch> batches;
  batches.push_back({4, Shadowed(4, 8, 3)});
  batches.push_back({0, Shadowed(0, 4, 2)});
  const StageVerdict v = JudgeStage(Header(8), {}, std::move(batches));
  ASSERT_TRUE(v.done);
  EXPECT_EQ(v.tile_samples, 0);
  EXPECT_EQ(v.samples_skipped, 0);
  ASSERT_EQ(v.events.size(), 2u);
  EXPECT_EQ(v.events[0].events.front().z, 2.0f);  // samples [0, 4) first
}

TEST(JudgeStage, AdaptivePilotThatAgreesIsDone) {
  std::vector<StageBatch> batches;
  batches.push_back({2, Shadowed(2, 4, 2)});
  batches.push_back({0, Shadowed(0, 2, 2)});
  const StageVerdict v = JudgeStage(Header(64, 0.01, 4), {}, std::move(batches));
  ASSERT_TRUE(v.done);
  EXPECT_EQ(v.tile_samples, 4);
  EXPECT_EQ(v.samples_skipped, 60);
  ASSERT_EQ(v.events.size(), 1u);  // one merged list of every sample so far
  EXPECT_EQ(v.events[0].events.front(), (Event{2.0f, 4}));
}

TEST(JudgeStage, AdaptivePilotThatDisagreesGoesOnWithItsEventsKept) {
  std::vector<StageBatch> batches;
  batches.push_back({0, Shadowed(0, 2, 2)});
  batches.push_back({2, Shadowed(2, 4, 5)});  // the second half sees another shadow
  const StageVerdict v = JudgeStage(Header(64, 0.01, 4), {}, std::move(batches));
  ASSERT_FALSE(v.done);
  EXPECT_EQ(v.next.stage, 1);
  ASSERT_EQ(v.next.earlier.size(), 1u);
  EXPECT_EQ(v.next.earlier[0].events.size(), 3u);  // 2 (+2), 5 (+2), 8 (-4)

  // Stage 1 is [4, 8); cut into two batches, which changes nothing.
  const std::vector<SampleRange> ranges = AdaptiveStageRanges(1, 4, 64);
  ASSERT_EQ(ranges.size(), 1u);
  EXPECT_EQ(ranges[0].begin, 4);
  EXPECT_EQ(ranges[0].end, 8);
  std::vector<StageBatch> stage1;
  stage1.push_back({6, Shadowed(6, 8, 2)});
  stage1.push_back({4, Shadowed(4, 6, 5)});
  const StageVerdict w = JudgeStage(Header(64, 0.01, 4), v.next, std::move(stage1));
  EXPECT_TRUE(w.done);  // the same mix as the first four: A_8 = A_4
  EXPECT_EQ(w.tile_samples, 8);
}

TEST(JudgeStage, LastAdaptiveStageIsDoneWhateverTheEstimate) {
  std::vector<StageBatch> batches;
  batches.push_back({0, Shadowed(0, 1, 2)});
  batches.push_back({1, Shadowed(1, 2, 6)});
  const StageVerdict v = JudgeStage(Header(2, 1e-9, 2), {}, std::move(batches));
  EXPECT_TRUE(v.done);
  EXPECT_EQ(v.tile_samples, 2);
  EXPECT_EQ(v.samples_skipped, 0);
}

}  // namespace
}  // namespace pdsm
