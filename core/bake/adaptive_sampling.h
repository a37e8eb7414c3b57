// Adaptive sampling (the thesis' future work, docs/algorithms.md "Adaptive sampling"): a tile
// stops taking light samples once its attenuation has converged. The samples form a
// progressive sequence (Sobol, Halton, blue noise), so a tile baked with n samples uses the
// first n of the bake's samples. A tile is baked in stages whose sample ranges double:
//
//   stage 0 (pilot): [0, h) and [h, 2h), h = ceil(min_samples / 2)
//   stage k >= 1:    [2^k h, 2^(k+1) h)          the last range capped at the bake's samples
//
// After each stage, with N samples so far, the tile's error is estimated by the split-half
// difference max |A_N(z) - A_{N/2}(z)| over its pixels (ErrorEstimate below); the tile is
// done when it is at most the tolerance or N reached the maximum. The decision reads only
// merged event counts, which are exact integers whatever the batches, their order, the
// threads or the workers, so the file stays byte-identical.
#ifndef PDSM_CORE_BAKE_ADAPTIVE_SAMPLING_H_
#define PDSM_CORE_BAKE_ADAPTIVE_SAMPLING_H_

#include <span>
#include <vector>

#include "core/events/event.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

struct SampleRange {
  int begin = 0, end = 0;  // [begin, end) of the bake's samples
};

// The ranges of stage `stage` (two for the pilot, one after, none past the last stage).
// REQUIRES: 1 <= min_samples <= max_samples.
std::vector<SampleRange> AdaptiveStageRanges(int stage, int min_samples, int max_samples);

// Depth intervals of a function shorter than this fraction of the PDSM's depth range are a
// surface's thickness as the shadow maps see it (texel footprint, bias), not light-sampling
// error: the estimate skips them.
inline constexpr double kAdaptiveSurfaceDepthFraction = 1.0 / 256.0;

// Split-half error estimate of one tile: `first` holds the events of samples [0, n1),
// `second` those of [n1, n1 + n2). Returns the largest |A_{n1+n2}(z) - A_{n1}(z)|
// = n2 / (n1 + n2) * |A_second(z) - A_first(z)| over every pixel and every depth interval
// between events at least `min_interval` long (the last interval, to infinity, always counts).
// Sample-keyed events (an emitter-weighted bake) are judged by their unweighted counts: the
// weights only tilt shares the samples already resolve.
// REQUIRES: both have the same tile geometry; n1, n2 >= 1.
double SplitHalfError(const TileEvents& first, int n1, const TileEvents& second, int n2,
                      double min_interval, EventKeying keying);

// Judges a tile after one stage: the one decision the local bake and the service share, so
// their files stay byte-identical. `ranges`: the stage's AdaptiveStageRanges; `stage_results`:
// the merged events of each of those ranges, in the same order; `earlier`: the tile's events
// of all earlier stages (any number of lists). Returns whether the tile is done (estimate
// <= header.adaptive_tolerance, or the last range reached header.samples). On return
// `earlier` holds one merged list of every sample so far.
// REQUIRES: ranges.size() == stage_results.size() >= 1; header.adaptive().
bool JudgeAdaptiveStage(const PdsmHeader& header, const std::vector<SampleRange>& ranges,
                        std::vector<TileEvents> stage_results, std::vector<TileEvents>* earlier);

// The per-pixel part of SplitHalfError.
double SplitHalfPixelError(std::span<const Event> first, int n1, std::span<const Event> second,
                           int n2, double min_interval, EventKeying keying);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_ADAPTIVE_SAMPLING_H_
