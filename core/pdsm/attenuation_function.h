// A(z): the fraction of the light hidden from the point at depth z on one PDSM ray.
// Stored as vertices (z, A) with nondecreasing z; two vertices at the same z are a jump.
// Between vertices A is linear; before the first vertex A = 0 (nothing is hidden near the
// light), after the last it keeps the last value. A is right-continuous at a jump: at the
// jump's depth it takes the value after the jump, like "sum of counts at depths <= z".
#ifndef PDSM_CORE_PDSM_ATTENUATION_FUNCTION_H_
#define PDSM_CORE_PDSM_ATTENUATION_FUNCTION_H_

#include <span>

namespace pdsm {

struct Vertex {
  float z;  // light-space depth, world units
  float a;  // attenuation in [0, 1]
  bool operator==(const Vertex&) const = default;
};

// Evaluates A(z) by binary search, clamped to [0, 1]. O(log n).
float EvaluateAttenuation(std::span<const Vertex> function, double z);

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_ATTENUATION_FUNCTION_H_
