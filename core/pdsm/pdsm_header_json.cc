#include "core/pdsm/pdsm_header_json.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace pdsm {

std::string JsonString(std::string_view s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      out += absl::StrFormat("\\u%04x", c);
    } else {
      out += c;
    }
  }
  return out + "\"";
}

const char* SamplingName(SamplingPattern pattern) {
  switch (pattern) {
    case SamplingPattern::kStratified:
      return "stratified";
    case SamplingPattern::kUniform:
      return "uniform";
    case SamplingPattern::kSobol:
      return "sobol";
    case SamplingPattern::kHalton:
      return "halton";
    case SamplingPattern::kBlueNoise:
      return "blue-noise";
  }
  return "?";
}

const char* LightKindName(const PdsmHeader& header) {
  if (header.light_shape != LightShape::kDisk) return LightShapeName(header.light_shape);
  if (header.face_tangent > 0) return "sphere-face";
  return header.cone_half_angle_deg > 0 ? "spot" : "disk";
}

double SunDiameterDegrees(const PdsmHeader& header) {
  return 2 * std::atan(header.tan_half_angle) * 180 / std::numbers::pi;
}

namespace {

std::string LightSizeJson(const PdsmHeader& h) {
  switch (h.light_shape) {
    case LightShape::kRect:
      return absl::StrFormat(", \"lightSize\": [%.17g, %.17g]", 2 * h.light_half_width,
                             2 * h.light_half_height);
    case LightShape::kDisk:
      if (h.cone_half_angle_deg > 0) {
        return absl::StrFormat(", \"lightRadius\": %.17g, \"coneHalfAngleDeg\": %.17g",
                               h.light_radius, h.cone_half_angle_deg);
      }
      if (h.face_tangent > 0) {
        return absl::StrFormat(", \"lightRadius\": %.17g, \"faceTangent\": %.17g", h.light_radius,
                               h.face_tangent);
      }
      return absl::StrFormat(", \"lightRadius\": %.17g", h.light_radius);
    case LightShape::kSun:
      return absl::StrFormat(", \"angularDiameterDeg\": %.17g", SunDiameterDegrees(h));
  }
  return "";
}

std::string V3Json(const glm::dvec3& v) {
  return absl::StrFormat("[%.17g, %.17g, %.17g]", v.x, v.y, v.z);
}

}  // namespace

TileSampleCounts CountTileSamples(const PdsmHeader& header) {
  TileSampleCounts counts{.min = header.samples, .max = 0, .mean = 0};
  for (int n : header.tile_samples) {
    counts.min = std::min(counts.min, n);
    counts.max = std::max(counts.max, n);
    counts.mean += static_cast<double>(n) / header.tile_samples.size();
  }
  return counts;
}

std::string PdsmHeaderJson(const PdsmHeader& h, std::string_view extra_members) {
  const PdsmGeometry& g = h.geometry;
  const char* projection =
      g.projection == Projection::kPerspective ? "perspective" : "orthographic";
  std::string adaptive;
  if (h.adaptive()) {
    const TileSampleCounts tiles = CountTileSamples(h);
    adaptive = absl::StrFormat(
        ", \"adaptiveTolerance\": %.17g, \"adaptiveMinSamples\": %d, "
        "\"tileSamples\": {\"min\": %d, \"mean\": %.17g, \"max\": %d}",
        h.adaptive_tolerance, h.adaptive_min_samples, tiles.min, tiles.mean, tiles.max);
  }
  const std::string name =
      h.light_name.empty() ? "" : absl::StrCat(", \"name\": ", JsonString(h.light_name));
  return absl::StrFormat(
      "{\"formatVersion\": %d, \"scene\": %s%s, \"light\": %s, \"projection\": \"%s\", "
      "\"resolution\": [%d, %d], \"window\": [%.17g, %.17g, %.17g, %.17g], "
      "\"depthRange\": [%.17g, %.17g], \"lightCenter\": %s, \"lightNormal\": %s, "
      "\"samples\": %d, \"shadowMapResolution\": %d, \"epsilon\": %.17g, "
      "\"depthBias\": %.17g, \"slopeBias\": %.17g, \"tileSize\": %d, "
      "\"sampling\": \"%s\", \"seed\": \"%llu\"%s%s%s, \"surfacesOnly\": %s, "
      "\"zValidMin\": %.17g, \"weighting\": \"%s\", \"maxRefinement\": %d}",
      h.format_version, JsonString(h.scene_name), name, JsonString(LightKindName(h)), projection,
      g.width, g.height, g.s_min, g.s_max, g.t_min, g.t_max, g.z_near, g.z_far,
      V3Json(g.frame.center), V3Json(g.frame.n), h.samples, h.shadow_map_resolution, h.epsilon,
      h.depth_bias, h.slope_bias, h.tile_size, SamplingName(h.sampling),
      static_cast<unsigned long long>(h.seed), LightSizeJson(h), extra_members, adaptive,
      h.surfaces_only ? "true" : "false", g.z_valid_min,
      h.weighting == LightWeighting::kEmitter ? "emitter" : "unweighted", h.max_refinement);
}

}  // namespace pdsm
