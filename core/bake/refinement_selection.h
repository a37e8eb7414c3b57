// Which pixels of a baked PDSM need a finer lattice of rays, and over which depths (issue #15
// item 2, adaptive resolution; docs/algorithms.md section 10): pixels between whose rays the
// attenuation at a receiver surface changes by more than a threshold.
//
// Why at the receivers, and only there. Where a penumbra is narrower than a pixel, two
// neighbouring rays disagree on the shadow of the surface between them; a query there blends
// them and misses by up to their difference (contacts, vertical edges). Comparing neighbouring
// rays over all depths would flag every caster silhouette: right behind a surface that is not
// square to the rays, one ray is already inside the caster and the other not yet, a difference
// of 1 over a sliver of depth where nothing can be placed. So a pair is compared where a query
// between them lands: at the depths of the receivers on the ray through the midpoint of the two
// pixel centres. There the slope bias keeps both rays on the lit side of the surface they meet
// (docs/algorithms.md section 3: it covers a pixel's depth change), so they differ only by the
// shadow cast on it. A refined pixel's sub-pixel rays are baked over the receiver windows
// (core/bake/receiver_windows.h) of the pair that holds such a depth (its bands): the bytes go
// where the error was measured, and elsewhere the pixel keeps its function
// (core/pdsm/refined_pixel.h).
//
// Pure functions of the functions and windows given: the same input selects the same pixels,
// and bands, on any machine.
#ifndef PDSM_CORE_BAKE_REFINEMENT_SELECTION_H_
#define PDSM_CORE_BAKE_REFINEMENT_SELECTION_H_

#include <algorithm>
#include <cmath>
#include <span>
#include <utility>
#include <vector>

#include "core/bake/bake_plan.h"
#include "core/bake/receiver_windows.h"
#include "core/pdsm/attenuation_function.h"
#include "core/pdsm/pdsm_geometry.h"

namespace pdsm {

// The difference of attenuation between neighbouring rays at a receiver that a pixel may keep:
// a larger one is refined until each sub-pixel step keeps at most this much, assuming the
// difference spreads evenly (a jump of 0.8 at 0.1: 8x). Measured on the dragon's and
// sun_pillars' contacts (docs/accuracy.md, "Which pixels to refine").
inline constexpr double kRefinementGapThreshold = 0.1;

// The refinement a gap asks for: the smallest power of two f with gap / f <= threshold, at
// most max_refinement (1 for a NaN gap).
int RefinementForGap(double gap, int max_refinement, double threshold = kRefinementGapThreshold);

// What a pixel is refined to, and over which depths.
struct PixelRefinement {
  int factor = 1;                  // 1: not refined
  std::vector<DepthWindow> bands;  // sorted, disjoint; empty when factor is 1
};

// The rectangle one pixel wider on each side, within the map: the pixels whose functions and
// receivers SelectRefinement reads for `rect`.
TileRect GrownByOnePixel(const PdsmGeometry& geometry, const TileRect& rect);

// Sorts `bands` and merges those that overlap or touch.
void MergeBands(std::vector<DepthWindow>* bands);

// Where SelectRefinement compares the pairs of a tile `rect` of `plan`, each over
// GrownByOnePixel(rect): the pixels' receiver windows (ComputeReceiverWindows), and the receiver
// depths on the rays between neighbours (ComputeReceiverWindowsAt a sliver of a pixel around
// them): point (x, y) of `across_x` lies between pixels (x, y) and (x + 1, y), of `across_y`
// between (x, y) and (x, y + 1). REQUIRES: plan.receivers.
struct PairReceivers {
  TileWindows pixels, across_x, across_y;
};
PairReceivers ComputePairReceivers(const BakePlan& plan, const TileRect& rect);

// The refinement of each pixel of `rect`, row-major. Every pair of 4-neighbours with a pixel in
// `rect` is compared at each receiver depth between them (`receivers`, ComputePairReceivers);
// a difference that asks for refinement (RefinementForGap) refines both pixels, by the largest
// factor any of their pairs asks for, over the receiver windows of either pixel that hold that
// depth. `function_at(x, y)` gives the function (std::span<const Vertex>) of any pixel of
// GrownByOnePixel(geometry, rect). REQUIRES: max_refinement is 1, 2, 4 or 8.
template <typename FunctionAt>
std::vector<PixelRefinement> SelectRefinement(const PdsmGeometry& geometry, const TileRect& rect,
                                              int max_refinement, const PairReceivers& receivers,
                                              FunctionAt&& function_at) {
  std::vector<PixelRefinement> out(static_cast<size_t>(rect.width) * rect.height);
  if (max_refinement <= 1) return out;
  const TileRect& grown = receivers.pixels.rect;
  auto inside = [&](int x, int y) {
    return x >= rect.x0 && x < rect.x0 + rect.width && y >= rect.y0 && y < rect.y0 + rect.height;
  };
  auto at = [&](const TileWindows& w, int x, int y) {
    return w.Pixel(static_cast<size_t>(y - grown.y0) * grown.width + (x - grown.x0));
  };
  auto raise = [&](int x, int y, int f, const DepthWindow& band) {
    if (!inside(x, y)) return;
    PixelRefinement& r = out[static_cast<size_t>(y - rect.y0) * rect.width + (x - rect.x0)];
    r.factor = std::max(r.factor, f);
    r.bands.push_back(band);
  };
  // Each pair once: every pixel's right and upper neighbours, from one pixel before the rect.
  for (int y = std::max(0, rect.y0 - 1); y < std::min(geometry.height, rect.y0 + rect.height);
       ++y) {
    for (int x = std::max(0, rect.x0 - 1); x < std::min(geometry.width, rect.x0 + rect.width);
         ++x) {
      const std::span<const Vertex> here = function_at(x, y);
      for (const bool along_x : {true, false}) {
        const int nx = along_x ? x + 1 : x, ny = along_x ? y : y + 1;
        if (nx >= geometry.width || ny >= geometry.height) continue;
        if (!inside(x, y) && !inside(nx, ny)) continue;
        const std::span<const Vertex> there = function_at(nx, ny);
        if (std::equal(here.begin(), here.end(), there.begin(), there.end())) continue;
        for (const DepthWindow& between :
             at(along_x ? receivers.across_x : receivers.across_y, x, y)) {
          const double z = 0.5 * (between.lo + between.hi);
          const double gap = std::abs(static_cast<double>(EvaluateAttenuation(here, z)) -
                                      EvaluateAttenuation(there, z));
          const int f = RefinementForGap(gap, max_refinement);
          if (f == 1) continue;
          DepthWindow band = between;
          for (const std::span<const DepthWindow> pixel :
               {at(receivers.pixels, x, y), at(receivers.pixels, nx, ny)}) {
            for (const DepthWindow& w : pixel) {
              if (w.lo <= z && z <= w.hi) {
                band.lo = std::min(band.lo, w.lo);
                band.hi = std::max(band.hi, w.hi);
              }
            }
          }
          raise(x, y, f, band);
          raise(nx, ny, f, band);
        }
      }
    }
  }
  for (PixelRefinement& r : out) MergeBands(&r.bands);
  return out;
}

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_REFINEMENT_SELECTION_H_
