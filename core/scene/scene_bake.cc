#include "core/scene/scene_bake.h"

#include <algorithm>
#include <string>
#include <tuple>
#include <vector>

#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/sampling/light_samples.h"

namespace pdsm::internal {
namespace {

absl::StatusOr<FrustumOverride> BuildFrustum(const FieldChecker& checks,
                                             const pdsm::v1::Frustum& frustum, LightShape shape) {
  const std::string window_field = "bake.frustum.window";
  const std::string depth_field = "bake.frustum.depthRange";
  if (frustum.window_size() != 4) {
    return checks.Error(window_field,
                        absl::StrCat("must have 4 numbers [sMin, sMax, tMin, tMax] (got ",
                                     frustum.window_size(), ")"));
  }
  if (absl::Status s = checks.CheckAllFinite(window_field, frustum.window()); !s.ok()) return s;
  if (frustum.depth_range_size() != 2) {
    return checks.Error(depth_field, absl::StrCat("must have 2 numbers [near, far] (got ",
                                                  frustum.depth_range_size(), ")"));
  }
  if (absl::Status s = checks.CheckAllFinite(depth_field, frustum.depth_range()); !s.ok()) {
    return s;
  }
  FrustumOverride out{frustum.window(0), frustum.window(1),      frustum.window(2),
                      frustum.window(3), frustum.depth_range(0), frustum.depth_range(1)};
  if (!(out.s_min < out.s_max && out.t_min < out.t_max)) {
    return checks.Error(window_field, absl::StrCat("needs sMin < sMax and tMin < tMax (got ",
                                                   FormatDoubles(frustum.window()), ")"));
  }
  // A perspective PDSM divides by depth, so its range must lie in front of the light; the
  // sun's orthographic one may start behind the plane the plan puts it on.
  if (shape != LightShape::kSun && !(out.z_near > 0)) {
    return checks.Error(depth_field, absl::StrCat("needs 0 < near < far (got ",
                                                  FormatDoubles(frustum.depth_range()), ")"));
  }
  if (!(out.z_near < out.z_far)) {
    return checks.Error(depth_field, absl::StrCat("needs near < far (got ",
                                                  FormatDoubles(frustum.depth_range()), ")"));
  }
  return out;
}

// The counts and sizes: resolution, samples, shadowMapResolution, tileSize.
absl::Status BuildSizes(const FieldChecker& checks, const pdsm::v1::BakeParams& bake,
                        BakeSettings* out) {
  if (!bake.resolution().empty()) {
    if (bake.resolution_size() != 2) {
      return checks.Error(
          "bake.resolution",
          absl::StrCat("must have 2 numbers [width, height] (got ", bake.resolution_size(), ")"));
    }
    for (int i = 0; i < 2; ++i) {
      if (absl::Status s = checks.CheckUintRange(Indexed("bake.resolution", i), bake.resolution(i),
                                                 kMaxPdsmResolution);
          !s.ok()) {
        return s;
      }
    }
    out->width = static_cast<int>(bake.resolution(0));
    out->height = static_cast<int>(bake.resolution(1));
  }
  if (bake.has_samples()) {
    if (absl::Status s = checks.CheckUintRange("bake.samples", bake.samples(), kMaxSamples);
        !s.ok()) {
      return s;
    }
    out->samples = static_cast<int>(bake.samples());
  }
  if (bake.has_shadow_map_resolution()) {
    if (absl::Status s = checks.CheckUintRange(
            "bake.shadowMapResolution", bake.shadow_map_resolution(), kMaxShadowMapResolution);
        !s.ok()) {
      return s;
    }
    out->shadow_map_resolution = static_cast<int>(bake.shadow_map_resolution());
  }
  if (bake.has_tile_size()) {
    if (absl::Status s = checks.CheckUintRange("bake.tileSize", bake.tile_size(), kMaxTileSize);
        !s.ok()) {
      return s;
    }
    out->tile_size = static_cast<int>(bake.tile_size());
  }
  if (bake.has_tile_group_size()) {
    if (bake.tile_group_size() > 0) {
      if (absl::Status s =
              checks.CheckUintRange("bake.tileGroupSize", bake.tile_group_size(), kMaxTileSize);
          !s.ok()) {
        return s;
      }
    }
    out->tile_group_size = static_cast<int>(bake.tile_group_size());
  }
  return absl::OkStatus();
}

// The real-valued and plain parameters: epsilon, depthBias, slopeBias, seed, surfacesOnly.
absl::Status BuildScalars(const FieldChecker& checks, const pdsm::v1::BakeParams& bake,
                          BakeSettings* out) {
  if (bake.has_epsilon()) {
    const char* field = "bake.epsilon";
    if (absl::Status s = checks.CheckFinite(field, bake.epsilon()); !s.ok()) return s;
    if (!(bake.epsilon() >= 0 && bake.epsilon() <= 1)) {
      return checks.Error(
          field, absl::StrCat("must be in [0, 1] (got ", FormatDouble(bake.epsilon()), ")"));
    }
    out->epsilon = bake.epsilon();
  }
  for (const auto& [name, has, value] :
       {std::tuple("bake.depthBias", bake.has_depth_bias(), bake.depth_bias()),
        std::tuple("bake.slopeBias", bake.has_slope_bias(), bake.slope_bias())}) {
    if (!has) continue;
    if (absl::Status s = checks.CheckFinite(name, value); !s.ok()) return s;
    if (!(value >= 0)) {
      return checks.Error(name, absl::StrCat("must be >= 0 (got ", FormatDouble(value), ")"));
    }
  }
  if (bake.has_depth_bias()) out->depth_bias = bake.depth_bias();
  if (bake.has_slope_bias()) out->slope_bias = bake.slope_bias();
  if (bake.has_seed()) out->seed = bake.seed();
  if (bake.has_surfaces_only()) out->surfaces_only = bake.surfaces_only();
  if (bake.has_max_refinement()) {
    const uint32_t f = bake.max_refinement();
    if (f != 1 && f != 2 && f != 4 && f != 8) {
      return checks.Error("bake.maxRefinement", absl::StrCat("must be 1, 2, 4 or 8 (got ", f, ")"));
    }
    out->max_refinement = static_cast<int>(f);
  }
  return absl::OkStatus();
}

// The enums: sampling, compressionMetric and weighting.
absl::Status BuildEnums(const FieldChecker& checks, const pdsm::v1::BakeParams& bake,
                        BakeSettings* out) {
  switch (bake.sampling()) {
    case pdsm::v1::SAMPLING_DEFAULT:  // the measured best (docs/accuracy.md)
    case pdsm::v1::SOBOL:
      out->sampling = SamplingPattern::kSobol;
      break;
    case pdsm::v1::STRATIFIED:
      out->sampling = SamplingPattern::kStratified;
      break;
    case pdsm::v1::UNIFORM:
      out->sampling = SamplingPattern::kUniform;
      break;
    case pdsm::v1::HALTON:
      out->sampling = SamplingPattern::kHalton;
      break;
    case pdsm::v1::BLUE_NOISE:
      out->sampling = SamplingPattern::kBlueNoise;
      break;
    default:
      return checks.Error("bake.sampling",
                          absl::StrCat("unknown value (got ", bake.sampling(), ")"));
  }
  switch (bake.compression_metric()) {
    case pdsm::v1::COMPRESSION_METRIC_DEFAULT:
    case pdsm::v1::VERTICAL:
      out->compression_metric = CompressionMetric::kVertical;
      break;
    case pdsm::v1::PERPENDICULAR:
      out->compression_metric = CompressionMetric::kPerpendicular;
      break;
    default:
      return checks.Error("bake.compressionMetric",
                          absl::StrCat("unknown value (got ", bake.compression_metric(), ")"));
  }
  switch (bake.weighting()) {
    case pdsm::v1::WEIGHTING_DEFAULT:
    case pdsm::v1::UNWEIGHTED:
      out->weighting = LightWeighting::kUnweighted;
      break;
    case pdsm::v1::EMITTER:
      out->weighting = LightWeighting::kEmitter;
      break;
    default:
      return checks.Error("bake.weighting",
                          absl::StrCat("unknown value (got ", bake.weighting(), ")"));
  }
  return absl::OkStatus();
}

// Adaptive sampling needs a progressive pattern: a tile uses a prefix of the samples.
absl::Status BuildAdaptive(const FieldChecker& checks, const pdsm::v1::BakeParams& bake,
                           BakeSettings* out) {
  if (bake.has_adaptive_min_samples()) {
    if (absl::Status s = checks.CheckUintRange("bake.adaptiveMinSamples",
                                               bake.adaptive_min_samples(), kMaxSamples);
        !s.ok()) {
      return s;
    }
    out->adaptive_min_samples = static_cast<int>(bake.adaptive_min_samples());
  }
  if (!bake.has_adaptive_tolerance()) return absl::OkStatus();
  const double tolerance = bake.adaptive_tolerance();
  if (absl::Status s = checks.CheckFinite("bake.adaptiveTolerance", tolerance); !s.ok()) {
    return s;
  }
  if (!(tolerance >= 0 && tolerance <= 1)) {
    return checks.Error("bake.adaptiveTolerance",
                        absl::StrCat("must be in [0, 1] (got ", FormatDouble(tolerance), ")"));
  }
  out->adaptive_tolerance = tolerance;
  if (!out->adaptive()) return absl::OkStatus();
  if (!IsProgressive(out->sampling)) {
    return checks.Error(
        "bake.sampling",
        "STRATIFIED cannot be used with bake.adaptiveTolerance: a tile uses the first "
        "n samples, so the pattern must be progressive (SOBOL, HALTON, BLUE_NOISE, "
        "UNIFORM)");
  }
  out->adaptive_min_samples = std::min(out->adaptive_min_samples, out->samples);
  return absl::OkStatus();
}

// The map as a whole: its pixels and its tiles, within the limits of scene.h.
absl::Status CheckMapSize(const FieldChecker& checks, const BakeSettings& b) {
  const int64_t pixels = int64_t{b.width} * b.height;
  if (pixels > kMaxPdsmPixels) {
    return checks.Error("bake.resolution",
                        absl::StrCat("a map holds at most ", kMaxPdsmPixels,
                                     " pixels (32768x32768) (got ", b.width, "x", b.height, ")"));
  }
  const int64_t tiles = int64_t{(b.width + b.tile_size - 1) / b.tile_size} *
                        ((b.height + b.tile_size - 1) / b.tile_size);
  if (tiles > kMaxPdsmTiles) {
    return checks.Error(
        "bake.tileSize",
        absl::StrCat("a ", b.width, "x", b.height, " map in tiles of ", b.tile_size, " pixels has ",
                     tiles, " tiles, more than ", kMaxPdsmTiles, ": use larger tiles"));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<BakeSettings> BuildBake(const FieldChecker& checks, const pdsm::v1::BakeParams& bake,
                                       LightShape shape) {
  BakeSettings out;
  if (absl::Status s = BuildSizes(checks, bake, &out); !s.ok()) return s;
  if (absl::Status s = CheckMapSize(checks, out); !s.ok()) return s;
  if (absl::Status s = BuildScalars(checks, bake, &out); !s.ok()) return s;
  if (absl::Status s = BuildEnums(checks, bake, &out); !s.ok()) return s;
  if (bake.has_frustum()) {
    absl::StatusOr<FrustumOverride> frustum = BuildFrustum(checks, bake.frustum(), shape);
    if (!frustum.ok()) return frustum.status();
    out.frustum = *frustum;
  }
  if (absl::Status s = BuildAdaptive(checks, bake, &out); !s.ok()) return s;
  return out;
}

pdsm::v1::BakeParams BakeParamsOf(const BakeSettings& b) {
  pdsm::v1::BakeParams out;
  out.add_resolution(b.width);
  out.add_resolution(b.height);
  out.set_samples(b.samples);
  out.set_shadow_map_resolution(b.shadow_map_resolution);
  out.set_epsilon(b.epsilon);
  if (b.depth_bias) out.set_depth_bias(*b.depth_bias);
  out.set_slope_bias(b.slope_bias);
  out.set_tile_size(b.tile_size);
  out.set_seed(b.seed);
  switch (b.sampling) {
    case SamplingPattern::kStratified:
      out.set_sampling(pdsm::v1::STRATIFIED);
      break;
    case SamplingPattern::kUniform:
      out.set_sampling(pdsm::v1::UNIFORM);
      break;
    case SamplingPattern::kSobol:
      out.set_sampling(pdsm::v1::SOBOL);
      break;
    case SamplingPattern::kHalton:
      out.set_sampling(pdsm::v1::HALTON);
      break;
    case SamplingPattern::kBlueNoise:
      out.set_sampling(pdsm::v1::BLUE_NOISE);
      break;
  }
  out.set_compression_metric(b.compression_metric == CompressionMetric::kVertical
                                 ? pdsm::v1::VERTICAL
                                 : pdsm::v1::PERPENDICULAR);
  out.set_weighting(b.weighting == LightWeighting::kEmitter ? pdsm::v1::EMITTER
                                                            : pdsm::v1::UNWEIGHTED);
  if (b.frustum) {
    pdsm::v1::Frustum* f = out.mutable_frustum();
    for (double x : {b.frustum->s_min, b.frustum->s_max, b.frustum->t_min, b.frustum->t_max}) {
      f->add_window(x);
    }
    f->add_depth_range(b.frustum->z_near);
    f->add_depth_range(b.frustum->z_far);
  }
  out.set_adaptive_tolerance(b.adaptive_tolerance);
  out.set_adaptive_min_samples(b.adaptive_min_samples);
  out.set_surfaces_only(b.surfaces_only);
  out.set_tile_group_size(b.tile_group_size);
  out.set_max_refinement(b.max_refinement);
  return out;
}

pdsm::v1::BakeParams MergedBakeParams(const pdsm::v1::BakeParams& base,
                                      const pdsm::v1::BakeParams& top,
                                      std::set<std::string>* replaced) {
  // ListFields gives exactly the "set" fields: present optionals and messages, non-empty
  // repeated fields, non-default proto3 enums.
  std::vector<const google::protobuf::FieldDescriptor*> fields;
  top.GetReflection()->ListFields(top, &fields);
  pdsm::v1::BakeParams merged = base;
  for (const google::protobuf::FieldDescriptor* field : fields) {
    merged.GetReflection()->ClearField(&merged, field);
    if (replaced != nullptr) replaced->insert(field->json_name());
  }
  merged.MergeFrom(top);
  return merged;
}

void ClearBakeFields(const std::set<std::string>& names, pdsm::v1::BakeParams* params) {
  const google::protobuf::Descriptor* descriptor = params->GetDescriptor();
  for (int i = 0; i < descriptor->field_count(); ++i) {
    const google::protobuf::FieldDescriptor* field = descriptor->field(i);
    if (names.contains(field->json_name())) params->GetReflection()->ClearField(params, field);
  }
}

}  // namespace pdsm::internal
