// Fast emitter-weighted attenuation along one ray (core/events/emitter_weighting.h): A(z) with
// the ray's hidden set, in O(1) per event and per evaluation instead of O(samples).
//
// Each sample's share of the light, φ_k(w) = q_k(w)^(-3/2) / Σ_j q_j(w)^(-3/2) (w = 1/z), is a
// smooth function of w: the zeros of q_k lie at least 1 / |(a_k, b_k)| off the real axis,
// while a ray's depths usually span a far shorter stretch of w. So on a piece of the ray's w-range
// every share is a Chebyshev series of kChebyshevTerms terms, and A = Σ_{k hidden} φ_k is the
// series whose coefficients are the hidden samples' sums, kept up to date event by event.
//
// Pieces are made on demand by halving the w-range until every share's interpolant is within
// the tolerance, summed over all samples (so whichever samples are hidden, A is): checked at
// the points halfway between the interpolation nodes. A piece still too coarse after
// kMaxShareSplits halvings is evaluated exactly. With no sample hidden A is 0 and with all of
// them 1, exactly. Deterministic: same events, samples and ray give the same bits.
#ifndef PDSM_CORE_EVENTS_EMITTER_SHARES_H_
#define PDSM_CORE_EVENTS_EMITTER_SHARES_H_

#include <vector>

#include "core/events/emitter_weighting.h"

namespace pdsm {

// 4 terms, halving more often where they do not suffice, beat 6 and 8 (assembly thread-s on
// plates 0.108 / 0.141 / 0.173, on the dragon 0.435 / 0.556 / 0.652: docs/performance.md).
inline constexpr int kChebyshevTerms = 4;
inline constexpr int kMaxShareSplits = 8;

// Not thread-safe. Holds `ray`, which must outlive it; its hidden set moves only through Apply.
class EmitterShares {
 public:
  // Depths to be evaluated lie in [z_near, z_far] (0 < z_near <= z_far); the interpolants stay
  // within `tolerance` of the exact A there (see above). `exact`: evaluate every depth exactly
  // (O(samples) each), cheaper for a ray of a few events than making any interpolant.
  EmitterShares(EmitterRay* ray, double z_near, double z_far, double tolerance, bool exact);

  // Applies one event to the ray's hidden set (EmitterRay::Apply).
  void Apply(const Event& e);

  // A at depth z in [z_near, z_far].
  double At(double z);

  int hidden() const { return ray_->hidden(); }
  int total() const { return ray_->total(); }

 private:
  struct Piece {
    int level = 0, index = 0;  // the piece is the index-th of 2^level equal parts of the range
    bool split = false;        // too coarse: its halves hold the answer
    bool exact = false;        // too coarse at the last level: evaluated exactly
    double w0 = 0, w1 = 0;
    std::vector<double> coefficients;  // kChebyshevTerms per sample, sample-major
  };

  // The leaf piece holding w, made (with its ancestors) when first needed.
  int Locate(double w);
  Piece Make(int level, int index) const;
  // The hidden samples' coefficient sums of piece `current_`.
  void SumHidden();

  EmitterRay* ray_;
  double w_lo_, w_hi_;
  double tolerance_;
  bool exact_;
  std::vector<Piece> pieces_;
  int current_ = -1;  // the piece whose sums `sums_` holds
  double sums_[kChebyshevTerms] = {};
};

}  // namespace pdsm

#endif  // PDSM_CORE_EVENTS_EMITTER_SHARES_H_
