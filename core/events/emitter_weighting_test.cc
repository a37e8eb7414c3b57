#include "core/events/emitter_weighting.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/events/consolidation.h"

namespace pdsm {
namespace {

std::vector<glm::dvec2> RandomSamples(std::mt19937_64& rng, int n, double half_size) {
  std::uniform_real_distribution<double> u(-half_size, half_size);
  std::vector<glm::dvec2> samples(n);
  for (glm::dvec2& s : samples) s = {u(rng), u(rng)};
  return samples;
}

// The definition, in 3-D: sample k at (a, b, 0) on a light of normal (0, 0, 1), the point at
// z (s, t, 1); each sample weighs cos(angle at the light) / distance².
double WeightedByDefinition(const std::vector<glm::dvec2>& samples, const std::vector<bool>& hidden,
                            double s, double t, double z) {
  const glm::dvec3 point(s * z, t * z, z);
  double all = 0, part = 0;
  for (size_t k = 0; k < samples.size(); ++k) {
    const glm::dvec3 d = point - glm::dvec3(samples[k], 0.0);
    const double r = glm::length(d);
    const double weight = (d.z / r) / (r * r);
    all += weight;
    if (hidden[k]) part += weight;
  }
  return part / all;
}

TEST(EmitterRayTest, MatchesTheDefinitionInThreeDimensions) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const std::vector<glm::dvec2> samples = RandomSamples(rng, 1 + trial % 37, 3.0);
    EmitterRay ray(samples, static_cast<int>(samples.size()));
    const double s = 2 * u(rng) - 1, t = 2 * u(rng) - 1, z = 0.1 + 20 * u(rng);
    ray.SetRay(s, t);
    std::vector<bool> hidden(samples.size());
    for (size_t k = 0; k < samples.size(); ++k) {
      hidden[k] = u(rng) < 0.5;
      if (hidden[k]) ray.Apply(Event{1.0f, SampleEventKey(static_cast<int>(k))});
    }
    EXPECT_NEAR(ray.Attenuation(z), WeightedByDefinition(samples, hidden, s, t, z), 1e-12);
  }
}

TEST(EmitterRayTest, PlateausAreExactAndATinyLightIsTheCount) {
  std::mt19937_64 rng(6);
  const std::vector<glm::dvec2> samples = RandomSamples(rng, 64, 2.0);
  EmitterRay ray(samples, 64);
  ray.SetRay(0.3, -0.2);
  EXPECT_EQ(ray.Attenuation(0.5), 0.0);
  for (int k = 0; k < 64; ++k) ray.Apply(Event{1.0f, SampleEventKey(k)});
  EXPECT_EQ(ray.Attenuation(0.5), 1.0);  // near the light, where the weights differ most
  ray.Apply(Event{2.0f, -SampleEventKey(10)});
  EXPECT_LT(ray.Attenuation(0.5), 1.0);
  // A light a millionth of the depth: every sample weighs the same to first order in its size
  // (shares differ by ~3 |s| size / z = 1e-6), A = hidden / N.
  const std::vector<glm::dvec2> tiny = RandomSamples(rng, 64, 1e-6);
  EmitterRay small(tiny, 64);
  small.SetRay(0.3, -0.2);
  for (int k = 0; k < 16; ++k) small.Apply(Event{1.0f, SampleEventKey(k)});
  EXPECT_NEAR(small.Attenuation(1.0), 0.25, 1e-6);
}

// An adaptive tile weighs a prefix of the samples: an event of a later one changes nothing and
// writes nowhere, nor does a repeated entry.
TEST(EmitterRayTest, EventsOfOtherSamplesAndRepeatsChangeNothing) {
  const std::vector<glm::dvec2> samples = {{-1, 0}, {1, 0}, {0, 1}, {0, -1}};
  EmitterRay ray(samples, 2);
  ray.SetRay(0.0, 0.0);
  EXPECT_FALSE(ray.Apply(Event{1.0f, SampleEventKey(2)}));
  EXPECT_FALSE(ray.Apply(Event{1.0f, -SampleEventKey(3)}));
  EXPECT_FALSE(ray.Apply(Event{1.0f, std::numeric_limits<int32_t>::min()}));
  EXPECT_EQ(ray.hidden(), 0);
  EXPECT_TRUE(ray.Apply(Event{1.0f, SampleEventKey(1)}));
  EXPECT_FALSE(ray.Apply(Event{2.0f, SampleEventKey(1)}));
  EXPECT_EQ(ray.hidden(), 1);
  EXPECT_NEAR(ray.Attenuation(1.0), 0.5, 1e-12);  // the two samples mirror each other
}

TEST(RoundAttenuationTest, MultiplesOfTheQuantumWithinHalfOfItPlateausAndNaNKept) {
  const double tolerance = EmitterTolerance(0.01);
  const double quantum = EmitterQuantum(tolerance);
  EXPECT_LE(quantum, tolerance / 4);
  EXPECT_GT(quantum, tolerance / 8);
  EXPECT_EQ(std::exp2(std::round(std::log2(quantum))), quantum);  // a power of two
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Vertex> vertices = {{1.0f, 0.0f},
                                  {2.0f, 1.0f},
                                  {3.0f, std::numeric_limits<float>::quiet_NaN()},
                                  {4.0f, static_cast<float>(quantum / 3)}};
  for (int k = 0; k < 1000; ++k) vertices.push_back({5.0f, u(rng)});
  const std::vector<Vertex> original = vertices;
  RoundAttenuation(quantum, &vertices);
  EXPECT_EQ(vertices[0].a, 0.0f);
  EXPECT_EQ(vertices[1].a, 1.0f);
  EXPECT_TRUE(std::isnan(vertices[2].a));
  EXPECT_EQ(vertices[3].a, 0.0f);
  for (size_t k = 4; k < vertices.size(); ++k) {
    EXPECT_LE(std::abs(vertices[k].a - original[k].a), quantum / 2 + 1e-7);
    EXPECT_EQ(std::fmod(vertices[k].a, quantum), 0.0);
    EXPECT_EQ(vertices[k].z, original[k].z);
  }
}

// A ray through random casters: each sample hidden on random depth intervals.
std::vector<Event> RandomRayEvents(std::mt19937_64& rng, int samples, double z_lo, double z_hi) {
  std::uniform_real_distribution<double> u(z_lo, z_hi);
  std::uniform_int_distribution<int> changes(0, 3);
  std::vector<Event> events;
  for (int k = 0; k < samples; ++k) {
    std::vector<float> z(changes(rng));
    for (float& d : z) d = static_cast<float>(u(rng));
    std::sort(z.begin(), z.end());
    for (size_t i = 0; i < z.size(); ++i) {
      events.push_back(Event{z[i], i % 2 == 0 ? SampleEventKey(k) : -SampleEventKey(k)});
    }
  }
  NormalizeEvents(&events, EventKeying::kSampleKeys);
  return ConsolidateEvents(events, EventKeying::kSampleKeys);
}

// The exact A at z from the events, hidden set replayed (right-continuous).
double ExactAt(const std::vector<Event>& events, EmitterRay* ray, double z) {
  ray->ClearHidden();
  for (const Event& e : events) {
    if (e.z <= z) ray->Apply(e);
  }
  return ray->Attenuation(z);
}

// A is read from the shares' interpolants (core/events/emitter_shares.h) within a quarter of
// the tolerance; the chords between vertices keep the rest.
TEST(EmitterWeightedFunctionTest, WithinTheToleranceEverywhereAndAQuarterOfItAtEvents) {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0;
  for (int trial = 0; trial < 60; ++trial) {
    // Lights from small to larger than the depths (where the shares drift most).
    const double half_size = 0.1 + 5.0 * u(rng);
    const int n = 8 + trial % 57;
    const std::vector<glm::dvec2> samples = RandomSamples(rng, n, half_size);
    EmitterRay ray(samples, n);
    const double s = 2 * u(rng) - 1, t = 2 * u(rng) - 1;
    ray.SetRay(s, t);
    const std::vector<Event> events = RandomRayEvents(rng, n, 0.5, 12.0);
    const double tolerance = EmitterTolerance(0.02);
    const double z_end = 15.0;
    const std::vector<Vertex> f = EmitterWeightedFunction(events, &ray, z_end, tolerance);
    ASSERT_FALSE(f.empty() && !events.empty());
    ASSERT_TRUE(std::is_sorted(f.begin(), f.end(),
                               [](const Vertex& a, const Vertex& b) { return a.z < b.z; }));
    for (const Event& e : events) {  // right after each event: a vertex
      EXPECT_NEAR(EvaluateAttenuation(f, e.z), ExactAt(events, &ray, e.z), 0.25 * tolerance);
    }
    for (int k = 0; k < 400; ++k) {
      const double z = 0.5 + (z_end - 0.5) * u(rng);
      worst = std::max(worst, std::abs(EvaluateAttenuation(f, z) - ExactAt(events, &ray, z)));
    }
    EXPECT_EQ(EvaluateAttenuation(f, 0.25), 0.0f);  // before any event
  }
  std::printf("worst deviation %.5f (tolerance %.5f)\n", worst, EmitterTolerance(0.02));
  EXPECT_LE(worst, EmitterTolerance(0.02));
}

TEST(EmitterWeightedFunctionTest, PieceMatchesTheWholeFunctionInsideItsWindow) {
  std::mt19937_64 rng(9);
  const std::vector<glm::dvec2> samples = RandomSamples(rng, 32, 2.0);
  EmitterRay ray(samples, 32);
  ray.SetRay(0.1, 0.2);
  const std::vector<Event> events = RandomRayEvents(rng, 32, 1.0, 10.0);
  const double tolerance = EmitterTolerance(0.0);
  const std::vector<Vertex> whole = EmitterWeightedFunction(events, &ray, 12.0, tolerance);
  const std::vector<Vertex> piece = EmitterWeightedPiece(events, &ray, 3.0, 6.0, tolerance);
  ASSERT_GE(piece.size(), 2u);
  EXPECT_EQ(piece.front().z, 3.0f);
  EXPECT_EQ(piece.back().z, 6.0f);
  for (double z = 3.0; z < 6.0; z += 0.01) {
    EXPECT_NEAR(EvaluateAttenuation(piece, z), EvaluateAttenuation(whole, z), 2 * tolerance) << z;
  }
}

TEST(EmitterWeightedFunctionTest, AFullUmbraTailNeedsNoVertexAndStaysOne) {
  const std::vector<glm::dvec2> samples = {{-1, -1}, {1, -1}, {-1, 1}, {1, 1}};
  EmitterRay ray(samples, 4);
  ray.SetRay(0.0, 0.0);
  std::vector<Event> events;
  for (int k = 0; k < 4; ++k) events.push_back(Event{static_cast<float>(2 + k), SampleEventKey(k)});
  const std::vector<Vertex> f = EmitterWeightedFunction(events, &ray, 100.0, 1e-3);
  EXPECT_EQ(f.back().a, 1.0f);
  EXPECT_EQ(f.back().z, 5.0f);  // no vertex is added past the last event: A stays 1
  EXPECT_EQ(EvaluateAttenuation(f, 50.0), 1.0f);
}

}  // namespace
}  // namespace pdsm
