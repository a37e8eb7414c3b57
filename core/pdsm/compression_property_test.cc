// Property tests of the compression contract (core/pdsm/compression.h) over random functions
// built like real ones: random ±1 events from N samples turned into step functions.
#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "core/events/consolidation.h"
#include "core/pdsm/compression.h"

namespace pdsm {
namespace {

std::vector<Vertex> RandomStepFunction(std::mt19937_64& rng) {
  std::uniform_int_distribution<int> samples_dist(1, 256);
  const int samples = samples_dist(rng);
  std::uniform_int_distribution<int> count_dist(1, 400);
  const int count = count_dist(rng);
  std::uniform_real_distribution<double> dz(0.0, 0.05);
  std::vector<Event> events;
  double z = 1.0;
  int hidden = 0;
  for (int k = 0; k < count; ++k) {
    z += dz(rng) + 1e-4;
    int step = (rng() & 1) ? +1 : -1;
    if (hidden == 0) step = +1;
    if (hidden == samples) step = -1;
    hidden += step;
    events.push_back(Event{static_cast<float>(z), step});
  }
  return FunctionFromEvents(events, samples);
}

// Depths to check A at: every vertex depth, just before it, and midpoints.
std::vector<double> ProbeDepths(const std::vector<Vertex>& f) {
  std::vector<double> probes;
  for (size_t k = 0; k < f.size(); ++k) {
    probes.push_back(f[k].z);
    probes.push_back(std::nextafter(static_cast<double>(f[k].z), 0.0));
    if (k + 1 < f.size()) probes.push_back(0.5 * (static_cast<double>(f[k].z) + f[k + 1].z));
  }
  probes.push_back(f.empty() ? 0.0 : f.back().z + 1.0);
  return probes;
}

TEST(CompressionProperty, VerticalBoundHoldsEverywhere) {
  std::mt19937_64 rng(20261122);
  for (double epsilon : {1e-6, 1e-3, 0.01, 0.05, 0.3, 1.0}) {
    for (int trial = 0; trial < 300; ++trial) {
      const std::vector<Vertex> f = RandomStepFunction(rng);
      const std::vector<Vertex> c =
          CompressFunction(f, epsilon, CompressionMetric::kVertical, 1.0);
      ASSERT_LE(c.size(), f.size());
      std::set<float> depths;
      for (const Vertex& v : f) depths.insert(v.z);
      for (size_t k = 0; k < c.size(); ++k) {
        ASSERT_TRUE(depths.count(c[k].z)) << "compression moved a depth";
        if (k > 0) ASSERT_LE(c[k - 1].z, c[k].z);
      }
      for (double z : ProbeDepths(f)) {
        ASSERT_LE(std::abs(EvaluateAttenuation(c, z) - EvaluateAttenuation(f, z)), epsilon)
            << "epsilon " << epsilon << " trial " << trial << " z " << z;
      }
    }
  }
}

TEST(CompressionProperty, ZeroEpsilonIsLossless) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Vertex> f = RandomStepFunction(rng);
    f.push_back(f.back());  // an exact duplicate is the only thing ε = 0 may drop
    const std::vector<Vertex> c = CompressFunction(f, 0.0, CompressionMetric::kVertical, 1.0);
    ASSERT_EQ(c.size(), f.size() - 1);
    ASSERT_TRUE(std::equal(c.begin(), c.end(), f.begin()));
  }
}

TEST(CompressionProperty, PerpendicularVerticesNearTheirSegmentLine) {
  std::mt19937_64 rng(99);
  const double scale = 2.0;
  for (double epsilon : {1e-3, 0.02, 0.1}) {
    for (int trial = 0; trial < 200; ++trial) {
      const std::vector<Vertex> f = RandomStepFunction(rng);
      const std::vector<Vertex> c =
          CompressFunction(f, epsilon, CompressionMetric::kPerpendicular, scale);
      for (const Vertex& v : f) {
        // The output segment spanning v's depth (strictly increasing in depth).
        for (size_t k = 0; k + 1 < c.size(); ++k) {
          if (!(c[k].z < v.z && v.z < c[k + 1].z)) continue;
          const double z0 = c[k].z / scale, z1 = c[k + 1].z / scale;
          const double a0 = c[k].a, a1 = c[k + 1].a;
          const double dist = std::abs((a1 - a0) * (v.z / scale - z0) - (z1 - z0) * (v.a - a0)) /
                              std::hypot(z1 - z0, a1 - a0);
          ASSERT_LE(dist, epsilon + 1e-6) << "trial " << trial;
        }
      }
    }
  }
}

TEST(CompressionProperty, PenumbraRampCompresses) {
  // 256 samples entering shadow one by one over a depth interval: a ramp of small steps.
  std::vector<Event> events;
  for (int k = 0; k < 256; ++k) events.push_back(Event{1.0f + k * 0.01f, +1});
  const std::vector<Vertex> f = FunctionFromEvents(events, 256);
  const std::vector<Vertex> c = CompressFunction(f, 0.02, CompressionMetric::kVertical, 1.0);
  EXPECT_LT(c.size(), 16u);
  EXPECT_NEAR(EvaluateAttenuation(c, 10.0), 1.0, 0.02);
}

TEST(CompressionProperty, LargeJumpStaysAJump) {
  const std::vector<Vertex> f = {{1.0f, 0.0f}, {1.0f, 0.5f}, {2.0f, 0.5f}, {2.0f, 1.0f}};
  const std::vector<Vertex> c = CompressFunction(f, 0.1, CompressionMetric::kVertical, 1.0);
  EXPECT_FLOAT_EQ(EvaluateAttenuation(c, 1.0), 0.5f);
  EXPECT_FLOAT_EQ(EvaluateAttenuation(c, 2.0), 1.0f);
  EXPECT_NEAR(EvaluateAttenuation(c, std::nextafter(1.0, 0.0)), 0.0, 0.1);
}

}  // namespace
}  // namespace pdsm
