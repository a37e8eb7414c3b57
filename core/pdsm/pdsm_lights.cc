#include "core/pdsm/pdsm_lights.h"

#include <limits>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "core/scene/sphere_faces.h"

namespace pdsm {
namespace {

// The light a part belongs to: its sphere's name for a face, else its own.
std::string_view LightOfPart(const PdsmHeader& header) {
  if (header.face_tangent > 0) {
    const std::string_view sphere = SphereOfFace(header.light_name);
    if (!sphere.empty()) return sphere;
  }
  return header.light_name;
}

std::string Listed(const std::vector<PdsmLightParts>& lights) {
  std::vector<std::string> names;
  for (const PdsmLightParts& light : lights) names.push_back(light.name);
  return absl::StrCat("\"", absl::StrJoin(names, "\", \""), "\"");
}

}  // namespace

std::vector<PdsmLightParts> LightsOfParts(std::span<const PdsmHeader> headers) {
  std::vector<PdsmLightParts> lights;
  for (size_t p = 0; p < headers.size(); ++p) {
    const std::string_view light = LightOfPart(headers[p]);
    // A sphere's faces are stored together: a face joins the light before it when both are
    // faces of one sphere.
    if (headers[p].face_tangent > 0 && !lights.empty() && lights.back().name == light &&
        headers[lights.back().parts.back()].face_tangent > 0) {
      lights.back().parts.push_back(static_cast<int>(p));
      continue;
    }
    lights.push_back(PdsmLightParts{std::string(light), {static_cast<int>(p)}});
  }
  return lights;
}

absl::StatusOr<PdsmLightParts> FindLightParts(std::span<const PdsmHeader> headers,
                                              std::string_view path, std::string_view name) {
  std::vector<PdsmLightParts> lights = LightsOfParts(headers);
  if (name.empty()) {
    if (lights.size() == 1) return lights[0];
    return absl::FailedPreconditionError(absl::StrFormat(
        "%s holds %d lights (%s): name one (--light NAME)", path, lights.size(), Listed(lights)));
  }
  for (PdsmLightParts& light : lights) {
    if (light.name == name) return std::move(light);
  }
  for (size_t p = 0; p < headers.size(); ++p) {
    if (headers[p].light_name == name) {
      return PdsmLightParts{std::string(name), {static_cast<int>(p)}};
    }
  }
  return absl::NotFoundError(
      absl::StrFormat("%s has no light \"%s\"; its lights: %s", path, name, Listed(lights)));
}

absl::StatusOr<std::vector<PdsmLightParts>> SelectLights(std::span<const PdsmHeader> headers,
                                                         std::string_view path,
                                                         std::string_view name) {
  if (name.empty()) return LightsOfParts(headers);
  absl::StatusOr<PdsmLightParts> found = FindLightParts(headers, path, name);
  if (!found.ok()) return found.status();
  return std::vector<PdsmLightParts>{*std::move(found)};
}

int PartAt(std::span<const PdsmHeader> headers, const PdsmLightParts& light,
           const glm::dvec3& p_world) {
  int best = light.parts[0];
  if (light.parts.size() == 1) return best;
  double best_dot = -std::numeric_limits<double>::infinity();
  for (const int part : light.parts) {
    const LightFrame& frame = headers[part].geometry.frame;
    const double dot = glm::dot(frame.n, p_world - frame.center);
    if (dot > best_dot) {
      best_dot = dot;
      best = part;
    }
  }
  return best;
}

}  // namespace pdsm
