#include "core/scene/alpha_mask.h"

#include <cmath>

namespace pdsm {
namespace {

// Texel index `i` (any integer) wrapped into [0, n).
int WrapIndex(int64_t i, int n, TextureWrap wrap) {
  switch (wrap) {
    case TextureWrap::kClampToEdge:
      return static_cast<int>(i < 0 ? 0 : (i >= n ? n - 1 : i));
    case TextureWrap::kMirroredRepeat: {
      const int64_t period = 2 * int64_t{n};
      int64_t m = i % period;
      if (m < 0) m += period;
      return static_cast<int>(m < n ? m : period - 1 - m);
    }
    case TextureWrap::kRepeat:
      break;
  }
  int64_t m = i % n;
  if (m < 0) m += n;
  return static_cast<int>(m);
}

}  // namespace

double AlphaMask::Sample(const glm::dvec2& uv) const {
  // GL_LINEAR: the four texels around uv * size - 0.5, weighted by the fractions.
  const double x = uv.x * width - 0.5, y = uv.y * height - 0.5;
  if (!std::isfinite(x) || !std::isfinite(y)) return 0.0;
  const double fx = std::floor(x), fy = std::floor(y);
  const double ax = x - fx, ay = y - fy;
  // UVs far outside [0, 1] are wrapped in 64-bit texel indices; beyond that range there is no
  // meaningful texture coordinate left in a float UV anyway.
  constexpr double kLimit = 4e18;
  if (std::abs(fx) > kLimit || std::abs(fy) > kLimit) return 0.0;
  const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
  const int x0 = WrapIndex(ix, width, wrap_u), x1 = WrapIndex(ix + 1, width, wrap_u);
  const int y0 = WrapIndex(iy, height, wrap_v), y1 = WrapIndex(iy + 1, height, wrap_v);
  const auto at = [&](int tx, int ty) {
    return alpha[static_cast<size_t>(ty) * width + tx] / 255.0;
  };
  const double top = (1 - ax) * at(x0, y0) + ax * at(x1, y0);
  const double bottom = (1 - ax) * at(x0, y1) + ax * at(x1, y1);
  return (1 - ay) * top + ay * bottom;
}

bool AlphaMask::Valid() const {
  return width >= 1 && height >= 1 && width <= kMaxAlphaMaskSide && height <= kMaxAlphaMaskSide &&
         alpha.size() == static_cast<size_t>(width) * height && cutoff > 0 && cutoff <= 1 &&
         static_cast<uint8_t>(wrap_u) <= 2 && static_cast<uint8_t>(wrap_v) <= 2;
}

bool SameMask(const AlphaMask& a, const AlphaMask& b) {
  return a.width == b.width && a.height == b.height && a.wrap_u == b.wrap_u &&
         a.wrap_v == b.wrap_v && a.cutoff == b.cutoff && a.alpha == b.alpha;
}

}  // namespace pdsm
