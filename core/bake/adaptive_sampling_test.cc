#include "core/bake/adaptive_sampling.h"

#include <gtest/gtest.h>

#include <vector>

namespace pdsm {
namespace {

// The stages cover [0, max) exactly once, in order, each after the pilot doubling the count.
TEST(AdaptiveStageRangesTest, StagesTileTheSamplesAndDouble) {
  for (auto [min_samples, max_samples] :
       {std::pair{16, 256}, std::pair{16, 100}, std::pair{1, 1}, std::pair{1, 7}, std::pair{5, 5},
        std::pair{7, 65536}, std::pair{64, 64}}) {
    int next = 0;
    int stage = 0;
    for (;; ++stage) {
      const std::vector<SampleRange> ranges = AdaptiveStageRanges(stage, min_samples, max_samples);
      if (ranges.empty()) break;
      ASSERT_LE(ranges.size(), stage == 0 ? 2u : 1u);
      for (const SampleRange& r : ranges) {
        ASSERT_EQ(r.begin, next) << min_samples << "/" << max_samples << " stage " << stage;
        ASSERT_LT(r.begin, r.end);
        next = r.end;
      }
      // After the pilot, a stage adds as many samples as all before it (or up to the max).
      if (stage > 0) {
        EXPECT_TRUE(ranges[0].end - ranges[0].begin == ranges[0].begin ||
                    ranges[0].end == max_samples);
      }
    }
    EXPECT_EQ(next, max_samples) << min_samples << "/" << max_samples;
    const std::vector<SampleRange> pilot = AdaptiveStageRanges(0, min_samples, max_samples);
    EXPECT_EQ(pilot.back().end, std::min(max_samples, 2 * ((min_samples + 1) / 2)));
  }
}

std::vector<Event> Events(std::initializer_list<Event> e) { return e; }

TEST(SplitHalfErrorTest, AgreeingHalvesGiveZero) {
  const auto a = Events({{5.0f, 4}, {8.0f, -4}});
  EXPECT_EQ(SplitHalfPixelError(a, 8, a, 8, 0.0, EventKeying::kCounts), 0.0);
  EXPECT_EQ(SplitHalfPixelError({}, 8, {}, 8, 0.0, EventKeying::kCounts), 0.0);
}

TEST(SplitHalfErrorTest, DisagreementIsWeightedDifference) {
  // First half: 2 of 8 in shadow after z = 5; second: 6 of 8. A_16 = 8/16, A_8 = 2/8:
  // |A_16 - A_8| = 0.25 = (8 / 16) * |6/8 - 2/8|.
  const auto first = Events({{5.0f, 2}});
  const auto second = Events({{5.0f, 6}});
  EXPECT_DOUBLE_EQ(SplitHalfPixelError(first, 8, second, 8, 0.0, EventKeying::kCounts), 0.25);
  // Unequal halves: n1 = 8, n2 = 24, both 50% in shadow -> no difference.
  EXPECT_DOUBLE_EQ(SplitHalfPixelError(Events({{5.0f, 4}}), 8, Events({{5.0f, 12}}), 24, 0.0,
                                       EventKeying::kCounts),
                   0.0);
}

// Events of the two halves at slightly different depths (one surface seen through different
// shadow-map texels) disagree only inside the surface's thickness: skipped.
TEST(SplitHalfErrorTest, SurfaceThicknessIsSkipped) {
  const auto first = Events({{5.000f, 8}});
  const auto second = Events({{5.001f, 8}});
  EXPECT_DOUBLE_EQ(SplitHalfPixelError(first, 8, second, 8, 0.0, EventKeying::kCounts), 0.5);
  EXPECT_EQ(SplitHalfPixelError(first, 8, second, 8, 0.01, EventKeying::kCounts), 0.0);
  // A long disagreement still counts.
  const auto late = Events({{6.0f, 8}});
  EXPECT_DOUBLE_EQ(SplitHalfPixelError(first, 8, late, 8, 0.01, EventKeying::kCounts), 0.5);
}

TEST(SplitHalfErrorTest, TileErrorIsTheWorstPixel) {
  TileEvents a, b;
  a.width = b.width = 2;
  a.height = b.height = 1;
  a.events = {{5.0f, 4}};
  a.offsets = {0, 0, 1};
  b.events = {{5.0f, 4}, {5.0f, 1}};
  b.offsets = {0, 1, 2};
  // Pixel 0: 0 vs 4/8 -> 0.25; pixel 1: 4/8 vs 1/8 -> 0.1875.
  EXPECT_DOUBLE_EQ(SplitHalfError(a, 8, b, 8, 0.0, EventKeying::kCounts), 0.25);
}

// One pixel whose `count` samples are all hidden from depth 5 on.
TileEvents OnePixel(int count) {
  TileEvents t;
  t.width = t.height = 1;
  if (count != 0) t.events = {{5.0f, count}};
  t.offsets = {0, t.events.size()};
  return t;
}

PdsmHeader AdaptiveHeader(int max_samples, double tolerance) {
  PdsmHeader h;
  h.samples = max_samples;
  h.adaptive_tolerance = tolerance;
  h.geometry.z_near = 1;
  h.geometry.z_far = 10;
  return h;
}

// The decision the local bake and the service share: agreeing pilot halves stop the tile,
// disagreeing ones do not, reaching the maximum always does; `earlier` ends as one merged list
// of every sample so far.
TEST(JudgeAdaptiveStageTest, StopsOnAgreementOrAtTheMaximum) {
  const PdsmHeader h = AdaptiveHeader(64, 0.05);
  const std::vector<SampleRange> pilot = AdaptiveStageRanges(0, 16, 64);  // [0,8), [8,16)
  ASSERT_EQ(pilot.size(), 2u);

  std::vector<TileEvents> earlier;
  std::vector<TileEvents> agree;
  agree.push_back(OnePixel(4));
  agree.push_back(OnePixel(4));
  EXPECT_TRUE(JudgeAdaptiveStage(h, pilot, std::move(agree), &earlier));
  ASSERT_EQ(earlier.size(), 1u);
  EXPECT_EQ(earlier[0].events.size(), 1u);
  EXPECT_EQ(earlier[0].events[0].count, 8);

  earlier.clear();
  std::vector<TileEvents> differ;
  differ.push_back(OnePixel(0));
  differ.push_back(OnePixel(8));  // 0 of 8 vs 8 of 8: estimate 0.5
  EXPECT_FALSE(JudgeAdaptiveStage(h, pilot, std::move(differ), &earlier));
  ASSERT_EQ(earlier.size(), 1u);
  EXPECT_EQ(earlier[0].events[0].count, 8);

  // The last stage ends at the maximum: done whatever the halves say.
  const std::vector<SampleRange> last = {{32, 64}};
  std::vector<TileEvents> final_range;
  final_range.push_back(OnePixel(0));
  EXPECT_TRUE(JudgeAdaptiveStage(h, last, std::move(final_range), &earlier));
  ASSERT_EQ(earlier.size(), 1u);
  EXPECT_EQ(earlier[0].events[0].count, 8);
}

}  // namespace
}  // namespace pdsm
