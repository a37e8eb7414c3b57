// The global shadow-map texel grid. Every shadow map of a bake, whatever its sample and tile,
// is a window of this one lattice, so texels are snapped the same way everywhere (thesis 3.3).
#ifndef PDSM_CORE_BAKE_SHADOW_MAP_LATTICE_H_
#define PDSM_CORE_BAKE_SHADOW_MAP_LATTICE_H_

#include <cmath>
#include <cstdint>

namespace pdsm {

// Texel (k, l) covers s in [s_origin + k * pitch_s, s_origin + (k + 1) * pitch_s), same for t.
struct ShadowMapLattice {
  double s_origin = 0, t_origin = 0;
  double pitch_s = 1, pitch_t = 1;

  int64_t TexelS(double s) const {
    return static_cast<int64_t>(std::floor((s - s_origin) / pitch_s));
  }
  int64_t TexelT(double t) const {
    return static_cast<int64_t>(std::floor((t - t_origin) / pitch_t));
  }
  double EdgeS(int64_t k) const { return s_origin + static_cast<double>(k) * pitch_s; }
  double EdgeT(int64_t l) const { return t_origin + static_cast<double>(l) * pitch_t; }
};

// A rectangle of lattice texels: [x0, x0 + width) x [y0, y0 + height).
struct ShadowMapWindow {
  int64_t x0 = 0, y0 = 0;
  int width = 0, height = 0;
};

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_SHADOW_MAP_LATTICE_H_
