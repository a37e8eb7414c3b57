// Merging event lists is exact and order independent; consolidation folds near events.
#include <algorithm>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/events/consolidation.h"
#include "core/events/event.h"

namespace pdsm {
namespace {

std::vector<Event> RandomNormalizedList(std::mt19937_64& rng) {
  std::uniform_int_distribution<int> depth(0, 40), count(0, 30);
  std::vector<Event> list;
  for (int k = count(rng); k > 0; --k) {
    list.push_back(Event{1.0f + 0.25f * depth(rng), (rng() & 1) ? 1 : -1});
  }
  NormalizeEvents(&list);
  return list;
}

TEST(Merge, OrderIndependentAndEqualToNormalizedConcatenation) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<std::vector<Event>> lists(1 + trial % 7);
    std::vector<Event> all;
    for (auto& list : lists) {
      list = RandomNormalizedList(rng);
      all.insert(all.end(), list.begin(), list.end());
    }
    NormalizeEvents(&all);
    for (int shuffle = 0; shuffle < 5; ++shuffle) {
      std::shuffle(lists.begin(), lists.end(), rng);
      std::vector<std::span<const Event>> spans(lists.begin(), lists.end());
      ASSERT_EQ(MergeEventLists(spans), all);
    }
  }
}

TEST(Merge, NormalizeSumsTiesAndDropsZeros) {
  std::vector<Event> e = {{2.0f, 1}, {1.0f, 1}, {2.0f, -1}, {1.0f, 1}, {3.0f, -1}};
  NormalizeEvents(&e);
  EXPECT_EQ(e, (std::vector<Event>{{1.0f, 2}, {3.0f, -1}}));
}

TEST(Consolidation, FoldsEventsWithinTheDepthResolution) {
  const float z = 10.0f;
  const float near = static_cast<float>(z * (1 + 0.5 * kConsolidationRelativeDepth));
  const float far = static_cast<float>(z * (1 + 4 * kConsolidationRelativeDepth));
  const std::vector<Event> in = {{z, 1}, {near, 1}, {far, -1}};
  EXPECT_EQ(ConsolidateEvents(in), (std::vector<Event>{{z, 2}, {far, -1}}));
  const std::vector<Event> cancel = {{z, 1}, {near, -1}};
  EXPECT_TRUE(ConsolidateEvents(cancel).empty());
}

TEST(Consolidation, FunctionIsCumulativeCountOverSamples) {
  const std::vector<Event> events = {{1.0f, 2}, {2.0f, 1}, {3.0f, -3}};
  const std::vector<Vertex> f = FunctionFromEvents(events, 4);
  EXPECT_EQ(EvaluateAttenuation(f, 0.5), 0.0f);
  EXPECT_EQ(EvaluateAttenuation(f, 1.0), 0.5f);   // right-continuous: counts at depth <= z
  EXPECT_EQ(EvaluateAttenuation(f, 2.5), 0.75f);
  EXPECT_EQ(EvaluateAttenuation(f, 3.0), 0.0f);
}

}  // namespace
}  // namespace pdsm
