// Platform-independent pseudo-randomness for the sample patterns: a splitmix64 generator and
// a 64-bit hash. std:: distributions are implementation-defined (libstdc++ and libc++ differ),
// so every random choice of a bake goes through these integer functions instead.
#ifndef PDSM_CORE_SAMPLING_HASH_RNG_H_
#define PDSM_CORE_SAMPLING_HASH_RNG_H_

#include <cstdint>

namespace pdsm {

// splitmix64's finalizer (Steele et al. 2014): a bijective 64-bit mixer.
inline uint64_t Mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Hash of a few integers; order matters.
inline uint64_t HashInts(uint64_t a, uint64_t b, uint64_t c = 0, uint64_t d = 0) {
  uint64_t h = Mix64(a + 0x9e3779b97f4a7c15ULL);
  h = Mix64(h ^ (b + 0x632be59bd9b4e019ULL));
  h = Mix64(h ^ (c + 0x8cb92ba72f3d8dd7ULL));
  return Mix64(h ^ (d + 0xd1b54a32d192ed03ULL));
}

class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : state_(seed) {}
  uint64_t Next() { return Mix64(state_ += 0x9e3779b97f4a7c15ULL); }
  // Uniform in [0, 1) with 53 random bits.
  double NextDouble() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }

 private:
  uint64_t state_;
};

}  // namespace pdsm

#endif  // PDSM_CORE_SAMPLING_HASH_RNG_H_
