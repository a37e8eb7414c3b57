#include "core/sampling/low_discrepancy.h"

#include <algorithm>
#include <cmath>

#include "core/sampling/hash_rng.h"

namespace pdsm {
namespace {

// Sobol dimension 0: the bits of the index reversed (van der Corput, base 2).
uint32_t SobolDimension0(uint32_t index) {
  uint32_t result = 0;
  for (uint32_t v = 1u << 31; index != 0; index >>= 1, v >>= 1) {
    if (index & 1) result ^= v;
  }
  return result;
}

// Sobol dimension 1: primitive polynomial x + 1, whose direction numbers are the rows of
// Pascal's triangle mod 2 (v_{k+1} = v_k ^ (v_k >> 1)).
uint32_t SobolDimension1(uint32_t index) {
  uint32_t result = 0;
  for (uint32_t v = 1u << 31; index != 0; index >>= 1, v ^= v >> 1) {
    if (index & 1) result ^= v;
  }
  return result;
}

double BelowOne(double x) { return std::min(x, std::nextafter(1.0, 0.0)); }

// Owen-scrambled radical inverse in base 3. 34 digits: 3^-34 < 2^-53, below double's
// resolution, so the (infinitely many) scrambled trailing digits are all accounted for.
double OwenScrambledRadicalInverse3(uint32_t index, uint64_t seed) {
  constexpr int kDigits = 34;
  // The six permutations of {0, 1, 2}.
  static constexpr uint8_t kPermutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                                  {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  uint8_t scrambled[kDigits];
  uint64_t prefix = 0;  // the original digits before d, as a base-3 number
  for (int d = 0; d < kDigits; ++d) {
    const uint32_t digit = index % 3;
    index /= 3;
    const uint64_t choice = HashInts(seed, d, prefix) % 6;
    scrambled[d] = kPermutations[choice][digit];
    prefix = prefix * 3 + digit;
  }
  double value = 0.0;  // from the least significant digit up: exact rounding at the end
  for (int d = kDigits - 1; d >= 0; --d) value = (value + scrambled[d]) / 3.0;
  return BelowOne(value);
}

double ToUnit(uint32_t bits) { return static_cast<double>(bits) * 0x1.0p-32; }

}  // namespace

uint32_t OwenScrambleBase2(uint32_t x, uint64_t seed) {
  uint32_t result = x;
  // Level 31 is the most significant bit; the flip of each bit depends on the bits above it
  // (the node of the binary tree the point sits in), which is what makes it Owen's scramble.
  for (int level = 31; level >= 0; --level) {
    const uint32_t prefix = level == 31 ? 0u : x >> (level + 1);
    if (HashInts(seed, level, prefix) & 1) result ^= 1u << level;
  }
  return result;
}

std::vector<glm::dvec2> SobolUnitSquare(int count, uint64_t seed) {
  std::vector<glm::dvec2> points;
  if (count <= 0) return points;
  points.reserve(count);
  const uint64_t seed_x = HashInts(seed, 0x50b01), seed_y = HashInts(seed, 0x50b02);
  for (int i = 0; i < count; ++i) {
    const uint32_t index = static_cast<uint32_t>(i);
    points.emplace_back(ToUnit(OwenScrambleBase2(SobolDimension0(index), seed_x)),
                        ToUnit(OwenScrambleBase2(SobolDimension1(index), seed_y)));
  }
  return points;
}

std::vector<glm::dvec2> HaltonUnitSquare(int count, uint64_t seed) {
  std::vector<glm::dvec2> points;
  if (count <= 0) return points;
  points.reserve(count);
  const uint64_t seed_x = HashInts(seed, 0x4a102), seed_y = HashInts(seed, 0x4a103);
  for (int i = 0; i < count; ++i) {
    const uint32_t index = static_cast<uint32_t>(i);
    points.emplace_back(ToUnit(OwenScrambleBase2(SobolDimension0(index), seed_x)),
                        OwenScrambledRadicalInverse3(index, seed_y));
  }
  return points;
}

}  // namespace pdsm
