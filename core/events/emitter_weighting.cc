#include "core/events/emitter_weighting.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "core/events/emitter_shares.h"

namespace pdsm {

double EmitterTolerance(double epsilon) { return std::clamp(epsilon / 4, 0x1.0p-14, 0x1.0p-8); }

double EmitterQuantum(double tolerance) { return std::exp2(std::floor(std::log2(tolerance / 4))); }

void RoundAttenuation(double quantum, std::vector<Vertex>* vertices) {
  for (Vertex& v : *vertices) {
    v.a = static_cast<float>(std::nearbyint(v.a / quantum) * quantum);  // NaN stays NaN
  }
}

EmitterRay::EmitterRay(std::span<const glm::dvec2> samples, int total_samples)
    : total_(total_samples) {
  assert(total_samples >= 1 && static_cast<size_t>(total_samples) <= samples.size());
  a_.resize(total_);
  b_.resize(total_);
  for (int k = 0; k < total_; ++k) a_[k] = samples[k].x, b_[k] = samples[k].y;
  hidden_.assign(total_, 0.0);
}

void EmitterRay::SetRay(double s, double t) {
  s_ = s;
  t_ = t;
  ClearHidden();
}

void EmitterRay::ClearHidden() {
  std::fill(hidden_.begin(), hidden_.end(), 0.0);
  hidden_count_ = 0;
}

bool EmitterRay::Apply(const Event& e) {
  const int k = SampleOfEvent(e);
  if (k < 0 || k >= total_) return false;  // not this ray's samples: never written out of bounds
  const double now = e.count > 0 ? 1.0 : 0.0;
  if (hidden_[k] == now) return false;  // not for alternating events; keeps the count true
  hidden_[k] = now;
  hidden_count_ += e.count > 0 ? 1 : -1;
  return true;
}

double EmitterRay::Weights(double w, double* weights) const {
  double all = 0;
  for (int k = 0; k < total_; ++k) {
    const double u = s_ - a_[k] * w, v = t_ - b_[k] * w;
    const double q = u * u + v * v + 1.0;
    weights[k] = 1.0 / (q * std::sqrt(q));
    all += weights[k];
  }
  return all;
}

double EmitterRay::Attenuation(double z) const {
  if (hidden_count_ == 0) return 0.0;
  if (hidden_count_ == total_) return 1.0;
  const double w = 1.0 / z;
  double all = 0, hidden = 0;
  // (s - a w, t - b w): where the ray meets sample k's shadow map; its weight q^(-3/2).
  for (int k = 0; k < total_; ++k) {
    const double u = s_ - a_[k] * w, v = t_ - b_[k] * w;
    const double q = u * u + v * v + 1.0;
    const double weight = 1.0 / (q * std::sqrt(q));
    all += weight;
    hidden += hidden_[k] * weight;
  }
  return hidden / all;
}

namespace {

// Builds one function's vertices along a ray, moving its hidden set event by event. A is
// read from the shares' interpolants, within a quarter of the tolerance; the chords take the
// rest.
class FunctionBuilder {
 public:
  FunctionBuilder(EmitterRay* ray, double z_near, double z_far, size_t events, double tolerance,
                  std::vector<Vertex>* out)
      : shares_(ray, z_near, z_far, 0.25 * tolerance, FewEvents(events)),
        tolerance_(tolerance),
        out_(out) {}

  double At(double z) { return shares_.At(z); }

  void Push(double z, double a) {
    out_->push_back(Vertex{static_cast<float>(z), static_cast<float>(a)});
  }

  // Pushes the vertices strictly between (z0, a0) and (z1, a1) that keep the chords within the
  // tolerance of A at their midpoints, for the current hidden set.
  void Between(double z0, double a0, double z1, double a1, int depth = 0) {
    if (shares_.hidden() == 0 || shares_.hidden() == shares_.total()) return;  // A is constant
    if (depth >= kMaxBisections) return;
    const double zm = 0.5 * (z0 + z1);
    // Depths are stored as floats: no room for a vertex between.
    if (!(static_cast<float>(zm) > static_cast<float>(z0) &&
          static_cast<float>(zm) < static_cast<float>(z1))) {
      return;
    }
    const double am = At(zm);
    // A third of the tolerance at the midpoint: a chord strays most near it, but not exactly
    // there, and A itself is read within a quarter.
    if (std::abs(am - 0.5 * (a0 + a1)) <= tolerance_ / 3) return;
    Between(z0, a0, zm, am, depth + 1);
    Push(zm, am);
    Between(zm, am, z1, a1, depth + 1);
  }

  // Applies the events at events[*i]'s depth and moves *i past them.
  void ApplyDepth(std::span<const Event> events, size_t* i) {
    const float z = events[*i].z;
    for (; *i < events.size() && events[*i].z == z; ++*i) shares_.Apply(events[*i]);
  }

  bool Varies() const { return shares_.hidden() != 0 && shares_.hidden() != shares_.total(); }

 private:
  // A ray of a few events costs less evaluated exactly (O(samples) per depth) than making
  // the shares' interpolants (2 kChebyshevTerms - 1 such sums at least).
  static bool FewEvents(size_t events) { return 3 * events <= 2 * kChebyshevTerms; }

  EmitterShares shares_;
  double tolerance_;
  std::vector<Vertex>* out_;
};

}  // namespace

std::vector<Vertex> EmitterWeightedFunction(std::span<const Event> events, EmitterRay* ray,
                                            double z_end, double tolerance) {
  std::vector<Vertex> out;
  if (events.empty()) return out;
  out.reserve(2 * events.size());
  ray->ClearHidden();
  const double z_far = std::max<double>(z_end, events.back().z);
  FunctionBuilder f(ray, events.front().z, z_far, events.size(), tolerance, &out);
  double before = 0.0;  // A just before the next depth with events
  for (size_t i = 0; i < events.size();) {
    const double z = events[i].z;
    f.ApplyDepth(events, &i);
    const double after = f.At(z);
    f.Push(z, before);
    f.Push(z, after);
    if (i < events.size()) {
      const double next = events[i].z;
      before = f.At(next);
      f.Between(z, after, next, before);
    } else if (z_end > z && f.Varies()) {
      // Past the last event the shares still drift: follow them to the end of the depth range.
      const double end = f.At(z_end);
      f.Between(z, after, z_end, end);
      f.Push(z_end, end);
    }
  }
  return out;
}

std::vector<Vertex> EmitterWeightedPiece(std::span<const Event> events, EmitterRay* ray, double lo,
                                         double hi, double tolerance) {
  std::vector<Vertex> out;
  ray->ClearHidden();
  FunctionBuilder f(ray, lo, hi, events.size(), tolerance, &out);
  size_t i = 0;
  while (i < events.size() && events[i].z <= lo) f.ApplyDepth(events, &i);
  double z0 = lo, a0 = f.At(lo);
  f.Push(z0, a0);
  while (i < events.size() && events[i].z < hi) {
    const double z = events[i].z;
    const double before = f.At(z);
    f.Between(z0, a0, z, before);
    f.Push(z, before);
    f.ApplyDepth(events, &i);
    z0 = z;
    a0 = f.At(z);
    f.Push(z0, a0);
  }
  const double end = f.At(hi);
  f.Between(z0, a0, hi, end);
  f.Push(hi, end);
  return out;
}

}  // namespace pdsm
