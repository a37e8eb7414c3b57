#include "core/pdsm/attenuation_function.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace pdsm {
namespace {

TEST(EvaluateAttenuationTest, EmptyFunctionIsLit) {
  const std::vector<Vertex> f;
  EXPECT_EQ(EvaluateAttenuation(f, -1.0), 0.0f);
  EXPECT_EQ(EvaluateAttenuation(f, 0.0), 0.0f);
  EXPECT_EQ(EvaluateAttenuation(f, 1e30), 0.0f);
}

TEST(EvaluateAttenuationTest, ZeroBeforeFirstVertex) {
  // The first vertex's value is not extended backwards: before it nothing is hidden.
  const std::vector<Vertex> f = {{2.0f, 0.5f}, {3.0f, 1.0f}};
  EXPECT_EQ(EvaluateAttenuation(f, 1.0), 0.0f);
  EXPECT_EQ(EvaluateAttenuation(f, std::nextafter(2.0, 0.0)), 0.0f);
  EXPECT_EQ(EvaluateAttenuation(f, -5.0), 0.0f);
  EXPECT_EQ(EvaluateAttenuation(f, 2.0), 0.5f);
}

TEST(EvaluateAttenuationTest, RightContinuousAtJumps) {
  const std::vector<Vertex> f = {{1.0f, 0.0f},  {1.0f, 0.25f}, {2.0f, 0.25f},
                                 {2.0f, 0.75f}, {3.0f, 0.75f}, {3.0f, 0.5f}};
  EXPECT_EQ(EvaluateAttenuation(f, 1.0), 0.25f);
  EXPECT_EQ(EvaluateAttenuation(f, 2.0), 0.75f);
  EXPECT_EQ(EvaluateAttenuation(f, 3.0), 0.5f);
  // Left limits: just before each jump, the value before it.
  EXPECT_EQ(EvaluateAttenuation(f, std::nextafter(1.0, 0.0)), 0.0f);
  EXPECT_EQ(EvaluateAttenuation(f, std::nextafter(2.0, 0.0)), 0.25f);
  EXPECT_EQ(EvaluateAttenuation(f, std::nextafter(3.0, 0.0)), 0.75f);
}

TEST(EvaluateAttenuationTest, ThreeVerticesAtOneDepthTakeTheLast) {
  const std::vector<Vertex> f = {{1.0f, 0.0f}, {1.0f, 0.9f}, {1.0f, 0.3f}, {2.0f, 0.3f}};
  EXPECT_EQ(EvaluateAttenuation(f, 1.0), 0.3f);
  EXPECT_EQ(EvaluateAttenuation(f, 1.5), 0.3f);
}

TEST(EvaluateAttenuationTest, LinearBetweenVertices) {
  const std::vector<Vertex> f = {{1.0f, 0.0f}, {3.0f, 1.0f}, {5.0f, 0.5f}};
  EXPECT_FLOAT_EQ(EvaluateAttenuation(f, 1.5), 0.25f);
  EXPECT_FLOAT_EQ(EvaluateAttenuation(f, 2.0), 0.5f);
  EXPECT_FLOAT_EQ(EvaluateAttenuation(f, 3.0), 1.0f);
  EXPECT_FLOAT_EQ(EvaluateAttenuation(f, 4.0), 0.75f);
  EXPECT_FLOAT_EQ(EvaluateAttenuation(f, 4.5), 0.625f);
}

TEST(EvaluateAttenuationTest, ConstantAfterLastVertex) {
  const std::vector<Vertex> f = {{1.0f, 0.0f}, {2.0f, 0.4f}};
  EXPECT_EQ(EvaluateAttenuation(f, 2.0), 0.4f);
  EXPECT_EQ(EvaluateAttenuation(f, 2.5), 0.4f);
  EXPECT_EQ(EvaluateAttenuation(f, 1e20), 0.4f);
  const std::vector<Vertex> single = {{1.0f, 0.7f}};
  EXPECT_EQ(EvaluateAttenuation(single, 0.5), 0.0f);
  EXPECT_EQ(EvaluateAttenuation(single, 1.0), 0.7f);
  EXPECT_EQ(EvaluateAttenuation(single, 9.0), 0.7f);
}

// Against a straightforward linear scan on random piecewise-linear functions with jumps.
float ScanEvaluate(const std::vector<Vertex>& f, double z) {
  if (f.empty() || z < f.front().z) return 0.0f;
  size_t lo = 0;
  while (lo + 1 < f.size() && f[lo + 1].z <= z) ++lo;
  if (lo + 1 == f.size()) return f[lo].a;
  const double t = (z - f[lo].z) / (static_cast<double>(f[lo + 1].z) - f[lo].z);
  return static_cast<float>(f[lo].a + t * (static_cast<double>(f[lo + 1].a) - f[lo].a));
}

TEST(EvaluateAttenuationTest, MatchesLinearScanOnRandomFunctions) {
  std::mt19937_64 rng(31337);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<Vertex> f;
    double z = unit(rng);
    const int size = static_cast<int>(unit(rng) * 20);
    for (int k = 0; k < size; ++k) {
      if (unit(rng) < 0.7) z += unit(rng);  // else a jump
      f.push_back({static_cast<float>(z), static_cast<float>(unit(rng))});
    }
    for (int probe = 0; probe < 50; ++probe) {
      const double zq = -0.5 + unit(rng) * (z + 1.5);
      ASSERT_EQ(EvaluateAttenuation(f, zq), ScanEvaluate(f, zq)) << "trial " << trial;
    }
    for (const Vertex& v : f) {
      ASSERT_EQ(EvaluateAttenuation(f, v.z), ScanEvaluate(f, v.z)) << "trial " << trial;
    }
  }
}

}  // namespace
}  // namespace pdsm
