#include "core/events/event.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <span>
#include <vector>

namespace pdsm {
namespace {

// Depths from a small set, so that equal depths (ties) are common.
std::vector<Event> RandomEvents(std::mt19937_64& rng, int max_count) {
  static constexpr float kDepths[] = {0.5f, 1.0f, 1.25f, 2.0f, 3.5f, 3.5000002f, 10.0f};
  std::uniform_int_distribution<int> size_dist(0, max_count);
  std::uniform_int_distribution<int> depth_dist(0, std::size(kDepths) - 1);
  std::bernoulli_distribution sign(0.5);
  std::vector<Event> events(size_dist(rng));
  for (Event& e : events) e = Event{kDepths[depth_dist(rng)], sign(rng) ? 1 : -1};
  return events;
}

bool IsNormalized(const std::vector<Event>& events) {
  for (size_t i = 0; i < events.size(); ++i) {
    if (events[i].count == 0) return false;
    if (i > 0 && !(events[i - 1].z < events[i].z)) return false;
  }
  return true;
}

TEST(NormalizeEventsTest, SortsSumsAndDropsZeros) {
  std::vector<Event> events = {{3.0f, 1},  {1.0f, 1},  {2.0f, 1}, {1.0f, 2},
                               {2.0f, -1}, {5.0f, -1}, {3.0f, -4}};
  NormalizeEvents(&events, EventKeying::kCounts);
  const std::vector<Event> expected = {{1.0f, 3}, {3.0f, -3}, {5.0f, -1}};
  EXPECT_EQ(events, expected);
}

TEST(NormalizeEventsTest, EmptyAndAllCancelling) {
  std::vector<Event> events;
  NormalizeEvents(&events, EventKeying::kCounts);
  EXPECT_TRUE(events.empty());
  events = {{1.0f, 1}, {1.0f, -1}, {2.0f, 2}, {2.0f, -1}, {2.0f, -1}};
  NormalizeEvents(&events, EventKeying::kCounts);
  EXPECT_TRUE(events.empty());
}

TEST(NormalizeEventsTest, NearbyDistinctDepthsStayApart) {
  std::vector<Event> events = {{1.0f, 1}, {std::nextafter(1.0f, 2.0f), 1}};
  NormalizeEvents(&events, EventKeying::kCounts);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].count, 1);
  EXPECT_EQ(events[1].count, 1);
}

TEST(NormalizeEventsTest, RandomListsMatchCountPerDepth) {
  std::mt19937_64 rng(1234);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<Event> events = RandomEvents(rng, 30);
    std::vector<Event> normalized = events;
    NormalizeEvents(&normalized, EventKeying::kCounts);
    ASSERT_TRUE(IsNormalized(normalized));
    // Every depth's total is preserved (zero totals are absent).
    for (const Event& e : events) {
      int total = 0;
      for (const Event& f : events) total += f.z == e.z ? f.count : 0;
      const auto it = std::find_if(normalized.begin(), normalized.end(),
                                   [&](const Event& n) { return n.z == e.z; });
      if (total == 0) {
        EXPECT_EQ(it, normalized.end());
      } else {
        ASSERT_NE(it, normalized.end());
        EXPECT_EQ(it->count, total);
      }
    }
  }
}

std::vector<Event> MergeAll(const std::vector<std::vector<Event>>& lists) {
  std::vector<std::span<const Event>> spans(lists.begin(), lists.end());
  return MergeEventLists(spans, EventKeying::kCounts);
}

TEST(MergeEventListsTest, OrderIndependentAndEqualToNormalizedConcatenation) {
  std::mt19937_64 rng(42);
  std::uniform_int_distribution<int> list_count(0, 8);
  for (int trial = 0; trial < 500; ++trial) {
    std::vector<std::vector<Event>> lists(list_count(rng));
    std::vector<Event> concatenation;
    for (auto& list : lists) {
      list = RandomEvents(rng, 12);
      concatenation.insert(concatenation.end(), list.begin(), list.end());
      NormalizeEvents(&list, EventKeying::kCounts);  // the inputs are normalized lists
    }
    NormalizeEvents(&concatenation, EventKeying::kCounts);
    const std::vector<Event> reference = MergeAll(lists);
    ASSERT_TRUE(IsNormalized(reference));
    ASSERT_EQ(reference, concatenation) << "trial " << trial;
    for (int permutation = 0; permutation < 20; ++permutation) {
      std::shuffle(lists.begin(), lists.end(), rng);
      ASSERT_EQ(MergeAll(lists), reference) << "trial " << trial;
    }
  }
}

TEST(MergeEventListsTest, NoListsGivesEmpty) {
  EXPECT_TRUE(MergeEventLists({}, EventKeying::kCounts).empty());
}

TileEvents RandomTileEvents(std::mt19937_64& rng, int width, int height) {
  TileEvents tile;
  tile.tile_index = 7;
  tile.x0 = 32;
  tile.y0 = 16;
  tile.width = width;
  tile.height = height;
  tile.offsets.push_back(0);
  for (size_t p = 0; p < tile.PixelCount(); ++p) {
    std::vector<Event> pixel = RandomEvents(rng, 6);
    NormalizeEvents(&pixel, EventKeying::kCounts);
    tile.events.insert(tile.events.end(), pixel.begin(), pixel.end());
    tile.offsets.push_back(tile.events.size());
  }
  return tile;
}

TEST(MergeTileEventsTest, OrderIndependentAndPerPixelMerge) {
  std::mt19937_64 rng(777);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<TileEvents> parts;
    const int part_count = 1 + trial % 6;
    for (int k = 0; k < part_count; ++k) parts.push_back(RandomTileEvents(rng, 5, 3));
    const TileEvents reference = MergeTileEvents(parts, EventKeying::kCounts);
    EXPECT_EQ(reference.tile_index, 7);
    EXPECT_EQ(reference.x0, 32);
    EXPECT_EQ(reference.y0, 16);
    EXPECT_EQ(reference.width, 5);
    EXPECT_EQ(reference.height, 3);
    ASSERT_EQ(reference.offsets.size(), 16u);
    EXPECT_EQ(reference.offsets.front(), 0u);
    EXPECT_EQ(reference.offsets.back(), reference.events.size());
    for (size_t p = 0; p < reference.PixelCount(); ++p) {
      std::vector<Event> expected;
      for (const TileEvents& part : parts) {
        expected.insert(expected.end(), part.Pixel(p).begin(), part.Pixel(p).end());
      }
      NormalizeEvents(&expected, EventKeying::kCounts);
      const auto merged = reference.Pixel(p);
      ASSERT_EQ(std::vector<Event>(merged.begin(), merged.end()), expected)
          << "trial " << trial << " pixel " << p;
    }
    for (int permutation = 0; permutation < 10; ++permutation) {
      std::shuffle(parts.begin(), parts.end(), rng);
      const TileEvents merged = MergeTileEvents(parts, EventKeying::kCounts);
      ASSERT_EQ(merged.offsets, reference.offsets);
      ASSERT_EQ(merged.events, reference.events);
    }
  }
}

TEST(MergeTileEventsTest, NoPartsGivesEmptyTile) {
  const TileEvents merged = MergeTileEvents({}, EventKeying::kCounts);
  EXPECT_EQ(merged.PixelCount(), 0u);
  EXPECT_TRUE(merged.events.empty());
}

// Sample-keyed events (emitter-weighted bakes): per sample, entries and exits alternate along
// the ray. RandomSampleLists gives each of `samples` samples such a list, then deals the
// samples out to `lists` batches (a sample's events all in one batch, as a bake's are).
std::vector<std::vector<Event>> RandomSampleLists(std::mt19937_64& rng, int samples, int lists) {
  static constexpr float kDepths[] = {0.5f, 1.0f, 1.25f, 2.0f, 3.5f, 10.0f};
  std::uniform_int_distribution<int> depth(0, std::size(kDepths) - 1);
  std::uniform_int_distribution<int> batch(0, lists - 1);
  std::uniform_int_distribution<int> changes(0, 4);
  std::vector<std::vector<Event>> out(lists);
  for (int k = 0; k < samples; ++k) {
    std::vector<float> z(changes(rng));
    for (float& d : z) d = kDepths[depth(rng)];
    std::sort(z.begin(), z.end());
    std::vector<Event>& list = out[batch(rng)];
    for (size_t i = 0; i < z.size(); ++i) {
      const int32_t key = SampleEventKey(k);
      list.push_back(Event{z[i], i % 2 == 0 ? key : -key});
    }
  }
  for (auto& list : out) NormalizeEvents(&list, EventKeying::kSampleKeys);
  return out;
}

// Which samples are hidden just after depth z (right-continuous), by replaying a list.
std::vector<int> HiddenAfter(const std::vector<Event>& events, float z, int samples) {
  std::vector<int> hidden(samples, 0);
  for (const Event& e : events) {
    if (e.z <= z) hidden[SampleOfEvent(e)] += ShadowChange(e, EventKeying::kSampleKeys);
  }
  return hidden;
}

TEST(SampleKeyedEventsTest, NormalizeSortsByDepthAndKeyAndCancelsOnlyTheSameSample) {
  std::vector<Event> events = {{2.0f, 3}, {1.0f, -2}, {1.0f, 5}, {2.0f, -3}, {1.0f, 2}, {3.0f, -5}};
  NormalizeEvents(&events, EventKeying::kSampleKeys);
  // At 1: sample 1 leaves and enters (cancels), sample 4 enters; at 2: sample 2 leaves and
  // enters (cancels), where a count would also have cancelled different samples' changes.
  const std::vector<Event> expected = {{1.0f, 5}, {3.0f, -5}};
  EXPECT_EQ(events, expected);
  std::vector<Event> two_samples = {{1.0f, 3}, {1.0f, -2}};  // a count would sum these to +1
  NormalizeEvents(&two_samples, EventKeying::kSampleKeys);
  const std::vector<Event> kept = {{1.0f, -2}, {1.0f, 3}};
  EXPECT_EQ(two_samples, kept);
}

TEST(SampleKeyedEventsTest, MergeIsOrderIndependentAndKeepsEverySamplesState) {
  std::mt19937_64 rng(77);
  for (int trial = 0; trial < 300; ++trial) {
    const int samples = 1 + trial % 40;
    std::vector<std::vector<Event>> lists = RandomSampleLists(rng, samples, 1 + trial % 5);
    std::vector<Event> all;
    for (const auto& list : lists) all.insert(all.end(), list.begin(), list.end());
    std::vector<std::span<const Event>> spans(lists.begin(), lists.end());
    const std::vector<Event> merged = MergeEventLists(spans, EventKeying::kSampleKeys);
    EXPECT_TRUE(std::is_sorted(merged.begin(), merged.end(), KeyedBefore));
    for (int permutation = 0; permutation < 5; ++permutation) {
      std::shuffle(spans.begin(), spans.end(), rng);
      ASSERT_EQ(MergeEventLists(spans, EventKeying::kSampleKeys), merged) << "trial " << trial;
    }
    for (float z : {0.75f, 1.0f, 1.5f, 2.0f, 3.5f, 20.0f}) {
      EXPECT_EQ(HiddenAfter(merged, z, samples), HiddenAfter(all, z, samples)) << z;
    }
    // Tile merges of the same lists agree.
    std::vector<TileEvents> parts;
    for (const auto& list : lists) {
      parts.push_back(
          TileEvents{.width = 1, .height = 1, .offsets = {0, list.size()}, .events = list});
    }
    EXPECT_EQ(MergeTileEvents(parts, EventKeying::kSampleKeys).events, merged);
  }
}

}  // namespace
}  // namespace pdsm
