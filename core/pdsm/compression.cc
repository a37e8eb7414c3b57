#include "core/pdsm/compression.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace pdsm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Output values are stored as float: shrink the tolerance by float's rounding of values in
// [0, 1] so the stored result still meets epsilon.
double StoredTolerance(double epsilon) { return std::max(0.0, epsilon - 0x1.0p-23); }

std::vector<Vertex> RemoveDuplicates(std::span<const Vertex> function) {
  std::vector<Vertex> out;
  for (const Vertex& v : function) {
    if (out.empty() || !(out.back() == v)) out.push_back(v);
  }
  return out;
}

// The admissible set of lines through the origin, as an interval of a line parameter:
// slope for kVertical, angle in (z / depth_scale, A) for kPerpendicular.
class LineCone {
 public:
  LineCone(CompressionMetric metric, double tolerance, double depth_scale)
      : metric_(metric), tolerance_(tolerance), inv_scale_(1.0 / depth_scale) {}

  void Reset(double z, double a) {
    z0_ = z;
    a0_ = a;
    lo_ = -kInf;
    hi_ = kInf;
  }
  double origin_z() const { return z0_; }
  double origin_a() const { return a0_; }

  // Narrows the cone to lines passing within tolerance of (z, a), z > origin (exactly through
  // it when `exact`); false (and no change) when that would leave no line.
  bool Admit(double z, double a, bool exact = false) {
    const double tolerance = exact ? 0.0 : tolerance_;
    double lo, hi;
    const double dz = z - z0_;
    if (metric_ == CompressionMetric::kVertical) {
      // The window is clipped to [0, 1] so the line never leaves the range of attenuation;
      // clamping a segment's end afterwards would bend it and break the bound.
      lo = (std::max(a - tolerance, 0.0) - a0_) / dz;
      hi = (std::min(a + tolerance, 1.0) - a0_) / dz;
    } else {
      const double dzn = dz * inv_scale_;
      const double da = a - a0_;
      const double dist = std::hypot(dzn, da);
      constexpr double kSteepest = std::numbers::pi / 2 - 1e-9;
      // As for kVertical, the line must stay in [0, 1] at every vertex it covers.
      lo = std::max(std::atan2(0.0 - a0_, dzn), -kSteepest);
      hi = std::min(std::atan2(1.0 - a0_, dzn), kSteepest);
      if (dist > tolerance) {
        const double angle = std::clamp(std::atan2(da, dzn), -kSteepest, kSteepest);
        const double half = std::asin(tolerance / dist);
        lo = std::max(lo, angle - half);
        hi = std::min(hi, angle + half);
      }
    }
    lo = std::max(lo, lo_);
    hi = std::min(hi, hi_);
    if (lo > hi) return false;
    lo_ = lo;
    hi_ = hi;
    return true;
  }

  // Value of the middle admissible line at depth z.
  double ValueAt(double z) const {
    if (lo_ == -kInf) return a0_;  // unconstrained: flat
    const double mid = 0.5 * (lo_ + hi_);
    if (metric_ == CompressionMetric::kVertical) return a0_ + mid * (z - z0_);
    return a0_ + std::tan(mid) * (z - z0_) * inv_scale_;
  }

 private:
  CompressionMetric metric_;
  double tolerance_;
  double inv_scale_;
  double z0_ = 0, a0_ = 0;
  double lo_ = -kInf, hi_ = kInf;
};

// Exact plateaus (issue #15): a stretch where A is exactly 0 (fully lit) or exactly 1 (umbra)
// is bounded by vertices of that exact value; those are kept as they are, so that the stretch
// stays exact instead of being lifted or lowered by up to epsilon. A vertex inside a plateau
// (its neighbours of the same value) is not needed: the segment between the plateau's ends,
// both exact, is flat.
bool Pinned(std::span<const Vertex> function, size_t i) {
  const float a = function[i].a;
  if (a != 0.0f && a != 1.0f) return false;
  return i == 0 || i + 1 == function.size() || function[i - 1].a != a || function[i + 1].a != a;
}

}  // namespace

std::vector<Vertex> CompressFunction(std::span<const Vertex> function, double epsilon,
                                     CompressionMetric metric, double depth_scale) {
  if (epsilon <= 0.0 || function.size() <= 2) return RemoveDuplicates(function);
  std::vector<Vertex> out;
  out.push_back(function[0]);
  LineCone cone(metric, StoredTolerance(epsilon), depth_scale);
  cone.Reset(function[0].z, function[0].a);
  size_t last_admitted = 0;   // index of the last input vertex the current segment covers
  size_t first_at_depth = 0;  // first input vertex at the depth of function[i]
  // A pinned vertex ends its segment with its own value: the cone holds only lines through it.
  auto emit_segment_end = [&](size_t index) {
    const double z = function[index].z;
    const float a =
        Pinned(function, index) ? function[index].a : static_cast<float>(cone.ValueAt(z));
    out.push_back(Vertex{function[index].z, a});
    cone.Reset(z, a);
  };
  for (size_t i = 1; i < function.size();) {
    const Vertex& v = function[i];
    if (static_cast<double>(v.z) == cone.origin_z()) {
      // A jump at the origin's depth: within tolerance it is absorbed, else it stays a jump;
      // a jump to an exact 0 or 1 always stays.
      if (std::abs(v.a - cone.origin_a()) > StoredTolerance(epsilon) ||
          (Pinned(function, i) && v.a != cone.origin_a())) {
        out.push_back(v);
        cone.Reset(v.z, v.a);
      }
      last_admitted = i++;
      continue;
    }
    // A jump may be spread over several vertices at one depth: track where the run starts.
    if (v.z != function[i - 1].z) first_at_depth = i;
    if (metric == CompressionMetric::kPerpendicular && last_admitted == i - 1 &&
        first_at_depth < i &&
        std::abs(v.a - function[first_at_depth].a) > StoredTolerance(epsilon)) {
      // A jump inside the segment: a near-vertical line would pass within the perpendicular
      // tolerance of both its ends and turn it into a ramp. End the segment, keep the jump.
      emit_segment_end(last_admitted);
      out.push_back(v);
      cone.Reset(v.z, v.a);
      last_admitted = i++;
      continue;
    }
    if (Pinned(function, i)) {
      // Kept exactly: the segment ends there if a line through it fits, else at the last
      // vertex admitted, and v is retried from there (a fresh cone always admits one point).
      if (cone.Admit(v.z, v.a, /*exact=*/true)) {
        emit_segment_end(i);
        last_admitted = i++;
        continue;
      }
    } else if (cone.Admit(v.z, v.a)) {
      last_admitted = i++;
      continue;
    }
    if (static_cast<double>(function[last_admitted].z) == cone.origin_z()) {
      // Nothing spans depth yet (only the perpendicular metric's clamp gets here): keep v.
      out.push_back(v);
      cone.Reset(v.z, v.a);
      last_admitted = i++;
      continue;
    }
    emit_segment_end(last_admitted);  // i is retried from the new origin
  }
  if (static_cast<double>(function[last_admitted].z) != cone.origin_z()) {
    emit_segment_end(last_admitted);
  }
  return out;
}

}  // namespace pdsm
