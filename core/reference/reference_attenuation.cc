#include "core/reference/reference_attenuation.h"

#include <cmath>

#include "absl/strings/str_format.h"
#include "core/reference/exact_visibility.h"

namespace pdsm {

absl::StatusOr<ReferenceMethod> ParseReferenceMethod(const std::string& text,
                                                     const std::string& flag) {
  if (text == "auto") return ReferenceMethod::kAuto;
  if (text == "exact") return ReferenceMethod::kExact;
  if (text == "embree") return ReferenceMethod::kEmbree;
  return absl::InvalidArgumentError(
      absl::StrFormat("%s: expected exact, embree or auto (got \"%s\")", flag, text));
}

bool HasAlphaTestedCasters(const Scene& scene) {
  for (const TriangleMesh& mesh : scene.meshes) {
    if (Casts(mesh.role) && mesh.has_masks()) return true;
  }
  return false;
}

ReferenceMethod ResolveReferenceMethod(ReferenceMethod method, const Scene& scene) {
  if (method != ReferenceMethod::kAuto) return method;
  return scene.light.shape == LightShape::kRect && !HasAlphaTestedCasters(scene)
             ? ReferenceMethod::kExact
             : ReferenceMethod::kEmbree;
}

const char* ReferenceMethodName(ReferenceMethod method) {
  switch (method) {
    case ReferenceMethod::kAuto:
      return "auto";
    case ReferenceMethod::kExact:
      return "exact";
    case ReferenceMethod::kEmbree:
      return "embree";
  }
  return "?";
}

absl::StatusOr<std::vector<double>> ReferenceAttenuation(const Scene& scene,
                                                         std::span<const glm::dvec3> points,
                                                         const ReferenceOptions& options) {
  WeightingSpec weighting = options.weighting;
  if (weighting.kind == LightWeighting::kIrradiance) {
    const double length = glm::length(weighting.normal_world);
    if (!std::isfinite(length) || !(length > 0.0)) {
      return absl::InvalidArgumentError(
          "irradiance weighting needs the receiver's normal (finite, not zero)");
    }
    weighting.normal_world /= length;
  }
  if (ResolveReferenceMethod(options.method, scene) == ReferenceMethod::kExact) {
    if (scene.light.is_sphere_face()) {
      // The exact method projects a planar light; a sphere's outline moves with the point.
      return absl::UnimplementedError(
          "the exact reference has no sphere light: use --method embree (or auto)");
    }
    if (HasAlphaTestedCasters(scene)) {
      // It clips whole triangles' shadows on the light; a texture's holes are not polygons.
      return absl::UnimplementedError(
          "the exact reference has no alpha-tested casters: use --method embree (or auto)");
    }
    return ExactAttenuation(scene, points, weighting);
  }
  return EmbreeAttenuation(scene, points, options.samples, options.seed, weighting);
}

}  // namespace pdsm
