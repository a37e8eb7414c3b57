#include "core/reference/reference_attenuation.h"

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

ReferenceMethod ResolveReferenceMethod(ReferenceMethod method, const LightSpec& light) {
  if (method != ReferenceMethod::kAuto) return method;
  return light.shape == LightShape::kRect ? ReferenceMethod::kExact : ReferenceMethod::kEmbree;
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
  if (ResolveReferenceMethod(options.method, scene.light) == ReferenceMethod::kExact) {
    if (scene.light.is_sphere_face()) {
      // The exact method projects a planar light; a sphere's outline moves with the point.
      return absl::UnimplementedError(
          "the exact reference has no sphere light: use --method embree (or auto)");
    }
    return ExactAttenuation(scene, points);
  }
  return EmbreeAttenuation(scene, points, options.samples, options.seed);
}

}  // namespace pdsm
