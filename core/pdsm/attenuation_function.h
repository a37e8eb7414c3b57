// A(z): the fraction of the light hidden from the point at depth z on one PDSM ray.
// Stored as vertices (z, A) with nondecreasing z; two vertices at the same z are a jump.
// Between vertices A is linear; before the first vertex A = 0 (nothing is hidden near the
// light), after the last it keeps the last value. A is right-continuous at a jump: at the
// jump's depth it takes the value after the jump, like "sum of counts at depths <= z".
// A is NaN where it is undefined: surfaces-only files (format version 2, docs/pdsm_format.md
// "Surfaces-only files") bracket each receiver window with NaN vertices, and interpolating
// from or to a NaN vertex gives NaN. (Depths nearer than the header's z_valid_min are
// outside the PDSM altogether: the query refuses them before any function is read.)
#ifndef PDSM_CORE_PDSM_ATTENUATION_FUNCTION_H_
#define PDSM_CORE_PDSM_ATTENUATION_FUNCTION_H_

#include <span>

namespace pdsm {

struct Vertex {
  float z;  // light-space depth, world units; finite
  float a;  // attenuation in [0, 1], or NaN (undefined: surfaces-only windows' brackets)
  bool operator==(const Vertex&) const = default;
};

// The depth of the vertex that opens a function defined only in windows (a surfaces-only
// function, a refined pixel's sub-function): the lowest float, so that every depth before the
// first window evaluates to NaN (EvaluateAttenuation interpolates from a NaN vertex).
inline constexpr float kUndefinedFrom = -3.40282347e+38f;

// Evaluates A(z) by binary search. O(log n). Finite values are clamped to [0, 1] (a
// compressed function may overshoot; the true one never does); NaN stays NaN: a NaN vertex
// at or around z makes the result NaN.
float EvaluateAttenuation(std::span<const Vertex> function, double z);

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_ATTENUATION_FUNCTION_H_
