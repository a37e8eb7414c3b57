#include "core/sampling/light_samples.h"

#include <cmath>
#include <numbers>

#include "core/sampling/blue_noise.h"
#include "core/sampling/hash_rng.h"
#include "core/sampling/low_discrepancy.h"

namespace pdsm {

std::vector<glm::dvec2> StratifiedUnitSquare(int count, uint64_t seed) {
  std::vector<glm::dvec2> points;
  if (count <= 0) return points;
  points.reserve(count);
  SplitMix64 rng(seed);
  const int rows = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(count))));
  // Spread the cells over the rows as evenly as possible; row heights follow the counts.
  double row_bottom = 0.0;
  for (int r = 0; r < rows; ++r) {
    const int cells = (count * (r + 1)) / rows - (count * r) / rows;
    const double row_height = static_cast<double>(cells) / count;
    for (int c = 0; c < cells; ++c) {
      const double x = (c + rng.NextDouble()) / cells;
      const double y = row_bottom + rng.NextDouble() * row_height;
      // (c + u) / cells can round up to 1.0: keep points inside [0, 1).
      const double below_one = std::nextafter(1.0, 0.0);
      points.emplace_back(std::min(x, below_one), std::min(y, below_one));
    }
    row_bottom += row_height;
  }
  return points;
}

std::vector<glm::dvec2> UniformUnitSquare(int count, uint64_t seed) {
  std::vector<glm::dvec2> points;
  SplitMix64 rng(seed);
  for (int i = 0; i < count; ++i) {
    const double x = rng.NextDouble();
    points.emplace_back(x, rng.NextDouble());
  }
  return points;
}

std::vector<glm::dvec2> UnitSquareSamples(int count, SamplingPattern pattern, uint64_t seed) {
  switch (pattern) {
    case SamplingPattern::kUniform:
      return UniformUnitSquare(count, seed);
    case SamplingPattern::kSobol:
      return SobolUnitSquare(count, seed);
    case SamplingPattern::kHalton:
      return HaltonUnitSquare(count, seed);
    case SamplingPattern::kBlueNoise:
      return BlueNoiseUnitSquare(count, seed);
    case SamplingPattern::kStratified:
      break;
  }
  return StratifiedUnitSquare(count, seed);
}

glm::dvec2 ConcentricDisk(const glm::dvec2& u) {
  const glm::dvec2 d = 2.0 * u - 1.0;
  if (d.x == 0.0 && d.y == 0.0) return {0.0, 0.0};
  constexpr double kPiOver4 = std::numbers::pi / 4.0;
  double r, theta;
  if (std::abs(d.x) > std::abs(d.y)) {
    r = d.x;
    theta = kPiOver4 * (d.y / d.x);
  } else {
    r = d.y;
    theta = 2.0 * kPiOver4 - kPiOver4 * (d.x / d.y);
  }
  return r * glm::dvec2(std::cos(theta), std::sin(theta));
}

std::vector<glm::dvec2> GenerateLightSamples(const LightSpec& light, int count,
                                             SamplingPattern pattern, uint64_t seed) {
  std::vector<glm::dvec2> unit = UnitSquareSamples(count, pattern, seed);
  for (glm::dvec2& p : unit) {
    switch (light.shape) {
      case LightShape::kRect:
        p = {(2.0 * p.x - 1.0) * light.half_width, (2.0 * p.y - 1.0) * light.half_height};
        break;
      case LightShape::kDisk:
        p = light.radius * ConcentricDisk(p);
        break;
      case LightShape::kSun:
        // Uniform on the disk of slopes: uniform in solid angle to O(angle^2), which for the
        // sun's 0.27 degree half-angle is far below any other error.
        p = light.tan_half_angle * ConcentricDisk(p);
        break;
    }
  }
  return unit;
}

}  // namespace pdsm
