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
  NormalizeEvents(&events);
  const std::vector<Event> expected = {{1.0f, 3}, {3.0f, -3}, {5.0f, -1}};
  EXPECT_EQ(events, expected);
}

TEST(NormalizeEventsTest, EmptyAndAllCancelling) {
  std::vector<Event> events;
  NormalizeEvents(&events);
  EXPECT_TRUE(events.empty());
  events = {{1.0f, 1}, {1.0f, -1}, {2.0f, 2}, {2.0f, -1}, {2.0f, -1}};
  NormalizeEvents(&events);
  EXPECT_TRUE(events.empty());
}

TEST(NormalizeEventsTest, NearbyDistinctDepthsStayApart) {
  std::vector<Event> events = {{1.0f, 1}, {std::nextafter(1.0f, 2.0f), 1}};
  NormalizeEvents(&events);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].count, 1);
  EXPECT_EQ(events[1].count, 1);
}

TEST(NormalizeEventsTest, RandomListsMatchCountPerDepth) {
  std::mt19937_64 rng(1234);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<Event> events = RandomEvents(rng, 30);
    std::vector<Event> normalized = events;
    NormalizeEvents(&normalized);
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
  return MergeEventLists(spans);
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
      NormalizeEvents(&list);  // the inputs are normalized lists
    }
    NormalizeEvents(&concatenation);
    const std::vector<Event> reference = MergeAll(lists);
    ASSERT_TRUE(IsNormalized(reference));
    ASSERT_EQ(reference, concatenation) << "trial " << trial;
    for (int permutation = 0; permutation < 20; ++permutation) {
      std::shuffle(lists.begin(), lists.end(), rng);
      ASSERT_EQ(MergeAll(lists), reference) << "trial " << trial;
    }
  }
}

TEST(MergeEventListsTest, NoListsGivesEmpty) { EXPECT_TRUE(MergeEventLists({}).empty()); }

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
    NormalizeEvents(&pixel);
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
    const TileEvents reference = MergeTileEvents(parts);
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
      NormalizeEvents(&expected);
      const auto merged = reference.Pixel(p);
      ASSERT_EQ(std::vector<Event>(merged.begin(), merged.end()), expected)
          << "trial " << trial << " pixel " << p;
    }
    for (int permutation = 0; permutation < 10; ++permutation) {
      std::shuffle(parts.begin(), parts.end(), rng);
      const TileEvents merged = MergeTileEvents(parts);
      ASSERT_EQ(merged.offsets, reference.offsets);
      ASSERT_EQ(merged.events, reference.events);
    }
  }
}

TEST(MergeTileEventsTest, NoPartsGivesEmptyTile) {
  const TileEvents merged = MergeTileEvents({});
  EXPECT_EQ(merged.PixelCount(), 0u);
  EXPECT_TRUE(merged.events.empty());
}

}  // namespace
}  // namespace pdsm
