// Emitter-weighted attenuation (issue #15 item 4, docs/algorithms.md "Emitter weighting"):
// each light sample counts by the power it emits toward the point, cos θ_light / r², instead
// of 1/N, normalised over the samples at that point: the fraction of the light's *solid angle*
// hidden (core/reference/light_weighting.h). The receiver's own cosine is left out: a PDSM
// also serves points it has never seen, whose normal nobody knows.
//
// For a planar light (rect, disk, spot) in the PDSM's frame, sample k at (a_k, b_k, 0) and the
// point at depth z on the ray of direction (s, t, 1), with w = 1/z:
//   cos θ_k / r_k² = q_k^(-3/2) / z²,   q_k = (s - a_k w)² + (t - b_k w)² + 1,
// (s - a_k w, t - b_k w) being where the ray lands in sample k's shadow map. The 1/z² cancels:
//   A(z) = Σ_{k hidden at z} q_k^(-3/2) / Σ_k q_k^(-3/2).
// A sun's directions, and a sphere's samples (already spread by solid angle), weigh the same
// under this definition: their bakes stay unweighted and exact.
//
// Between two events the hidden samples stay the same but their shares drift with z, so A is
// no longer a staircase. The function below is sampled at every event and, between events,
// wherever the chord would stray from A by more than a tolerance (a chord is kept when it is
// within half the tolerance at its midpoint, bisecting up to kMaxBisections times), then
// compressed as usual: the stored function is within epsilon + tolerance of A (measured by
// EmitterWeightedFunctionTest on random rays and lights; not a proof).
//
// Exact plateaus stay exact: with no sample hidden A is 0, with all of them 1, whatever the
// weights. Deterministic: the same events and samples give the same bits (fixed summation
// order), so every bake of a scene writes the same file.
#ifndef PDSM_CORE_EVENTS_EMITTER_WEIGHTING_H_
#define PDSM_CORE_EVENTS_EMITTER_WEIGHTING_H_

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "core/events/event.h"
#include "core/pdsm/attenuation_function.h"

namespace pdsm {

// Chords between events are halved at most this many times (1/1024 of the interval).
inline constexpr int kMaxBisections = 10;

// The tolerance of the piecewise-linear A for compression tolerance `epsilon`: a quarter of
// it, kept within [2^-14, 2^-8] so that a lossless bake (epsilon 0) stays finite and a coarse
// one keeps the weighting's own effect (differences of 0.01-0.06 from unweighted).
double EmitterTolerance(double epsilon);

// The step an emitter-weighted function's values are rounded to once compressed: the largest
// power of two at most tolerance / 4, so that rounding errs by at most tolerance / 8 (within
// the tolerance's budget: the stored function stays within epsilon + tolerance of A). Weighted
// values are not multiples of 1/N: their low mantissa bits are noise the file's ZIP cannot
// pack (plates at ε 0.01: 2.60 MB unrounded, 1.59 MB rounded; unweighted 1.77 MB).
double EmitterQuantum(double tolerance);

// Rounds every finite attenuation to a multiple of `quantum` (0 and 1 stay exact, NaN stays
// NaN). REQUIRES: quantum a power of two.
void RoundAttenuation(double quantum, std::vector<Vertex>* vertices);

// One ray's weights. Not thread-safe (it keeps the hidden set); one per thread.
class EmitterRay {
 public:
  // `samples`: the light's samples (a_k, b_k), light-space units, the bake's order; the
  // first `total_samples` of them weigh (adaptive tiles use a prefix); they are copied.
  // REQUIRES: 1 <= total_samples <= samples.size().
  EmitterRay(std::span<const glm::dvec2> samples, int total_samples);

  // Points the ray at direction (s, t, 1) and clears the hidden set.
  void SetRay(double s, double t);

  // Clears the hidden set (every sample lit), keeping the ray.
  void ClearHidden();

  // Applies one kSampleKeys event. Returns whether the sample's state changed: a repeated
  // entry or exit changes nothing, nor does an event of a sample past total_samples.
  bool Apply(const Event& e);

  // A at depth z (> 0) with the current hidden set, summed over every sample: O(samples).
  double Attenuation(double z) const;

  // Every sample's weight q_k^(-3/2) at w = 1/z into weights[0, total); returns their sum.
  double Weights(double w, double* weights) const;

  bool is_hidden(int sample) const { return hidden_[sample] != 0; }
  int hidden() const { return hidden_count_; }
  int total() const { return total_; }

 private:
  int total_;
  double s_ = 0, t_ = 0;
  std::vector<double> a_, b_;   // the samples' coordinates, apart (the sums vectorize)
  std::vector<double> hidden_;  // per sample: 1 while it is hidden, else 0
  int hidden_count_ = 0;
};

// The uncompressed A of one ray of an emitter-weighted bake from its consolidated kSampleKeys
// events: for every depth with events, (z, A before) and (z, A after), and between events and
// after the last (up to z_end, where A is then held) the vertices the tolerance needs. Empty
// for no events. `ray` has been SetRay for this pixel. REQUIRES: events sorted by depth, their
// depths > 0.
std::vector<Vertex> EmitterWeightedFunction(std::span<const Event> events, EmitterRay* ray,
                                            double z_end, double tolerance);

// The same on one window [lo, hi) of the ray (a surfaces-only bake): (lo, A(lo)) with every
// event at or before lo applied, the events inside with the vertices between, (hi, A(hi-)).
// REQUIRES: 0 < lo < hi.
std::vector<Vertex> EmitterWeightedPiece(std::span<const Event> events, EmitterRay* ray, double lo,
                                         double hi, double tolerance);

}  // namespace pdsm

#endif  // PDSM_CORE_EVENTS_EMITTER_WEIGHTING_H_
