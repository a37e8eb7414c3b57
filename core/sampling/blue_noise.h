// Blue-noise light samples: Mitchell's best-candidate algorithm (1991) with a fixed number
// of candidates per point. Each new point is, of kBestCandidateTries uniform candidates, the
// one farthest (on the torus) from the points already placed, so points keep apart like a
// Poisson-disk set and the sequence is progressive: its first n points do not depend on how
// many come after (adaptive sampling uses prefixes).
// Cost O(n log n): nearest-neighbour queries walk rings of a uniform grid sized for the final
// count. Coordinates and distances are 32-bit fixed point and 64-bit integers, so the points
// are identical on every platform (no floating-point contraction or rounding differences).
#ifndef PDSM_CORE_SAMPLING_BLUE_NOISE_H_
#define PDSM_CORE_SAMPLING_BLUE_NOISE_H_

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

namespace pdsm {

inline constexpr int kBestCandidateTries = 16;

// Points in [0,1)^2.
std::vector<glm::dvec2> BlueNoiseUnitSquare(int count, uint64_t seed);

}  // namespace pdsm

#endif  // PDSM_CORE_SAMPLING_BLUE_NOISE_H_
