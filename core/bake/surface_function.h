// The stored function of one pixel of a surfaces-only bake (docs/pdsm_format.md, "Surfaces-
// only files"): A(z) inside the pixel's depth windows, NaN between and around them. Built from
// the pixel's consolidated events, each window compressed on its own.
#ifndef PDSM_CORE_BAKE_SURFACE_FUNCTION_H_
#define PDSM_CORE_BAKE_SURFACE_FUNCTION_H_

#include <span>
#include <vector>

#include "core/bake/receiver_windows.h"
#include "core/events/emitter_weighting.h"
#include "core/events/event.h"
#include "core/pdsm/attenuation_function.h"
#include "core/scene/scene.h"

namespace pdsm {

// No events: no vertex (A = 0 everywhere, exact inside the windows). Otherwise
//   (kUndefinedFrom, NaN), then per window [lo, hi): (lo, A(lo)), the compressed jumps inside,
//   (hi, A(hi-)), (hi, NaN).
// A is right-continuous, so a window is defined on [lo, hi).
// REQUIRES: `events` consolidated; `windows` sorted and disjoint; compression arguments as
// CompressFunction's.
std::vector<Vertex> SurfaceFunction(std::span<const Event> events,
                                    std::span<const DepthWindow> windows, int total_samples,
                                    double epsilon, CompressionMetric metric, double depth_scale);

// The same for an emitter-weighted bake (consolidated kSampleKeys events): each window's piece
// is EmitterWeightedPiece's, within `tolerance`, then compressed. `ray` points at the pixel.
std::vector<Vertex> EmitterSurfaceFunction(std::span<const Event> events,
                                           std::span<const DepthWindow> windows, EmitterRay* ray,
                                           double tolerance, double epsilon,
                                           CompressionMetric metric, double depth_scale);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_SURFACE_FUNCTION_H_
