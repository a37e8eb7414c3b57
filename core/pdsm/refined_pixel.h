// A refined pixel (format version 3, docs/pdsm_format.md "Refined pixels"; issue #15 item 2):
// where a penumbra is narrower than a pixel, the pixel keeps its own function and adds, over a
// few depth bands, the functions of an f x f lattice of sub-pixel rays (f = 2, 4 or 8), in its
// own deep samples (every index sample has attenuation -1, below any stored A, which never goes
// below -epsilon):
//
//   sample 0                 (z = f * f, a = -f)  the marker: attenuation -f <= -2
//   sample 1                 (z = B, a = -1)      the number of bands
//   samples 2 .. 2B + 1      (z = lo_k), (z = hi_k)  band k: [lo_k, hi_k], sorted, disjoint
//   the next f * f + 1       (z = end_m)          function m's end, counted in vertices from the
//                                                 first after them: m = 0 is the pixel's own
//                                                 function, m = 1 + k sub-function k, k = i + f*j
//                                                 for sub-pixel (i, j), row-major like pixels
//   the rest                 function 0's vertices, then 1's, ...: each an ordinary function
//
// Sub-pixel (i, j) of pixel (x, y) is the ray through (x + (i + 0.5) / f, y + (j + 0.5) / f) in
// pixel coordinates. The pixel is refined at the depths of its bands. Sub-functions are defined
// only in depth windows inside the bands (NaN-bracketed, as surfaces-only functions are): the
// bake keeps them around the receivers within a sub-pixel of each ray; a sub-function without
// vertex is defined nowhere, and where a sub-function is undefined its pixel's own function
// stands in for it. Counts and ends are integers below 2^24, exact in a float.
#ifndef PDSM_CORE_PDSM_REFINED_PIXEL_H_
#define PDSM_CORE_PDSM_REFINED_PIXEL_H_

#include <span>
#include <string>
#include <vector>

#include "core/pdsm/attenuation_function.h"

namespace pdsm {

// The refinements a file may hold: 1 (none), 2, 4, 8.
inline constexpr int kLargestRefinement = 8;
inline bool IsRefinementFactor(int f) { return f == 1 || f == 2 || f == 4 || f == 8; }

// A refined pixel's depth band, light-space z: [lo, hi].
struct RefinedBand {
  float lo = 0, hi = 0;
};

// The refinement of a pixel's samples: f for a refined pixel, 1 for an ordinary function. Only
// looks at the marker: REQUIRES samples a reader has checked (PixelFunctionFault).
inline int RefinementOf(std::span<const Vertex> samples) {
  return !samples.empty() && samples[0].a <= -2.0f ? static_cast<int>(-samples[0].a) : 1;
}

// Function m (0: the pixel's own, 1 + k: sub-function k) of a refined pixel of refinement f.
std::span<const Vertex> RefinedFunction(std::span<const Vertex> samples, int f, size_t m);

// The pixel's own function: the samples of an ordinary pixel, function 0 of a refined one.
inline std::span<const Vertex> OwnFunction(std::span<const Vertex> samples) {
  const int f = RefinementOf(samples);
  return f == 1 ? samples : RefinedFunction(samples, f, 0);
}

// Sub-function (i, j), 0 <= i, j < f, of a refined pixel of refinement f.
inline std::span<const Vertex> SubFunction(std::span<const Vertex> samples, int f, int i, int j) {
  return RefinedFunction(samples, f, 1 + static_cast<size_t>(i) + static_cast<size_t>(f) * j);
}

// Whether the pixel is refined at depth z: refined, and z in one of its bands.
bool RefinedAt(std::span<const Vertex> samples, double z);

// Appends a refined pixel of refinement f over `bands`, with the pixel's own function `own` and
// the f * f sub-functions `subs` (row-major), to `out`. REQUIRES: f is 2, 4 or 8; bands sorted,
// disjoint, not empty; subs.size() == f * f, each defined only inside the bands.
void AppendRefinedPixel(int f, std::span<const RefinedBand> bands, std::span<const Vertex> own,
                        std::span<const std::vector<Vertex>> subs, std::vector<Vertex>* out);

// What is wrong with a pixel's samples, or "" when nothing is: an ordinary function's depths
// must be nondecreasing and not NaN; a refined pixel (marker at sample 0) must have a factor of
// 2, 4 or 8 no larger than `max_refinement`, sorted bands, nondecreasing ends that span its
// samples, and functions that are ordinary functions. `max_refinement` 1 reads every pixel as an
// ordinary function (files before version 3).
std::string PixelFunctionFault(std::span<const Vertex> samples, int max_refinement);

// A of sub-pixel (i, j) of a pixel of refinement f > 1 at depth z: NaN where its sub-function is
// not defined (no vertex, or off its windows).
double SubPixelAttenuation(std::span<const Vertex> samples, int f, int i, int j, double z);

// A of the point of the lattice of sub-pixels of refinement f that lies in this pixel at
// sub-pixel (i, j) of that lattice (0 <= i, j < f): a pixel refined at z by f reads that
// sub-pixel, one refined by g < f the sub-pixel of its own lattice holding the point, each with
// the pixel's own function where the sub-function is undefined; any other pixel reads its own
// function. `*sub_defined` (optional) is set when a sub-function gave the value.
double LatticeAttenuation(std::span<const Vertex> samples, int f, int i, int j, double z,
                          bool* sub_defined = nullptr);

// A of the pixel at its centre and depth z, as a query there reads it
// (core/pdsm/pdsm_query.h): EvaluateAttenuation for an ordinary function; for a refined one,
// where one of its four central sub-pixels (f is even) is defined at z, their mean, each
// undefined one with the pixel's own function; elsewhere its own function's.
double EvaluatePixelCentre(std::span<const Vertex> samples, double z);

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_REFINED_PIXEL_H_
