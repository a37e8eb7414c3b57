#include "core/reference/accuracy_points.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "core/bake/bake_plan.h"
#include "core/sampling/hash_rng.h"

namespace pdsm {
namespace {

// Receiver triangles in front of the light (world), with their cumulative areas.
struct ReceiverAreas {
  std::vector<glm::dvec3> triangles;  // 3 vertices each
  std::vector<double> cumulative;     // running sum of areas
};

ReceiverAreas GatherReceivers(const Scene& scene) {
  ReceiverAreas r;
  double total = 0.0;
  for (const TriangleMesh& mesh : scene.meshes) {
    if (!Receives(mesh.role)) continue;
    for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
      const glm::dvec3 a = mesh.positions_world[mesh.indices[i]];
      const glm::dvec3 b = mesh.positions_world[mesh.indices[i + 1]];
      const glm::dvec3 c = mesh.positions_world[mesh.indices[i + 2]];
      const double area = 0.5 * glm::length(glm::cross(b - a, c - a));
      if (!(area > 0.0)) continue;
      total += area;
      r.triangles.insert(r.triangles.end(), {a, b, c});
      r.cumulative.push_back(total);
    }
  }
  return r;
}

// Uniform in a triangle (the square-root map).
glm::dvec3 InTriangle(const glm::dvec3* v, double u1, double u2) {
  const double su = std::sqrt(u1);
  return (1.0 - su) * v[0] + su * (1.0 - u2) * v[1] + su * u2 * v[2];
}

// DefaultBandHeight's rule.
double BandHeightOf(const PdsmGeometry& g) { return 0.5 * (g.z_far - g.z_near); }

}  // namespace

absl::StatusOr<double> DefaultBandHeight(const Scene& scene) {
  absl::StatusOr<BakePlan> plan = PlanBake(scene);
  if (!plan.ok()) return plan.status();
  return BandHeightOf(plan->geometry());
}

absl::StatusOr<AccuracyPoints> MakeAccuracyPoints(const Scene& scene,
                                                  const AccuracyPointCounts& counts,
                                                  uint64_t seed) {
  if (!(std::isfinite(counts.band_height) && counts.band_height >= 0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("band height: must be a finite number >= 0 (got ", counts.band_height, ")"));
  }
  absl::StatusOr<BakePlan> plan = PlanBake(scene);
  if (!plan.ok()) return plan.status();
  const PdsmGeometry& g = plan->geometry();
  // hash_rng, not std:: distributions: the same points on every standard library.
  SplitMix64 rng(HashInts(seed, 0x61636375726163ULL));
  auto u01 = [&rng](SplitMix64&) { return rng.NextDouble(); };
  AccuracyPoints points;
  points.band_height = counts.band_height > 0 ? counts.band_height : BandHeightOf(g);
  const bool ortho = g.projection == Projection::kOrthographic;

  const ReceiverAreas receivers = GatherReceivers(scene);
  // A receiver point, area-weighted, and its triangle's unit normal on the side facing the light.
  const auto on_receiver = [&](glm::dvec3* normal) {
    const double pick = u01(rng) * receivers.cumulative.back();
    const size_t t = std::min<size_t>(
        std::upper_bound(receivers.cumulative.begin(), receivers.cumulative.end(), pick) -
            receivers.cumulative.begin(),
        receivers.cumulative.size() - 1);
    const glm::dvec3* v = &receivers.triangles[3 * t];
    const double u1 = u01(rng), u2 = u01(rng);
    const glm::dvec3 p = InTriangle(v, u1, u2);
    *normal = glm::normalize(glm::cross(v[1] - v[0], v[2] - v[0]));
    const glm::dvec3 to_light = ortho ? -g.frame.n : g.frame.center - p;
    if (glm::dot(*normal, to_light) < 0) *normal = -*normal;
    return p;
  };
  // `count` receiver points moved by `place` (which may draw from the RNG too). Rejection keeps
  // only points inside the frustum; the attempt cap ends the loop for receivers wholly behind
  // the light.
  const auto draw_on_receivers = [&](int count, auto place, std::vector<glm::dvec3>* out) {
    for (int attempt = 0; !receivers.cumulative.empty() && static_cast<int>(out->size()) < count &&
                          attempt < 50 * count;
         ++attempt) {
      glm::dvec3 normal;
      const glm::dvec3 q = place(on_receiver(&normal), normal);
      if (g.Locate(q).has_value()) out->push_back(q);
    }
  };
  draw_on_receivers(
      counts.surface, [](const glm::dvec3& p, const glm::dvec3&) { return p; }, &points.surface);

  while (static_cast<int>(points.free_space.size()) < counts.free_space) {
    const double s = g.s_min + u01(rng) * (g.s_max - g.s_min);
    const double t = g.t_min + u01(rng) * (g.t_max - g.t_min);
    // Nearer than z_valid_min the PDSM knows nothing (the scan floor): no point there.
    const double z_min = std::max(g.z_near, g.z_valid_min);
    const double z = z_min + u01(rng) * (g.z_far - z_min);
    const glm::dvec3 p_light = ortho ? glm::dvec3(s, t, z) : glm::dvec3(s * z, t * z, z);
    points.free_space.push_back(g.frame.WorldFromLight(p_light));
  }

  // Heights in (0, h]: 1 - u is in (0, 1], so no band point lies on the receiver itself.
  draw_on_receivers(
      counts.band,
      [&](const glm::dvec3& p, const glm::dvec3& normal) {
        return p + normal * ((1.0 - u01(rng)) * points.band_height);
      },
      &points.band);
  return points;
}

ErrorStats CompareAttenuation(const std::vector<double>& estimate,
                              const std::vector<double>& reference) {
  std::vector<double> errors;
  ErrorStats stats;
  for (size_t k = 0; k < std::min(estimate.size(), reference.size()); ++k) {
    if (!std::isfinite(reference[k])) continue;
    if (std::isfinite(estimate[k])) {
      errors.push_back(std::abs(estimate[k] - reference[k]));
    } else {
      errors.push_back(1.0);
      ++stats.unknown;
    }
  }
  stats.count = errors.size();
  if (errors.empty()) return stats;
  std::sort(errors.begin(), errors.end());
  for (double e : errors) stats.mean += e;
  stats.mean /= errors.size();
  stats.p95 = errors[std::min(errors.size() - 1, errors.size() * 95 / 100)];
  stats.max = errors.back();
  return stats;
}

}  // namespace pdsm
