#include "core/events/emitter_shares.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace pdsm {
namespace {

// Random hidden sets changing along the ray: the interpolated A stays within the tolerance of
// the exact sum, for lights from a tenth of the depths to ten times them (where the shares
// change fastest and the w-range must be split, or evaluated exactly).
TEST(EmitterSharesTest, WithinTheToleranceOfTheExactSumForAnyHiddenSet) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const double half_size : {0.1, 1.0, 10.0}) {
    double worst = 0;
    for (int trial = 0; trial < 20; ++trial) {
      const int n = 16 + 10 * trial;
      std::vector<glm::dvec2> samples(n);
      for (glm::dvec2& s : samples)
        s = {half_size * (2 * u(rng) - 1), half_size * (2 * u(rng) - 1)};
      EmitterRay exact(samples, n), fast(samples, n);
      const double s = 2 * u(rng) - 1, t = 2 * u(rng) - 1;
      exact.SetRay(s, t);
      fast.SetRay(s, t);
      const double tolerance = 1e-3;
      EmitterShares shares(&fast, 1.0, 10.0, tolerance, /*exact=*/false);
      for (double z = 1.0; z <= 10.0; z += 0.05) {
        const int k = static_cast<int>(u(rng) * n);
        const Event e{static_cast<float>(z),
                      exact.is_hidden(k) ? -SampleEventKey(k) : SampleEventKey(k)};
        exact.Apply(e);
        shares.Apply(e);
        worst = std::max(worst, std::abs(shares.At(z) - exact.Attenuation(z)));
      }
    }
    std::printf("light half-size %.1f: worst %.2e\n", half_size, worst);
    EXPECT_LE(worst, 1e-3) << half_size;
  }
}

TEST(EmitterSharesTest, PlateausAreExact) {
  const std::vector<glm::dvec2> samples = {{-3, 0}, {3, 0}, {0, 3}};
  EmitterRay ray(samples, 3);
  ray.SetRay(0.2, 0.1);
  EmitterShares shares(&ray, 0.5, 5.0, 1e-3, false);
  EXPECT_EQ(shares.At(1.0), 0.0);
  for (int k = 0; k < 3; ++k) shares.Apply(Event{1.0f, SampleEventKey(k)});
  EXPECT_EQ(shares.At(2.0), 1.0);
  shares.Apply(Event{3.0f, -SampleEventKey(1)});
  EXPECT_GT(shares.At(3.0), 0.0);
  EXPECT_LT(shares.At(3.0), 1.0);
}

}  // namespace
}  // namespace pdsm
