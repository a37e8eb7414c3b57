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

TEST(StageAccumulator, MergesBatchesOfARangeWhateverTheirOrder) {
  StageAccumulator a(Header(8), 0), b(Header(8), 0);
  a.Add(4, Shadowed(4, 8, 3));
  a.Add(0, Shadowed(0, 4, 2));
  b.Add(0, Shadowed(0, 2, 2));
  b.Add(6, Shadowed(6, 8, 3));
  b.Add(2, Shadowed(2, 4, 2));
  b.Add(4, Shadowed(4, 6, 3));
  const std::vector<TileEvents> ra = a.TakeRanges(), rb = b.TakeRanges();
  ASSERT_EQ(ra.size(), 1u);
  ASSERT_EQ(rb.size(), 1u);
  EXPECT_EQ(ra[0].events, rb[0].events);
  EXPECT_EQ(ra[0].events, (std::vector<Event>{{2.0f, 4}, {3.0f, 4}, {8.0f, -8}}));
}

TEST(StageAccumulator, AdaptivePilotKeepsItsTwoHalvesApart) {
  StageAccumulator acc(Header(64, 0.01, 4), 0);  // ranges [0, 2) and [2, 4)
  acc.Add(2, Shadowed(2, 4, 5));
  acc.Add(0, Shadowed(0, 2, 2));
  const std::vector<TileEvents> ranges = acc.TakeRanges();
  ASSERT_EQ(ranges.size(), 2u);
  EXPECT_EQ(ranges[0].events.front(), (Event{2.0f, 2}));
  EXPECT_EQ(ranges[1].events.front(), (Event{5.0f, 2}));
}

TEST(JudgeStage, FixedCountStageIsTheTile) {
  StageAccumulator acc(Header(8), 0);
  acc.Add(4, Shadowed(4, 8, 3));
  acc.Add(0, Shadowed(0, 4, 2));
  const StageVerdict v = JudgeStage(Header(8), {}, acc.TakeRanges());
  ASSERT_TRUE(v.done);
  EXPECT_EQ(v.tile_samples, 0);
  EXPECT_EQ(v.samples_skipped, 0);
  ASSERT_EQ(v.events.size(), 1u);
  EXPECT_EQ(v.events[0].events.front(), (Event{2.0f, 4}));
}

TEST(JudgeStage, AdaptivePilotThatAgreesIsDone) {
  StageAccumulator acc(Header(64, 0.01, 4), 0);
  acc.Add(2, Shadowed(2, 4, 2));
  acc.Add(0, Shadowed(0, 2, 2));
  const StageVerdict v = JudgeStage(Header(64, 0.01, 4), {}, acc.TakeRanges());
  ASSERT_TRUE(v.done);
  EXPECT_EQ(v.tile_samples, 4);
  EXPECT_EQ(v.samples_skipped, 60);
  ASSERT_EQ(v.events.size(), 1u);  // one merged list of every sample so far
  EXPECT_EQ(v.events[0].events.front(), (Event{2.0f, 4}));
}

TEST(JudgeStage, AdaptivePilotThatDisagreesGoesOnWithItsEventsKept) {
  StageAccumulator pilot(Header(64, 0.01, 4), 0);
  pilot.Add(0, Shadowed(0, 2, 2));
  pilot.Add(2, Shadowed(2, 4, 5));  // the second half sees another shadow
  const StageVerdict v = JudgeStage(Header(64, 0.01, 4), {}, pilot.TakeRanges());
  ASSERT_FALSE(v.done);
  EXPECT_EQ(v.next.stage, 1);
  ASSERT_EQ(v.next.earlier.size(), 1u);
  EXPECT_EQ(v.next.earlier[0].events.size(), 3u);  // 2 (+2), 5 (+2), 8 (-4)

  // Stage 1 is [4, 8); cut into two batches, which changes nothing.
  const std::vector<SampleRange> ranges = StageRanges(Header(64, 0.01, 4), 1);
  ASSERT_EQ(ranges.size(), 1u);
  EXPECT_EQ(ranges[0].begin, 4);
  EXPECT_EQ(ranges[0].end, 8);
  StageAccumulator stage1(Header(64, 0.01, 4), 1);
  stage1.Add(6, Shadowed(6, 8, 2));
  stage1.Add(4, Shadowed(4, 6, 5));
  const StageVerdict w = JudgeStage(Header(64, 0.01, 4), v.next, stage1.TakeRanges());
  EXPECT_TRUE(w.done);  // the same mix as the first four: A_8 = A_4
  EXPECT_EQ(w.tile_samples, 8);
}

TEST(JudgeStage, LastAdaptiveStageIsDoneWhateverTheEstimate) {
  StageAccumulator acc(Header(2, 1e-9, 2), 0);
  acc.Add(0, Shadowed(0, 1, 2));
  acc.Add(1, Shadowed(1, 2, 6));
  const StageVerdict v = JudgeStage(Header(2, 1e-9, 2), {}, acc.TakeRanges());
  EXPECT_TRUE(v.done);
  EXPECT_EQ(v.tile_samples, 2);
  EXPECT_EQ(v.samples_skipped, 0);
}

}  // namespace
}  // namespace pdsm
