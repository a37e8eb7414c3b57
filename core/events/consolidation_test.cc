#include "core/events/consolidation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/pdsm/attenuation_function.h"

namespace pdsm {
namespace {

// A depth `fraction` of the consolidation tolerance beyond z.
float Beyond(float z, double fraction) {
  return static_cast<float>(z + fraction * kConsolidationRelativeDepth * std::abs(z));
}

TEST(ConsolidateEventsTest, EventsWithinToleranceMergeAtFirstDepth) {
  const float z = 100.0f;
  const float near = Beyond(z, 0.5);
  ASSERT_GT(near, z);
  const std::vector<Event> events = {{z, 1}, {near, 2}, {200.0f, -1}};
  const std::vector<Event> expected = {{z, 3}, {200.0f, -1}};
  EXPECT_EQ(ConsolidateEvents(events, EventKeying::kCounts), expected);
}

TEST(ConsolidateEventsTest, EventsBeyondToleranceStayApart) {
  const float z = 100.0f;
  const float far = Beyond(z, 1.5);
  const std::vector<Event> events = {{z, 1}, {far, 2}};
  EXPECT_EQ(ConsolidateEvents(events, EventKeying::kCounts), events);
}

TEST(ConsolidateEventsTest, ToleranceScalesWithDepth) {
  // At depth 1 the same absolute gap as above is far beyond the tolerance.
  const float gap = static_cast<float>(0.5 * kConsolidationRelativeDepth * 100.0);
  const std::vector<Event> events = {{1.0f, 1}, {1.0f + gap, 1}};
  EXPECT_EQ(ConsolidateEvents(events, EventKeying::kCounts), events);
}

TEST(ConsolidateEventsTest, GroupsAreMeasuredFromTheirFirstEvent) {
  // A chain of events each close to the previous: the group ends where the distance from the
  // group's first depth exceeds the tolerance, not the distance from the previous event.
  const float z0 = 50.0f;
  const float z1 = Beyond(z0, 0.6);
  const float z2 = Beyond(z0, 1.2);
  const float z3 = Beyond(z0, 1.7);
  ASSERT_LT(z0, z1);
  ASSERT_LT(z1, z2);
  ASSERT_LT(z2, z3);
  ASSERT_LE(z3 - z2, kConsolidationRelativeDepth * z2);  // z3 within tolerance of z2
  const std::vector<Event> events = {{z0, 1}, {z1, 1}, {z2, 1}, {z3, 1}};
  const std::vector<Event> expected = {{z0, 2}, {z2, 2}};
  EXPECT_EQ(ConsolidateEvents(events, EventKeying::kCounts), expected);
}

TEST(ConsolidateEventsTest, CancellingPairsWithinToleranceVanish) {
  const float z = 7.0f;
  const std::vector<Event> events = {{1.0f, 1}, {z, 1}, {Beyond(z, 0.9), -1}, {9.0f, -1}};
  const std::vector<Event> expected = {{1.0f, 1}, {9.0f, -1}};
  EXPECT_EQ(ConsolidateEvents(events, EventKeying::kCounts), expected);
}

TEST(ConsolidateEventsTest, EmptyStaysEmpty) {
  EXPECT_TRUE(ConsolidateEvents({}, EventKeying::kCounts).empty());
}

TEST(ConsolidateEventsTest, RandomListsKeepTotalsAndSpacing) {
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> gap(0.0, 3.0);  // in units of the tolerance
  std::bernoulli_distribution sign(0.5);
  for (int trial = 0; trial < 1000; ++trial) {
    std::vector<Event> events;
    float z = static_cast<float>(1.0 + 10.0 * std::generate_canonical<double, 53>(rng));
    int64_t total = 0;
    for (int k = 0; k < 40; ++k) {
      const float next = Beyond(z, gap(rng));
      if (!events.empty() && next <= events.back().z) continue;
      z = next;
      events.push_back({z, sign(rng) ? 1 : -1});
      total += events.back().count;
    }
    const std::vector<Event> out = ConsolidateEvents(events, EventKeying::kCounts);
    int64_t out_total = 0;
    for (size_t i = 0; i < out.size(); ++i) {
      out_total += out[i].count;
      ASSERT_NE(out[i].count, 0);
      // Output depths are input depths; consecutive ones are more than a tolerance apart.
      ASSERT_TRUE(std::any_of(events.begin(), events.end(),
                              [&](const Event& e) { return e.z == out[i].z; }));
      if (i > 0) {
        ASSERT_GT(static_cast<double>(out[i].z),
                  out[i - 1].z + kConsolidationRelativeDepth * std::abs(out[i - 1].z));
      }
    }
    ASSERT_EQ(out_total, total);
  }
}

TEST(FunctionFromEventsTest, TwoVerticesPerEventWithCumulativeValues) {
  const std::vector<Event> events = {{1.0f, 2}, {2.0f, 1}, {3.0f, -3}, {4.0f, 1}};
  const std::vector<Vertex> f = FunctionFromEvents(events, 4);
  const std::vector<Vertex> expected = {{1.0f, 0.0f},  {1.0f, 0.5f}, {2.0f, 0.5f}, {2.0f, 0.75f},
                                        {3.0f, 0.75f}, {3.0f, 0.0f}, {4.0f, 0.0f}, {4.0f, 0.25f}};
  EXPECT_EQ(f, expected);
  EXPECT_TRUE(FunctionFromEvents({}, 4).empty());
}

// Random consolidated event lists with counts +-1 and the cumulative count kept in [0, N].
std::vector<Event> RandomEventList(std::mt19937_64& rng, int total_samples, int max_events) {
  std::uniform_int_distribution<int> size_dist(0, max_events);
  std::uniform_real_distribution<double> step(0.001, 2.0);
  std::bernoulli_distribution sign(0.5);
  const int size = size_dist(rng);
  std::vector<Event> events;
  double z = 0.5;
  int hidden = 0;
  for (int k = 0; k < size; ++k) {
    z += step(rng);
    int count = sign(rng) ? 1 : -1;
    if (hidden + count < 0 || hidden + count > total_samples) count = -count;
    hidden += count;
    events.push_back({static_cast<float>(z), count});
  }
  return ConsolidateEvents(events, EventKeying::kCounts);
}

float CountFraction(const std::vector<Event>& events, double z, int n) {
  int64_t sum = 0;
  for (const Event& e : events) {
    if (e.z <= z) sum += e.count;
  }
  return static_cast<float>(static_cast<double>(sum) / n);
}

TEST(FunctionFromEventsTest, EvaluatesToCountFractionEverywhere) {
  std::mt19937_64 rng(99);
  std::uniform_int_distribution<int> samples_dist(1, 256);
  for (int trial = 0; trial < 2000; ++trial) {
    const int n = samples_dist(rng);
    const std::vector<Event> events = RandomEventList(rng, n, 40);
    const std::vector<Vertex> f = FunctionFromEvents(events, n);
    ASSERT_EQ(f.size(), 2 * events.size());
    int64_t hidden = 0;
    for (size_t k = 0; k < events.size(); ++k) {
      ASSERT_EQ(f[2 * k].z, events[k].z);
      ASSERT_EQ(f[2 * k + 1].z, events[k].z);
      ASSERT_EQ(f[2 * k].a, static_cast<float>(static_cast<double>(hidden) / n));
      hidden += events[k].count;
      ASSERT_EQ(f[2 * k + 1].a, static_cast<float>(static_cast<double>(hidden) / n));
    }
    // At each event depth (right-continuous), just before it, between events and beyond.
    std::vector<double> probes = {0.0, 1e9};
    for (size_t k = 0; k < events.size(); ++k) {
      const double z = events[k].z;
      probes.push_back(z);
      probes.push_back(std::nextafter(z, -1e30));
      probes.push_back(std::nextafter(z, 1e30));
      if (k + 1 < events.size()) probes.push_back(0.5 * (z + events[k + 1].z));
    }
    for (double z : probes) {
      ASSERT_EQ(EvaluateAttenuation(f, z), CountFraction(events, z, n))
          << "trial " << trial << " z " << z;
    }
  }
}

TEST(ConsolidateEventsTest, SampleKeyedRunsKeepEachSamplesNetChange) {
  const float z = 7.0f;
  // Within one run: sample 0 enters and leaves (nothing), sample 1 leaves, sample 2 enters,
  // leaves and enters again (enters), sample 3 enters; all at the run's first depth, by key.
  const std::vector<Event> events = {{z, 1},
                                     {z, 3},
                                     {Beyond(z, 0.2), -2},
                                     {Beyond(z, 0.3), -1},
                                     {Beyond(z, 0.4), -3},
                                     {Beyond(z, 0.5), 4},
                                     {Beyond(z, 0.6), 3},
                                     {9.0f, -4}};
  const std::vector<Event> expected = {{z, -2}, {z, 3}, {z, 4}, {9.0f, -4}};
  EXPECT_EQ(ConsolidateEvents(events, EventKeying::kSampleKeys), expected);
}

}  // namespace
}  // namespace pdsm
