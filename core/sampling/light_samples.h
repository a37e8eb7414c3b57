// Light samples (thesis 3.1): where on the light each shadow map is rendered from.
// Rect and disk: offsets (a, b) on the light plane, light-space units. Sun: direction slopes
// (a, b), the sample direction being (a, b, 1) in light space.
// Every sample stands for the same share of the light (equal-area cells), so the attenuation
// is a plain count / N.
#ifndef PDSM_CORE_SAMPLING_LIGHT_SAMPLES_H_
#define PDSM_CORE_SAMPLING_LIGHT_SAMPLES_H_

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "core/scene/scene.h"

namespace pdsm {

// Points in [0,1)^2, one per cell of an equal-area partition: n rows, row r holding k_r cells
// of height k_r / count, so any count (primes too) is stratified without bias.
std::vector<glm::dvec2> StratifiedUnitSquare(int count, uint64_t seed);

// Independent uniform points in [0,1)^2.
std::vector<glm::dvec2> UniformUnitSquare(int count, uint64_t seed);

// The pattern's points in [0,1)^2 (core/sampling/low_discrepancy.h, blue_noise.h).
std::vector<glm::dvec2> UnitSquareSamples(int count, SamplingPattern pattern, uint64_t seed);

// Whether every prefix of the pattern's sequence is itself a well-spread set (Sobol, Halton,
// blue noise, uniform), so that a tile may use only the first n samples (adaptive sampling).
// Stratified is not: its first cells fill the bottom rows of the light.
inline bool IsProgressive(SamplingPattern pattern) {
  return pattern != SamplingPattern::kStratified;
}

// Shirley–Chiu concentric map of [0,1)^2 onto the unit disk; preserves area fractions.
glm::dvec2 ConcentricDisk(const glm::dvec2& u);

// The bake's samples. Deterministic in (light, count, pattern, seed) on every platform.
std::vector<glm::dvec2> GenerateLightSamples(const LightSpec& light, int count,
                                             SamplingPattern pattern, uint64_t seed);

}  // namespace pdsm

#endif  // PDSM_CORE_SAMPLING_LIGHT_SAMPLES_H_
