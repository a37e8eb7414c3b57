#include "core/bake/window_fit.h"

#include <algorithm>
#include <cmath>

#include "core/bake/bake_plan.h"

namespace pdsm {
namespace {

constexpr double kInf = WindowFit::kInf;

// The part of triangle (a, b, c) with z >= z_min (Sutherland–Hodgman against one plane).
int ClipTriangleNear(const glm::dvec3 tri[3], double z_min, glm::dvec3 out[4]) {
  int n = 0;
  for (int k = 0; k < 3; ++k) {
    const glm::dvec3& p = tri[k];
    const glm::dvec3& q = tri[(k + 1) % 3];
    const bool p_in = p.z >= z_min, q_in = q.z >= z_min;
    if (p_in) out[n++] = p;
    if (p_in != q_in) {
      const double f = (z_min - p.z) / (q.z - p.z);
      out[n++] = p + f * (q - p);
      out[n - 1].z = z_min;
    }
  }
  return n;
}

// The part of convex polygon `in` (n vertices) where `side(p)` <= 0, `side` affine
// (Sutherland–Hodgman against one plane). `out` holds n + 1 vertices.
template <typename Side>
int ClipPolygon(const glm::dvec3* in, int n, Side side, glm::dvec3* out) {
  int m = 0;
  for (int k = 0; k < n; ++k) {
    const glm::dvec3& p = in[k];
    const glm::dvec3& q = in[(k + 1) % n];
    const double fp = side(p), fq = side(q);
    if (fp <= 0) out[m++] = p;
    if ((fp <= 0) != (fq <= 0)) out[m++] = p + (fp / (fp - fq)) * (q - p);
  }
  return m;
}

// The nearest depth of polygon `poly` (n <= 4 vertices, z > 0) inside the pyramid |x| <=
// max_tangent z + reach_x, |y| <= max_tangent z + reach_y; +inf when none of it is inside.
// With reach 0 that is the window's own pyramid (what a receiver needs resolved); with the
// light's half extents it holds every point between a sample and a point in the window (what
// a caster can shadow there: x' = a + (x - a) z' / z).
double NearestDepthInPyramid(const glm::dvec3* poly, int n, double max_tangent, double reach_x,
                             double reach_y) {
  glm::dvec3 a[8], b[8];
  n = ClipPolygon(
      poly, n, [&](const glm::dvec3& p) { return p.x - max_tangent * p.z - reach_x; }, a);
  n = ClipPolygon(
      a, n, [&](const glm::dvec3& p) { return -p.x - max_tangent * p.z - reach_x; }, b);
  n = ClipPolygon(
      b, n, [&](const glm::dvec3& p) { return p.y - max_tangent * p.z - reach_y; }, a);
  n = ClipPolygon(
      a, n, [&](const glm::dvec3& p) { return -p.y - max_tangent * p.z - reach_y; }, b);
  double z = kInf;
  for (int k = 0; k < n; ++k) z = std::min(z, b[k].z);
  return z;
}

// How far from its centre a light's samples reach across its plane: the half extents along x
// and y (a sphere face's groups stretch its disk by up to 1 / cos of its widest direction:
// core/bake/face_samples.h).
glm::dvec2 LightReach(const LightSpec& light) {
  const double t = light.face_tangent;
  switch (light.shape) {
    case LightShape::kRect:
      return {light.half_width, light.half_height};
    case LightShape::kDisk:
      return glm::dvec2(light.radius * std::sqrt(1 + 2 * t * t));
    case LightShape::kSun:
      break;
  }
  return {0, 0};
}

// `max_tangent`: perspective windows stop at |s|, |t| <= it (kMaxWindowTangent, a spot's cone
// or a sphere's face); `reach`: LightReach. A perspective triangle's s, t outside the window
// count at its edge, while its depths count only where it lies inside the window's pyramid
// (receivers) or can shadow a point in it (casters): a ground that crosses a sideways light's
// plane far below the light once made the nearest caster 1e-5 away (bench/sphere_faces.py).
void FitTriangle(const glm::dvec3 tri[3], bool casts, bool receives, Projection projection,
                 double z_min, double max_tangent, const glm::dvec2& reach, WindowFit* fit) {
  glm::dvec3 clipped[4];
  const int n = projection == Projection::kPerspective ? ClipTriangleNear(tri, z_min, clipped) : 3;
  if (projection == Projection::kOrthographic) std::copy(tri, tri + 3, clipped);
  for (int k = 0; k < n; ++k) {
    const glm::dvec3& p = clipped[k];
    double s = p.x, t = p.y;
    if (projection == Projection::kPerspective) {
      s = std::clamp(p.x / p.z, -max_tangent, max_tangent);
      t = std::clamp(p.y / p.z, -max_tangent, max_tangent);
    }
    fit->s_lo = std::min(fit->s_lo, s);
    fit->s_hi = std::max(fit->s_hi, s);
    fit->t_lo = std::min(fit->t_lo, t);
    fit->t_hi = std::max(fit->t_hi, t);
    if (casts) fit->z_near_casters_anywhere = std::min(fit->z_near_casters_anywhere, p.z);
    if (projection == Projection::kOrthographic) {
      if (casts) fit->z_near_casters = std::min(fit->z_near_casters, p.z);
      if (receives) fit->z_near_receivers = std::min(fit->z_near_receivers, p.z);
    }
    fit->z_far_all = std::max(fit->z_far_all, p.z);
  }
  if (projection == Projection::kPerspective && n > 0) {
    if (casts) {
      fit->z_near_casters = std::min(
          fit->z_near_casters, NearestDepthInPyramid(clipped, n, max_tangent, reach.x, reach.y));
    }
    if (receives) {
      fit->z_near_receivers =
          std::min(fit->z_near_receivers, NearestDepthInPyramid(clipped, n, max_tangent, 0, 0));
    }
  }
}

// The triangle's vertices in light space, as both fits compute them.
void LightTriangle(const TriangleMesh& mesh, size_t k, const LightFrame& frame, glm::dvec3 tri[3]) {
  for (int v = 0; v < 3; ++v)
    tri[v] = frame.LightFromWorld(mesh.positions_world[mesh.indices[3 * k + v]]);
}

// One triangle into the fit, as both fits do it.
class TriangleFitter {
 public:
  explicit TriangleFitter(const FitRequest& request)
      : request_(request),
        max_tangent_(MaxWindowTangent(request.light)),
        reach_(LightReach(request.light)) {}

  void Add(const TriangleMesh& mesh, size_t k, WindowFit* fit) const {
    glm::dvec3 tri[3];
    LightTriangle(mesh, k, request_.g.frame, tri);
    if (std::max({tri[0].z, tri[1].z, tri[2].z}) < request_.z_min) return;  // behind the light
    FitTriangle(tri, Casts(mesh.role), Receives(mesh.role), request_.g.projection, request_.z_min,
                max_tangent_, reach_, fit);
  }
  double max_tangent() const { return max_tangent_; }
  const glm::dvec2& reach() const { return reach_; }

 private:
  const FitRequest& request_;
  double max_tangent_;
  glm::dvec2 reach_;
};

// Whether values of at least `bound` (at most, for MayRaise) may still move `current`. Depths
// of vertices (or z_min, where a triangle is clipped) and the sun's s, t are coordinates, which
// the box bounds exactly: compared exactly, so that a box whose greatest depth ties the farthest
// so far (a flat ground, and every tree standing on it) is skipped. A perspective s, t is a
// quotient of interpolated points, rounded more: 1e-12 of it is left as slack.
bool MayLower(double bound, double current, bool quotient = false) {
  return quotient ? bound - 1e-12 * (1 + std::abs(bound)) < current : bound < current;
}
bool MayRaise(double bound, double current, bool quotient = false) {
  return quotient ? bound + 1e-12 * (1 + std::abs(bound)) > current : bound > current;
}

// Whether no point of the light-space box `b` lies inside the pyramid |x| <= m z + reach.x,
// |y| <= m z + reach.y, by a margin far over the clipping's rounding: NearestDepthInPyramid then
// finds nothing of a triangle in it. The pyramid is widest at the box's far end.
bool OutsidePyramid(const LightBox& b, double m, const glm::dvec2& reach) {
  const double widest_x = m * b.hi.z + reach.x, widest_y = m * b.hi.z + reach.y;
  const double size = std::abs(b.lo.x) + std::abs(b.hi.x) + std::abs(b.lo.y) + std::abs(b.hi.y) +
                      std::abs(widest_x) + std::abs(widest_y);
  const double margin = 1e-9 * size;
  return b.lo.x - widest_x > margin || -b.hi.x - widest_x > margin || b.lo.y - widest_y > margin ||
         -b.hi.y - widest_y > margin;
}

// The widest s, t a point of the light-space box `b` can give, its depths from `z_lo` on (a
// perspective light's x / z over x in [lo, hi], z in [z_lo, hi.z] > 0 is extreme at a corner;
// clamped), as a fit of that box alone.
WindowFit BoxWindow(const LightBox& b, double z_lo, bool perspective, double max_tangent) {
  WindowFit w;
  w.s_lo = b.lo.x, w.s_hi = b.hi.x, w.t_lo = b.lo.y, w.t_hi = b.hi.y;
  w.z_near_casters = w.z_near_receivers = w.z_near_casters_anywhere = z_lo;
  w.z_far_all = b.hi.z;
  if (perspective) {
    const auto clamp = [&](double v) { return std::clamp(v, -max_tangent, max_tangent); };
    w.s_lo = clamp(std::min(b.lo.x / z_lo, b.lo.x / b.hi.z));
    w.s_hi = clamp(std::max(b.hi.x / z_lo, b.hi.x / b.hi.z));
    w.t_lo = clamp(std::min(b.lo.y / z_lo, b.lo.y / b.hi.z));
    w.t_hi = clamp(std::max(b.hi.y / z_lo, b.hi.y / b.hi.z));
  }
  return w;
}

// Whether a triangle with every vertex in the light-space box `b` can move a bound of `fit`.
// A perspective light's nearest caster and receiver count only inside their pyramids: a lamp's
// window holds a few houses, while the roofs of the whole village lie nearer than its ground.
bool BoxMayChangeFit(const LightBox& b, bool casts, bool receives, const FitRequest& request,
                     double max_tangent, const glm::dvec2& reach, const WindowFit& fit) {
  if (b.hi.z < request.z_min) return false;  // every such triangle is skipped
  const bool perspective = request.g.projection == Projection::kPerspective;
  // Depths its (clipped) points take; perspective points nearer than z_min are clipped there.
  const double z_lo = perspective ? std::max(b.lo.z, request.z_min) : b.lo.z;
  if (MayRaise(b.hi.z, fit.z_far_all)) return true;
  if (casts && MayLower(z_lo, fit.z_near_casters_anywhere)) return true;
  // Within the pyramids, depths are interpolated where the sides clip: slack, as for quotients.
  if (casts && MayLower(z_lo, fit.z_near_casters, perspective) &&
      !(perspective && OutsidePyramid(b, max_tangent, reach))) {
    return true;
  }
  if (receives && MayLower(z_lo, fit.z_near_receivers, perspective) &&
      !(perspective && OutsidePyramid(b, max_tangent, glm::dvec2(0.0)))) {
    return true;
  }
  const WindowFit box = BoxWindow(b, z_lo, perspective, max_tangent);
  if (perspective) {
    // A bound already at the clamp cannot move further.
    if (fit.s_lo > -max_tangent && MayLower(box.s_lo, fit.s_lo, true)) return true;
    if (fit.s_hi < max_tangent && MayRaise(box.s_hi, fit.s_hi, true)) return true;
    if (fit.t_lo > -max_tangent && MayLower(box.t_lo, fit.t_lo, true)) return true;
    return fit.t_hi < max_tangent && MayRaise(box.t_hi, fit.t_hi, true);
  }
  return MayLower(box.s_lo, fit.s_lo) || MayRaise(box.s_hi, fit.s_hi) ||
         MayLower(box.t_lo, fit.t_lo) || MayRaise(box.t_hi, fit.t_hi);
}

class IndexedFit {
 public:
  IndexedFit(const SceneIndex& index, const FitRequest& request)
      : index_(index), request_(request), fitter_(request) {}

  size_t triangles_fitted() const { return triangles_fitted_; }

  WindowFit Run() {
    const auto& tree = index_.tree();
    if (tree.empty()) return fit_;
    // Seeds: for each bound, the cluster whose box promises the most, found greedily down the
    // tree, so that the full walk skips most of what the extremes already beat.
    for (int bound = 0; bound < kBounds; ++bound) {
      size_t i = 0;
      for (int level = static_cast<int>(tree.size()) - 1; level >= 0 && i != kNone; --level) {
        i = MostPromising(level, i, bound);
      }
      if (i != kNone) AddCluster(i);
    }
    Visit(static_cast<int>(tree.size()) - 1, 0);
    return fit_;
  }

 private:
  static constexpr size_t kNone = ~size_t{0};

  // The bounds a seed is sought for: the farthest depth, the nearest, and the window's sides.
  static constexpr int kBounds = 6;
  static double Promise(const WindowFit& w, int bound) {
    switch (bound) {
      case 0:
        return w.z_far_all;
      case 1:
        return -w.z_near_casters;
      case 2:
        return -w.s_lo;
      case 3:
        return w.s_hi;
      case 4:
        return -w.t_lo;
      default:
        return w.t_hi;
    }
  }

  // The child of tree node (level, i) (a cluster below level 0) in front of the light whose
  // box promises the most for `bound`; kNone when none is in front or wanted.
  size_t MostPromising(int level, size_t i, int bound) const {
    size_t best = kNone;
    double best_promise = 0;
    const bool perspective = request_.g.projection == Projection::kPerspective;
    const size_t n = level == 0 ? index_.clusters().size() : index_.tree()[level - 1].size();
    for (size_t c = i * SceneIndex::kTreeFanout; c < std::min(n, (i + 1) * SceneIndex::kTreeFanout);
         ++c) {
      const auto [lo, hi, casts, receives] = ChildBox(level, c);
      if (request_.receivers_only && !receives) continue;
      const LightBox b = LightBoxOf(request_.g.frame, lo, hi);
      if (b.hi.z < request_.z_min) continue;
      const double z_lo = perspective ? std::max(b.lo.z, request_.z_min) : b.lo.z;
      const double promise = Promise(BoxWindow(b, z_lo, perspective, fitter_.max_tangent()), bound);
      if (best == kNone || promise > best_promise) best = c, best_promise = promise;
    }
    return best;
  }

  SceneIndex::Box ChildBox(int level, size_t c) const {
    if (level > 0) return index_.tree()[level - 1][c];
    const SceneCluster& cluster = index_.clusters()[c];
    return SceneIndex::Box{cluster.lo, cluster.hi, cluster.casts, cluster.receives};
  }

  void Visit(int level, size_t i) {
    const SceneIndex::Box& box = index_.tree()[level][i];
    if (!MayChange(box)) return;
    const size_t n = level == 0 ? index_.clusters().size() : index_.tree()[level - 1].size();
    for (size_t c = i * SceneIndex::kTreeFanout; c < std::min(n, (i + 1) * SceneIndex::kTreeFanout);
         ++c) {
      if (level > 0) {
        Visit(level - 1, c);
      } else if (MayChange(ChildBox(0, c))) {
        AddCluster(c);
      }
    }
  }

  bool MayChange(const SceneIndex::Box& box) const {
    if (request_.receivers_only && !box.receives) return false;
    return BoxMayChangeFit(LightBoxOf(request_.g.frame, box.lo, box.hi), box.casts, box.receives,
                           request_, fitter_.max_tangent(), fitter_.reach(), fit_);
  }

  // A seed added again changes nothing: every bound is a minimum or a maximum.
  void AddCluster(size_t c) {
    const SceneCluster& cluster = index_.clusters()[c];
    const Scene& scene = index_.scene();
    for (uint32_t k = cluster.first; k < cluster.first + cluster.count; ++k) {
      const SceneTriangle& t = index_.triangles()[k];
      const TriangleMesh& mesh = scene.meshes[t.mesh];
      if (request_.receivers_only && !Receives(mesh.role)) continue;
      fitter_.Add(mesh, t.triangle, &fit_);
      ++triangles_fitted_;
    }
  }

  const SceneIndex& index_;
  const FitRequest& request_;
  TriangleFitter fitter_;
  WindowFit fit_;
  size_t triangles_fitted_ = 0;
};

}  // namespace

WindowFit FitEveryTriangle(const std::vector<TriangleMesh>& meshes, const FitRequest& request) {
  WindowFit fit;
  const TriangleFitter fitter(request);
  for (const TriangleMesh& mesh : meshes) {
    if (request.receivers_only && !Receives(mesh.role)) continue;
    for (size_t k = 0; 3 * k + 2 < mesh.indices.size(); ++k) fitter.Add(mesh, k, &fit);
  }
  return fit;
}

WindowFit FitIndexed(const SceneIndex& index, const FitRequest& request, size_t* triangles_fitted) {
  IndexedFit fit(index, request);
  const WindowFit result = fit.Run();
  if (triangles_fitted != nullptr) *triangles_fitted = fit.triangles_fitted();
  return result;
}

}  // namespace pdsm
