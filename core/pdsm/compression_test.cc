#include "core/pdsm/compression.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/events/consolidation.h"
#include "core/events/event.h"
#include "core/pdsm/attenuation_function.h"

namespace pdsm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const double kEpsilons[] = {1e-6, 1e-3, 0.01, 0.05, 0.3, 1.0};

std::string Describe(const std::vector<Vertex>& f) {
  std::ostringstream os;
  os.precision(9);
  os << "[";
  for (size_t i = 0; i < f.size(); ++i)
    os << (i ? ", " : "") << "(" << f[i].z << ", " << f[i].a << ")";
  os << "]";
  return os.str();
}

// ---------------------------------------------------------------------------------------------
// Random functions like the bake's: events with counts +-1, N in 1..256, the hidden count kept
// in [0, N], normalized, consolidated and turned into a step function. Steps are log-uniform so
// that penumbra-like runs of close events and long flat stretches both occur.

std::vector<Vertex> RandomEventFunction(std::mt19937_64& rng) {
  std::uniform_int_distribution<int> samples_dist(1, 256);
  std::uniform_int_distribution<int> size_dist(0, 80);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int n = samples_dist(rng);
  const int size = size_dist(rng);
  const double step_scale = std::pow(10.0, -3.0 + 3.0 * unit(rng));  // a ramp's step size
  double z = 1.0 + 20.0 * unit(rng);
  int hidden = 0;
  int direction = 1;
  std::vector<Event> events;
  for (int k = 0; k < size; ++k) {
    z += step_scale * std::pow(10.0, -1.0 + 3.0 * unit(rng));
    if (unit(rng) < 0.2) direction = -direction;  // runs of entering or leaving shadow
    int count = direction;
    if (hidden + count < 0 || hidden + count > n) count = -count;
    hidden += count;
    events.push_back({static_cast<float>(z), count});
  }
  NormalizeEvents(&events, EventKeying::kCounts);
  return FunctionFromEvents(ConsolidateEvents(events, EventKeying::kCounts), n);
}

// Random piecewise-linear functions with values in [0, 1] and nondecreasing depths, jumps
// (repeated depths) included.
std::vector<Vertex> RandomPiecewiseLinear(std::mt19937_64& rng) {
  std::uniform_int_distribution<int> size_dist(0, 60);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int size = size_dist(rng);
  const bool walk = unit(rng) < 0.5;
  double z = 0.5 + 5.0 * unit(rng);
  double a = unit(rng);
  std::vector<Vertex> f;
  for (int k = 0; k < size; ++k) {
    if (k > 0 && unit(rng) > 0.25) z += std::pow(10.0, -3.0 + 3.0 * unit(rng));
    a = walk ? std::clamp(a + 0.2 * (unit(rng) - 0.5), 0.0, 1.0) : unit(rng);
    f.push_back({static_cast<float>(z), static_cast<float>(a)});
  }
  return f;
}

std::vector<Vertex> RandomFunction(std::mt19937_64& rng, int trial) {
  return trial % 2 == 0 ? RandomEventFunction(rng) : RandomPiecewiseLinear(rng);
}

// ---------------------------------------------------------------------------------------------
// Checks.

// Output depths are input depths, nondecreasing, and there are no more vertices than input.
testing::AssertionResult StructureHolds(const std::vector<Vertex>& in,
                                        const std::vector<Vertex>& out) {
  if (out.size() > in.size()) {
    return testing::AssertionFailure()
           << "output larger than input: " << out.size() << " > " << in.size();
  }
  for (size_t i = 0; i < out.size(); ++i) {
    if (i > 0 && out[i].z < out[i - 1].z) {
      return testing::AssertionFailure() << "output depth decreases at " << i;
    }
    if (std::none_of(in.begin(), in.end(), [&](const Vertex& v) { return v.z == out[i].z; })) {
      return testing::AssertionFailure() << "output depth " << out[i].z << " is not an input depth";
    }
  }
  if (!in.empty() &&
      (out.empty() || out.front().z != in.front().z || out.back().z != in.back().z)) {
    return testing::AssertionFailure() << "output does not span the input's depths";
  }
  return testing::AssertionSuccess();
}

// Depths where |A' - A| is largest on each piece: every input depth (the right-continuous
// value), just before it (the left limit), midpoints between distinct depths, and outside.
std::vector<double> Probes(const std::vector<Vertex>& in) {
  std::vector<double> probes;
  if (in.empty()) return probes;
  probes.push_back(in.front().z - 1.0);
  probes.push_back(in.back().z + 1.0);
  for (size_t i = 0; i < in.size(); ++i) {
    const double z = in[i].z;
    probes.push_back(z);
    probes.push_back(std::nextafter(z, -kInf));
    if (i + 1 < in.size() && in[i + 1].z > in[i].z) probes.push_back(0.5 * (z + in[i + 1].z));
  }
  return probes;
}

// Output vertices are attenuations: a in [0, 1] (attenuation_function.h).
testing::AssertionResult ValuesInRange(const std::vector<Vertex>& out) {
  for (const Vertex& v : out) {
    if (!(v.a >= 0.0f && v.a <= 1.0f)) {
      return testing::AssertionFailure()
             << "output value " << v.a << " at z = " << v.z << " outside [0, 1]: " << Describe(out);
    }
  }
  return testing::AssertionSuccess();
}

testing::AssertionResult VerticalBoundHolds(const std::vector<Vertex>& in,
                                            const std::vector<Vertex>& out, double epsilon) {
  for (double z : Probes(in)) {
    const double a_in = EvaluateAttenuation(in, z);
    const double a_out = EvaluateAttenuation(out, z);
    if (!(std::abs(a_out - a_in) <= epsilon + 1e-9)) {
      return testing::AssertionFailure()
             << "|A'(z) - A(z)| = " << std::abs(a_out - a_in) << " > epsilon " << epsilon
             << " at z = " << z << " (A = " << a_in << ", A' = " << a_out << ")\n  input "
             << Describe(in) << "\n  output " << Describe(out);
    }
  }
  return testing::AssertionSuccess();
}

// Distance in the plane (z / depth_scale, A) from input vertex p to the output segment that
// spans its depth: to the segment's line when it spans depth, to the segment itself when it is
// a jump (both ends at one depth). The smallest over spanning segments (a vertex at a segment
// boundary is spanned by two).
double PerpendicularDistance(const std::vector<Vertex>& out, const Vertex& p, double scale) {
  double best = kInf;
  if (out.size() == 1 && out[0].z == p.z) return std::abs(out[0].a - p.a);
  for (size_t k = 0; k + 1 < out.size(); ++k) {
    const Vertex& q0 = out[k];
    const Vertex& q1 = out[k + 1];
    if (!(q0.z <= p.z && p.z <= q1.z)) continue;
    if (q0.z == q1.z) {
      const double lo = std::min(q0.a, q1.a), hi = std::max(q0.a, q1.a);
      best = std::min(best, std::abs(p.a - std::clamp<double>(p.a, lo, hi)));
      continue;
    }
    const double dx = (static_cast<double>(q1.z) - q0.z) / scale;
    const double dy = static_cast<double>(q1.a) - q0.a;
    const double px = (static_cast<double>(p.z) - q0.z) / scale;
    const double py = static_cast<double>(p.a) - q0.a;
    best = std::min(best, std::abs(dx * py - dy * px) / std::hypot(dx, dy));
  }
  return best;
}

testing::AssertionResult PerpendicularBoundHolds(const std::vector<Vertex>& in,
                                                 const std::vector<Vertex>& out, double epsilon,
                                                 double scale) {
  for (const Vertex& p : in) {
    const double d = PerpendicularDistance(out, p, scale);
    if (!(d <= epsilon + 1e-9)) {
      return testing::AssertionFailure()
             << "vertex (" << p.z << ", " << p.a << ") is " << d << " from its output segment's "
             << "line, epsilon " << epsilon << ", depth_scale " << scale << "\n  input "
             << Describe(in) << "\n  output " << Describe(out);
    }
  }
  return testing::AssertionSuccess();
}

// The jumps of A larger than `size`: depths where the left limit and the value differ.
std::vector<float> JumpsLargerThan(const std::vector<Vertex>& f, double size) {
  std::vector<float> jumps;
  // From index 1: the output starts with the input's first vertex, so the step from 0 at the
  // first depth needs no second vertex.
  for (size_t i = 1; i < f.size(); ++i) {
    if (f[i].z == f[i - 1].z) continue;
    const double left = EvaluateAttenuation(f, std::nextafter(static_cast<double>(f[i].z), -kInf));
    const double right = EvaluateAttenuation(f, f[i].z);
    if (std::abs(right - left) > size) jumps.push_back(f[i].z);
  }
  return jumps;
}

int VerticesAtDepth(const std::vector<Vertex>& f, float z) {
  return static_cast<int>(
      std::count_if(f.begin(), f.end(), [&](const Vertex& v) { return v.z == z; }));
}

constexpr int kTrials = 3000;
constexpr int kMaxReported = 3;

// ---------------------------------------------------------------------------------------------

TEST(CompressFunctionTest, VerticalErrorBoundOnRandomFunctions) {
  for (double epsilon : kEpsilons) {
    std::mt19937_64 rng(1000);
    int failures = 0;
    for (int trial = 0; trial < kTrials; ++trial) {
      const std::vector<Vertex> in = RandomFunction(rng, trial);
      const std::vector<Vertex> out =
          CompressFunction(in, epsilon, CompressionMetric::kVertical, 1.0);
      ASSERT_TRUE(StructureHolds(in, out)) << "epsilon " << epsilon << " trial " << trial;
      ASSERT_TRUE(ValuesInRange(out)) << "epsilon " << epsilon << " trial " << trial;
      const testing::AssertionResult bound = VerticalBoundHolds(in, out, epsilon);
      if (!bound && ++failures <= kMaxReported) {
        ADD_FAILURE() << "epsilon " << epsilon << " trial " << trial << ": " << bound.message();
      }
    }
    EXPECT_EQ(failures, 0) << "functions violating |A' - A| <= epsilon " << epsilon << " of "
                           << kTrials;
  }
}

// The middle line of the slope interval may overshoot [0, 1] at a segment's end; clamping the
// end value after the fit would bend the segment away from the vertices it covered (here: the
// unclipped middle slope ends at 1.25, clamped to 1 the segment misses (1, 0.9) by 0.4). The
// fit must keep the bound and stored values must stay attenuations.
TEST(CompressFunctionTest, VerticalBoundHoldsWhenSegmentEndWouldExceedOne) {
  const std::vector<Vertex> in = {{0.0f, 0.0f}, {1.0f, 0.9f}, {2.0f, 1.0f}, {3.0f, 0.0f}};
  const std::vector<Vertex> out = CompressFunction(in, 0.3, CompressionMetric::kVertical, 1.0);
  EXPECT_TRUE(VerticalBoundHolds(in, out, 0.3));
  EXPECT_TRUE(ValuesInRange(out));
}

TEST(CompressFunctionTest, VerticalBoundHoldsWhenSegmentEndWouldFallBelowZero) {
  const std::vector<Vertex> in = {{0.0f, 1.0f}, {1.0f, 0.1f}, {2.0f, 0.0f}, {3.0f, 1.0f}};
  const std::vector<Vertex> out = CompressFunction(in, 0.3, CompressionMetric::kVertical, 1.0);
  EXPECT_TRUE(VerticalBoundHolds(in, out, 0.3));
  EXPECT_TRUE(ValuesInRange(out));
}

TEST(CompressFunctionTest, PerpendicularBoundOnRandomFunctions) {
  for (double epsilon : kEpsilons) {
    for (double depth_scale : {0.01, 1.0, 100.0}) {
      std::mt19937_64 rng(2000);
      int failures = 0;
      for (int trial = 0; trial < kTrials; ++trial) {
        const std::vector<Vertex> in = RandomFunction(rng, trial);
        const std::vector<Vertex> out =
            CompressFunction(in, epsilon, CompressionMetric::kPerpendicular, depth_scale);
        ASSERT_TRUE(StructureHolds(in, out))
            << "epsilon " << epsilon << " scale " << depth_scale << " trial " << trial;
        const testing::AssertionResult bound =
            PerpendicularBoundHolds(in, out, epsilon, depth_scale);
        if (!bound && ++failures <= kMaxReported) {
          ADD_FAILURE() << "trial " << trial << ": " << bound.message();
        }
      }
      EXPECT_EQ(failures, 0) << "functions violating the perpendicular bound, epsilon " << epsilon
                             << ", depth_scale " << depth_scale << ", of " << kTrials;
    }
  }
}

// Regression: the perpendicular metric once let steep segments (large depth_scale, or jumps
// absorbed into a ramp) end far outside [0, 1], breaking Vertex::a's contract and
// QueryAttenuation's. Its admissible angles are now limited to lines inside [0, 1].
TEST(CompressFunctionTest, PerpendicularOutputValuesAreAttenuations) {
  // Minimal cases: a full step at z = 1 with depth_scale 100 (the step is 0.01 wide in scaled
  // depth). Observed outputs: (0, 0) (2, 1.3333) and (0, 1) (2, -0.3333).
  const std::vector<Vertex> up = {{0.0f, 0.0f}, {1.0f, 0.0f}, {1.0f, 1.0f}, {2.0f, 1.0f}};
  EXPECT_TRUE(ValuesInRange(CompressFunction(up, 0.01, CompressionMetric::kPerpendicular, 100.0)));
  const std::vector<Vertex> down = {{0.0f, 1.0f}, {1.0f, 1.0f}, {1.0f, 0.0f}, {2.0f, 0.0f}};
  EXPECT_TRUE(
      ValuesInRange(CompressFunction(down, 0.01, CompressionMetric::kPerpendicular, 100.0)));
  // Random functions. Tiny excursions (float rounding of 0) are tolerated here; the bug is
  // excursions beyond epsilon.
  for (double epsilon : kEpsilons) {
    for (double depth_scale : {0.01, 1.0, 100.0}) {
      std::mt19937_64 rng(2500);
      int failures = 0;
      for (int trial = 0; trial < kTrials; ++trial) {
        const std::vector<Vertex> in = RandomFunction(rng, trial);
        const std::vector<Vertex> out =
            CompressFunction(in, epsilon, CompressionMetric::kPerpendicular, depth_scale);
        for (const Vertex& v : out) {
          if (v.a < -epsilon || v.a > 1.0 + epsilon) {
            if (++failures <= kMaxReported) {
              ADD_FAILURE() << "epsilon " << epsilon << " depth_scale " << depth_scale << " trial "
                            << trial << ": value " << v.a << " at z = " << v.z << "\n  input "
                            << Describe(in) << "\n  output " << Describe(out);
            }
            break;
          }
        }
      }
      EXPECT_EQ(failures, 0) << "outputs with values beyond [-epsilon, 1 + epsilon], epsilon "
                             << epsilon << ", depth_scale " << depth_scale << ", of " << kTrials;
    }
  }
}

TEST(CompressFunctionTest, VerticalOutputValuesAreAttenuations) {
  for (double epsilon : kEpsilons) {
    std::mt19937_64 rng(2600);
    for (int trial = 0; trial < kTrials; ++trial) {
      const std::vector<Vertex> in = RandomFunction(rng, trial);
      ASSERT_TRUE(ValuesInRange(CompressFunction(in, epsilon, CompressionMetric::kVertical, 1.0)))
          << "epsilon " << epsilon << " trial " << trial;
    }
  }
}

TEST(CompressFunctionTest, ZeroEpsilonIsLossless) {
  std::mt19937_64 rng(3000);
  std::bernoulli_distribution duplicate(0.2);
  for (int trial = 0; trial < kTrials; ++trial) {
    std::vector<Vertex> in = RandomFunction(rng, trial);
    // Sprinkle exact duplicates in.
    std::vector<Vertex> with_duplicates;
    for (const Vertex& v : in) {
      with_duplicates.push_back(v);
      if (duplicate(rng)) with_duplicates.push_back(v);
    }
    std::vector<Vertex> expected;
    for (const Vertex& v : with_duplicates) {
      if (expected.empty() || !(expected.back() == v)) expected.push_back(v);
    }
    for (CompressionMetric metric :
         {CompressionMetric::kVertical, CompressionMetric::kPerpendicular}) {
      ASSERT_EQ(CompressFunction(with_duplicates, 0.0, metric, 1.0), expected) << "trial " << trial;
    }
  }
}

TEST(CompressFunctionTest, EpsilonOneKeepsTheBound) {
  std::mt19937_64 rng(4000);
  for (int trial = 0; trial < kTrials; ++trial) {
    const std::vector<Vertex> in = RandomFunction(rng, trial);
    const std::vector<Vertex> out = CompressFunction(in, 1.0, CompressionMetric::kVertical, 1.0);
    ASSERT_TRUE(StructureHolds(in, out)) << "trial " << trial;
    ASSERT_TRUE(VerticalBoundHolds(in, out, 1.0)) << "trial " << trial;
  }
}

// With epsilon = 1 and values in (0, 0.5], the flat line through the first vertex is within
// epsilon of every vertex, so the slope interval never empties: one segment, two vertices.
// (Values are kept off exact 0: exact plateaus are kept whatever epsilon, tested below.)
TEST(CompressFunctionTest, EpsilonOneGivesOneSegmentForValuesUpToHalf) {
  std::mt19937_64 rng(4500);
  for (int trial = 0; trial < kTrials; ++trial) {
    std::vector<Vertex> in = RandomFunction(rng, trial);
    for (Vertex& v : in) v.a = 0.001f + 0.499f * v.a;
    for (CompressionMetric metric :
         {CompressionMetric::kVertical, CompressionMetric::kPerpendicular}) {
      const std::vector<Vertex> out = CompressFunction(in, 1.0, metric, 1.0);
      ASSERT_LE(out.size(), 2u) << "trial " << trial << " input " << Describe(in) << " output "
                                << Describe(out);
      ASSERT_TRUE(VerticalBoundHolds(in, out, 1.0));
    }
  }
}

// Issue #15: the input's exact plateaus (A exactly 0: fully lit; exactly 1: umbra) read exactly
// the same after compression, at every depth they span and whatever epsilon and metric, and
// the bound still holds elsewhere. Functions like the bake's (events of N samples, the hidden
// count reaching 0 and N) and random piecewise-linear ones clamped to [0, 1].
TEST(CompressFunctionTest, ExactPlateausStayExact) {
  int plateaus = 0;
  for (double epsilon : kEpsilons) {
    for (CompressionMetric metric :
         {CompressionMetric::kVertical, CompressionMetric::kPerpendicular}) {
      std::mt19937_64 rng(6000);
      for (int trial = 0; trial < kTrials; ++trial) {
        const std::vector<Vertex> in = RandomFunction(rng, trial);
        const std::vector<Vertex> out = CompressFunction(in, epsilon, metric, 1.0);
        ASSERT_TRUE(StructureHolds(in, out)) << "trial " << trial;
        ASSERT_TRUE(metric == CompressionMetric::kVertical
                        ? VerticalBoundHolds(in, out, epsilon)
                        : PerpendicularBoundHolds(in, out, epsilon, 1.0))
            << "epsilon " << epsilon << " trial " << trial;
        for (size_t i = 0; i + 1 < in.size(); ++i) {
          const float a = in[i].a;
          if (!(a == 0.0f || a == 1.0f) || in[i + 1].a != a || !(in[i + 1].z > in[i].z)) continue;
          ++plateaus;
          for (double f : {0.0, 0.25, 0.5, 0.75}) {
            const double z = in[i].z + f * (in[i + 1].z - in[i].z);
            ASSERT_EQ(EvaluateAttenuation(out, z), a)
                << "epsilon " << epsilon << " trial " << trial << " plateau at " << in[i].z << "..."
                << in[i + 1].z << ", z " << z << "\ninput " << Describe(in) << "\noutput "
                << Describe(out);
          }
        }
      }
    }
  }
  EXPECT_GT(plateaus, 10000) << "the random functions must hold plateaus to test";
}

// A jump larger than 2 epsilon cannot be followed within epsilon by a continuous function, so
// it must stay a jump: two output vertices at its depth.
TEST(CompressFunctionTest, VerticalKeepsJumpsLargerThanTwiceEpsilon) {
  for (double epsilon : kEpsilons) {
    std::mt19937_64 rng(5000);
    for (int trial = 0; trial < kTrials; ++trial) {
      const std::vector<Vertex> in = RandomFunction(rng, trial);
      const std::vector<Vertex> out =
          CompressFunction(in, epsilon, CompressionMetric::kVertical, 1.0);
      for (float z : JumpsLargerThan(in, 2 * epsilon)) {
        ASSERT_GE(VerticesAtDepth(out, z), 2)
            << "epsilon " << epsilon << " trial " << trial << " jump at " << z << "\n  input "
            << Describe(in) << "\n  output " << Describe(out);
      }
    }
  }
}

// compression.h: jumps stay jumps. Regression: the perpendicular metric once admitted a jump
// inside a segment like any vertex; in the plane (z / depth_scale, A) a near-vertical line passes
// within epsilon of both its ends, so {(0,0) (1,0) (1,1) (2,1)} at epsilon 0.01, depth_scale 100
// became {(0,0) (2,1.3333)}, with no vertex at z = 1.
TEST(CompressFunctionTest, PerpendicularKeepsJumpsLargerThanTwiceEpsilon) {
  const std::vector<Vertex> step = {{0.0f, 0.0f}, {1.0f, 0.0f}, {1.0f, 1.0f}, {2.0f, 1.0f}};
  const std::vector<Vertex> out =
      CompressFunction(step, 0.01, CompressionMetric::kPerpendicular, 100.0);
  EXPECT_EQ(VerticesAtDepth(out, 1.0f), 2) << Describe(out);
  for (double epsilon : kEpsilons) {
    for (double depth_scale : {0.01, 1.0, 100.0}) {
      std::mt19937_64 rng(5500);
      int failures = 0;
      for (int trial = 0; trial < kTrials; ++trial) {
        const std::vector<Vertex> in = RandomFunction(rng, trial);
        const std::vector<Vertex> compressed =
            CompressFunction(in, epsilon, CompressionMetric::kPerpendicular, depth_scale);
        for (float z : JumpsLargerThan(in, 2 * epsilon)) {
          if (VerticesAtDepth(compressed, z) < 2) {
            if (++failures <= kMaxReported) {
              ADD_FAILURE() << "epsilon " << epsilon << " depth_scale " << depth_scale << " trial "
                            << trial << " jump at " << z << "\n  input " << Describe(in)
                            << "\n  output " << Describe(compressed);
            }
            break;
          }
        }
      }
      EXPECT_EQ(failures, 0) << "functions losing a jump, epsilon " << epsilon << ", depth_scale "
                             << depth_scale << ", of " << kTrials;
    }
  }
}

TEST(CompressFunctionTest, StepStaysAJump) {
  // Lit, then a step of 0.5 in the middle of a flat stretch, then flat.
  const std::vector<Vertex> in = {{1.0f, 0.0f}, {2.0f, 0.0f}, {3.0f, 0.0f},
                                  {3.0f, 0.5f}, {4.0f, 0.5f}, {5.0f, 0.5f}};
  for (CompressionMetric metric :
       {CompressionMetric::kVertical, CompressionMetric::kPerpendicular}) {
    for (double epsilon : {0.01, 0.1, 0.2}) {
      const std::vector<Vertex> out = CompressFunction(in, epsilon, metric, 1.0);
      EXPECT_EQ(VerticesAtDepth(out, 3.0f), 2) << "epsilon " << epsilon << " " << Describe(out);
      EXPECT_NEAR(EvaluateAttenuation(out, 3.0), 0.5, epsilon);
      EXPECT_NEAR(EvaluateAttenuation(out, 2.999), 0.0, epsilon);
      // Flat stretches need no interior vertices.
      EXPECT_LE(out.size(), 4u) << Describe(out);
    }
  }
}

// A penumbra: 256 samples entering shadow one after another over a short depth range.
std::vector<Vertex> PenumbraRamp() {
  std::vector<Event> events;
  for (int k = 0; k < 256; ++k) events.push_back({static_cast<float>(10.0 + 0.01 * k), 1});
  return FunctionFromEvents(events, 256);
}

TEST(CompressFunctionTest, PenumbraRampCompresses) {
  const std::vector<Vertex> in = PenumbraRamp();
  ASSERT_EQ(in.size(), 512u);
  const std::vector<Vertex> vertical =
      CompressFunction(in, 0.02, CompressionMetric::kVertical, 1.0);
  EXPECT_LT(vertical.size(), 64u) << Describe(vertical);
  EXPECT_TRUE(VerticalBoundHolds(in, vertical, 0.02));
  for (double depth_scale : {0.01, 1.0, 100.0}) {
    const std::vector<Vertex> perpendicular =
        CompressFunction(in, 0.02, CompressionMetric::kPerpendicular, depth_scale);
    EXPECT_LT(perpendicular.size(), 64u) << "depth_scale " << depth_scale;
    EXPECT_TRUE(PerpendicularBoundHolds(in, perpendicular, 0.02, depth_scale));
  }
}

TEST(CompressFunctionTest, TinyInputsAreReturnedDeduplicated) {
  const std::vector<Vertex> empty;
  EXPECT_TRUE(CompressFunction(empty, 0.1, CompressionMetric::kVertical, 1.0).empty());
  const std::vector<Vertex> one = {{1.0f, 0.5f}};
  EXPECT_EQ(CompressFunction(one, 0.1, CompressionMetric::kVertical, 1.0), one);
  const std::vector<Vertex> jump = {{1.0f, 0.0f}, {1.0f, 0.5f}};
  EXPECT_EQ(CompressFunction(jump, 0.1, CompressionMetric::kVertical, 1.0), jump);
}

TEST(CompressFunctionTest, Deterministic) {
  std::mt19937_64 rng(6000);
  for (int trial = 0; trial < 200; ++trial) {
    const std::vector<Vertex> in = RandomFunction(rng, trial);
    EXPECT_EQ(CompressFunction(in, 0.05, CompressionMetric::kVertical, 1.0),
              CompressFunction(in, 0.05, CompressionMetric::kVertical, 1.0));
  }
}

}  // namespace
}  // namespace pdsm
