#include "worker/scan_convert.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pdsm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Depth at fraction f of the segment: linear in w = 1/z for perspective shadow maps, in z for
// the sun's orthographic ones.
class DepthAlongRay {
 public:
  DepthAlongRay(const RayInShadowMap& ray, Projection projection)
      : perspective_(projection == Projection::kPerspective),
        near_(perspective_ ? 1.0 / ray.z_near : ray.z_near),
        far_(perspective_ ? (std::isinf(ray.z_far) ? 0.0 : 1.0 / ray.z_far) : ray.z_far) {}

  double operator()(double f) const {
    if (f >= 1.0) return perspective_ ? (far_ == 0.0 ? kInf : 1.0 / far_) : far_;
    const double p = near_ + f * (far_ - near_);
    return perspective_ ? 1.0 / p : p;
  }

 private:
  bool perspective_;
  double near_, far_;
};

// Follows the ray's shadow state through successive texel pieces and emits its events.
class EventEmitter {
 public:
  EventEmitter(std::vector<Event>* events, int32_t key) : events_(events), key_(key) {}

  // Ends a segment that stops short of the ray's end: a shadowed ray leaves at z, so that
  // another segment of the same ray can start from the lit state.
  void Close(double z) {
    if (shadowed_) Emit(z, -key_);
    shadowed_ = false;
  }

  bool shadowed() const { return shadowed_; }

  void Piece(double z_in, double z_out, double z_sm) {
    if (z_sm <= z_in) {
      if (!shadowed_) Emit(z_in, key_);
      shadowed_ = true;
    } else if (z_sm < z_out) {
      if (shadowed_) Emit(z_in, -key_);
      Emit(z_sm, key_);
      shadowed_ = true;
    } else if (shadowed_) {
      Emit(z_in, -key_);
      shadowed_ = false;
    }
  }

 private:
  void Emit(double z, int32_t count) { events_->push_back(Event{static_cast<float>(z), count}); }

  std::vector<Event>* events_;
  int32_t key_;
  bool shadowed_ = false;
};

// Whether any texel of [x0, x1] x [y0, y1] (clamped to the window) holds a caster.
bool AnyCasterIn(const ShadowMapView& sm, int x0, int y0, int x1, int y1) {
  const int w = sm.window.width, h = sm.window.height;
  x0 = std::clamp(x0, 0, w - 1);
  x1 = std::clamp(x1, 0, w - 1);
  y0 = std::clamp(y0, 0, h - 1);
  y1 = std::clamp(y1, 0, h - 1);
  const size_t row = static_cast<size_t>(w) + 1;
  const uint32_t* s = sm.occupancy;
  const uint32_t count =
      s[(y1 + 1) * row + x1 + 1] - s[y0 * row + x1 + 1] - s[(y1 + 1) * row + x0] + s[y0 * row + x0];
  return count != 0;
}

}  // namespace

void BuildOccupancySums(const float* depth, int width, int height, std::vector<uint32_t>* sums) {
  const size_t row = static_cast<size_t>(width) + 1;
  sums->assign(row * (static_cast<size_t>(height) + 1), 0);
  uint32_t* out = sums->data();
  for (int y = 0; y < height; ++y) {
    const float* in = depth + static_cast<size_t>(y) * width;
    const uint32_t* above = out + static_cast<size_t>(y) * row;
    uint32_t* here = out + static_cast<size_t>(y + 1) * row;
    uint32_t run = 0;
    for (int x = 0; x < width; ++x) {
      run += in[x] != std::numeric_limits<float>::infinity() ? 1u : 0u;
      here[x + 1] = above[x + 1] + run;
    }
  }
}

int64_t ScanConvertRay(const ShadowMapView& sm, const RayInShadowMap& ray, Projection projection,
                       std::vector<Event>* events, SegmentEnd end, int32_t key) {
  const ShadowMapLattice& lat = sm.lattice;
  const ShadowMapWindow& win = sm.window;
  // Window-relative continuous texel coordinates of the segment's ends.
  const glm::dvec2 origin(lat.s_origin + win.x0 * lat.pitch_s, lat.t_origin + win.y0 * lat.pitch_t);
  const glm::dvec2 pitch(lat.pitch_s, lat.pitch_t);
  const glm::dvec2 p0 = (ray.st_near - origin) / pitch;
  const glm::dvec2 p1 = (ray.st_far - origin) / pitch;
  const glm::dvec2 d = p1 - p0;

  // The walk below visits only texels between the ends' texels (one more on each side covers
  // a step rounding takes past an end), so a box without a caster gives a walk without events:
  // the ray starts lit and would stay lit, open or closed.
  if (sm.occupancy != nullptr) {
    const glm::dvec2 lo = glm::floor(glm::min(p0, p1)), hi = glm::floor(glm::max(p0, p1));
    // Coordinates far outside the window (a clamped end) clamp to its edge.
    auto to_int = [](double v) { return static_cast<int>(std::clamp(v, -2.0, 2.0e9)); };
    if (!AnyCasterIn(sm, to_int(lo.x) - 1, to_int(lo.y) - 1, to_int(hi.x) + 1, to_int(hi.y) + 1)) {
      return 0;
    }
  }

  // Amanatides–Woo traversal over f in [0, 1].
  int ix = std::clamp(static_cast<int>(std::floor(p0.x)), 0, win.width - 1);
  int iy = std::clamp(static_cast<int>(std::floor(p0.y)), 0, win.height - 1);
  const int step_x = d.x > 0 ? 1 : -1;
  const int step_y = d.y > 0 ? 1 : -1;
  const double delta_x = d.x != 0 ? std::abs(1.0 / d.x) : kInf;
  const double delta_y = d.y != 0 ? std::abs(1.0 / d.y) : kInf;
  double next_x = d.x != 0 ? ((d.x > 0 ? ix + 1 : ix) - p0.x) / d.x : kInf;
  double next_y = d.y != 0 ? ((d.y > 0 ? iy + 1 : iy) - p0.y) / d.y : kInf;

  const DepthAlongRay depth_at(ray, projection);
  EventEmitter emitter(events, key);
  // A piece's depths are computed only when its texel holds a caster, or when a shadowed ray
  // leaves at z_in: most texels a ray crosses are empty, and each depth is a division. The
  // depth at a fraction is a pure function of it, so the events are the same.
  double f_in = 0.0, z_in = ray.z_near;
  bool z_in_known = true;
  int64_t walked = 0;
  while (true) {
    ++walked;
    const double f_out = std::min({next_x, next_y, 1.0});
    const float z_sm = sm.depth[static_cast<size_t>(iy) * win.width + ix];
    if (z_sm == std::numeric_limits<float>::infinity()) {
      // No caster: the piece is lit whatever its depths (Piece's last case).
      if (emitter.shadowed()) {
        if (!z_in_known) z_in = depth_at(f_in);
        emitter.Piece(z_in, kInf, kInf);
      }
      z_in_known = false;
    } else {
      if (!z_in_known) z_in = depth_at(f_in);
      const double z_out = depth_at(f_out);
      emitter.Piece(z_in, z_out, z_sm);
      z_in = z_out;
      z_in_known = true;
    }
    f_in = f_out;
    if (f_out >= 1.0) break;
    // Step into the next texel; stepping out of the window can only be rounding at the end.
    if (next_x <= next_y) {
      ix += step_x;
      next_x += delta_x;
    } else {
      iy += step_y;
      next_y += delta_y;
    }
    if (ix < 0 || ix >= win.width || iy < 0 || iy >= win.height) break;
  }
  if (end == SegmentEnd::kClose) emitter.Close(ray.z_far);
  return walked;
}

}  // namespace pdsm
