// Randomized low-discrepancy point sets for light sampling: Owen-scrambled Sobol and
// Owen-scrambled Halton. Both are *progressive*: the first n points of a sequence are a good
// set on their own, for every n, which adaptive sampling relies on (a tile uses a prefix of the
// bake's samples). Scrambling keeps the sequences' stratification (every elementary interval
// still holds its share of points) while making each estimate unbiased, with a seed chosen
// per bake. Everything is integer arithmetic: identical points on every platform.
#ifndef PDSM_CORE_SAMPLING_LOW_DISCREPANCY_H_
#define PDSM_CORE_SAMPLING_LOW_DISCREPANCY_H_

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

namespace pdsm {

// The first two dimensions of Sobol's sequence (van der Corput in base 2 and its Pascal-matrix
// companion, together a (0,2)-sequence in base 2), each dimension Owen-scrambled (nested
// uniform scrambling) by hashing (seed, dimension, level, prefix). Points in [0,1)^2.
std::vector<glm::dvec2> SobolUnitSquare(int count, uint64_t seed);

// Halton's sequence in bases 2 and 3, each dimension Owen-scrambled: digit d of the radical
// inverse is permuted by a permutation chosen by hashing (seed, dimension, d, the digits
// before d). Points in [0,1)^2.
std::vector<glm::dvec2> HaltonUnitSquare(int count, uint64_t seed);

// Owen scrambling of a 32-bit binary fraction x / 2^32; exposed for tests.
uint32_t OwenScrambleBase2(uint32_t x, uint64_t seed);

}  // namespace pdsm

#endif  // PDSM_CORE_SAMPLING_LOW_DISCREPANCY_H_
