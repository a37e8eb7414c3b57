// Compression of attenuation functions (thesis 3.2, after Lokovic & Veach 2000): a greedy
// piecewise-linear fit. From the current origin, keep the interval of slopes whose line passes
// within epsilon of every following vertex; when the next vertex empties it, end the segment
// at the previous vertex's depth with the middle slope and start again there.
//
// Guarantees (tested in compression_test.cc):
//  - Output depths are a subset of the input depths: no event moves.
//  - kVertical: |A'(z) - A(z)| <= epsilon for every z (A' the output, A the input), and
//    output values stay in [0, 1].
//  - kPerpendicular: in the plane (z / depth_scale, A), every input vertex lies within
//    epsilon of the line of the output segment spanning its depth (thesis: steep penumbra
//    steps do not force vertices). Output values stay in [0, 1].
//  - epsilon = 0 is lossless: only exact duplicates are removed.
//  - Jumps larger than 2 epsilon stay jumps (two vertices at one depth); kPerpendicular
//    keeps every jump larger than epsilon.
//  - Exact plateaus stay exact (issue #15): every input vertex whose value is exactly 0 or 1
//    and that bounds a stretch of that value is an output vertex with that value, so a fully
//    lit stretch reads 0 and an umbra reads 1, not within epsilon of them.
#ifndef PDSM_CORE_PDSM_COMPRESSION_H_
#define PDSM_CORE_PDSM_COMPRESSION_H_

#include <span>
#include <vector>

#include "core/pdsm/attenuation_function.h"
#include "core/scene/scene.h"

namespace pdsm {

// REQUIRES: epsilon in [0, 1]; depth_scale > 0 (used by kPerpendicular only);
// `function` sorted by depth.
std::vector<Vertex> CompressFunction(std::span<const Vertex> function, double epsilon,
                                     CompressionMetric metric, double depth_scale);

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_COMPRESSION_H_
