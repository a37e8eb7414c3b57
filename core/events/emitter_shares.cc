#include "core/events/emitter_shares.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace pdsm {
namespace {

constexpr int kTerms = kChebyshevTerms;

// Chebyshev nodes of the first kind on [-1, 1].
double Node(int i) { return std::cos(std::numbers::pi * (i + 0.5) / kTerms); }

// T_0(x) .. T_{n-1}(x).
void ChebyshevValues(double x, double* t) {
  t[0] = 1.0;
  t[1] = x;
  for (int j = 2; j < kTerms; ++j) t[j] = 2 * x * t[j - 1] - t[j - 2];
}

}  // namespace

EmitterShares::EmitterShares(EmitterRay* ray, double z_near, double z_far, double tolerance,
                             bool exact)
    : ray_(ray), w_lo_(1.0 / z_far), w_hi_(1.0 / z_near), tolerance_(tolerance), exact_(exact) {}

void EmitterShares::Apply(const Event& e) {
  if (!ray_->Apply(e) || current_ < 0) return;
  const Piece& piece = pieces_[current_];
  if (piece.exact) return;
  const int k = SampleOfEvent(e);
  const double sign = e.count > 0 ? 1.0 : -1.0;
  const double* c = piece.coefficients.data() + static_cast<size_t>(k) * kTerms;
  for (int j = 0; j < kTerms; ++j) sums_[j] += sign * c[j];
}

double EmitterShares::At(double z) {
  if (ray_->hidden() == 0) return 0.0;
  if (ray_->hidden() == ray_->total()) return 1.0;
  if (exact_) return ray_->Attenuation(z);
  const double w = std::clamp(1.0 / z, w_lo_, w_hi_);
  const int leaf = Locate(w);
  const Piece& piece = pieces_[leaf];
  if (piece.exact) return ray_->Attenuation(z);
  if (leaf != current_) {
    current_ = leaf;
    SumHidden();
  }
  const double x = std::clamp((2 * w - piece.w0 - piece.w1) / (piece.w1 - piece.w0), -1.0, 1.0);
  double t[kTerms];
  ChebyshevValues(x, t);
  double a = 0;
  for (int j = 0; j < kTerms; ++j) a += sums_[j] * t[j];
  return std::clamp(a, 0.0, 1.0);
}

int EmitterShares::Locate(double w) {
  int level = 0, index = 0;
  while (true) {
    int found = -1;
    for (size_t p = 0; p < pieces_.size(); ++p) {
      if (pieces_[p].level == level && pieces_[p].index == index) found = static_cast<int>(p);
    }
    if (found < 0) {
      pieces_.push_back(Make(level, index));
      found = static_cast<int>(pieces_.size()) - 1;
    }
    if (!pieces_[found].split) return found;
    const double middle = 0.5 * (pieces_[found].w0 + pieces_[found].w1);
    ++level;
    index = 2 * index + (w > middle ? 1 : 0);
  }
}

EmitterShares::Piece EmitterShares::Make(int level, int index) const {
  Piece piece;
  piece.level = level;
  piece.index = index;
  const double parts = std::ldexp(1.0, level);
  piece.w0 = w_lo_ + (w_hi_ - w_lo_) * (index / parts);
  piece.w1 = index + 1 == parts ? w_hi_ : w_lo_ + (w_hi_ - w_lo_) * ((index + 1) / parts);
  if (!(piece.w1 > piece.w0)) {  // one depth: exact evaluation costs what one node would
    piece.exact = true;
    return piece;
  }
  const int n = ray_->total();
  const double middle = 0.5 * (piece.w0 + piece.w1), half = 0.5 * (piece.w1 - piece.w0);
  // Shares at the nodes, then the coefficients (discrete cosine transform).
  std::vector<double> shares(static_cast<size_t>(n) * kTerms);
  std::vector<double> weights(n);
  for (int i = 0; i < kTerms; ++i) {
    const double all = ray_->Weights(middle + half * Node(i), weights.data());
    for (int k = 0; k < n; ++k) shares[static_cast<size_t>(k) * kTerms + i] = weights[k] / all;
  }
  double cosines[kTerms][kTerms];
  for (int j = 0; j < kTerms; ++j) {
    for (int i = 0; i < kTerms; ++i) {
      cosines[j][i] = std::cos(std::numbers::pi * j * (i + 0.5) / kTerms);
    }
  }
  piece.coefficients.assign(static_cast<size_t>(n) * kTerms, 0.0);
  for (int k = 0; k < n; ++k) {
    const double* f = shares.data() + static_cast<size_t>(k) * kTerms;
    double* c = piece.coefficients.data() + static_cast<size_t>(k) * kTerms;
    for (int j = 0; j < kTerms; ++j) {
      double sum = 0;
      for (int i = 0; i < kTerms; ++i) sum += f[i] * cosines[j][i];
      c[j] = (j == 0 ? 1.0 : 2.0) * sum / kTerms;
    }
  }
  // The check: halfway between nodes, |share - interpolant| summed over every sample bounds
  // the error of A for any hidden set.
  for (int m = 1; m < kTerms; ++m) {
    const double x = std::cos(std::numbers::pi * m / kTerms);
    const double all = ray_->Weights(middle + half * x, weights.data());
    double t[kTerms];
    ChebyshevValues(x, t);
    double error = 0;
    for (int k = 0; k < n; ++k) {
      const double* c = piece.coefficients.data() + static_cast<size_t>(k) * kTerms;
      double p = 0;
      for (int j = 0; j < kTerms; ++j) p += c[j] * t[j];
      error += std::abs(weights[k] / all - p);
    }
    if (error > tolerance_) {
      piece.coefficients.clear();
      if (level < kMaxShareSplits) {
        piece.split = true;
      } else {
        piece.exact = true;
      }
      return piece;
    }
  }
  return piece;
}

void EmitterShares::SumHidden() {
  std::fill(std::begin(sums_), std::end(sums_), 0.0);
  const Piece& piece = pieces_[current_];
  for (int k = 0; k < ray_->total(); ++k) {
    if (!ray_->is_hidden(k)) continue;
    const double* c = piece.coefficients.data() + static_cast<size_t>(k) * kTerms;
    for (int j = 0; j < kTerms; ++j) sums_[j] += c[j];
  }
}

}  // namespace pdsm
