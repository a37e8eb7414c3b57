// `pdsm info PDSM.exr [--json]`: what a PDSM file holds and how it was made.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/cli_common.h"
#include "client/commands.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_header_json.h"
#include "core/pdsm/pdsm_lights.h"
#include "core/pdsm/refined_pixel.h"

namespace pdsm {
namespace {

struct InfoFlags {
  std::string pdsm_path;
  std::string light;
  bool json = false;
};

// The light's size as the scene file gives it: "size 3 x 3", "radius 0.5", "0.53 deg across".
std::string LightSizeText(const PdsmHeader& h) {
  switch (h.light_shape) {
    case LightShape::kRect:
      return absl::StrFormat("size %.6g x %.6g", 2 * h.light_half_width, 2 * h.light_half_height);
    case LightShape::kDisk:
      if (h.cone_half_angle_deg > 0) {
        return absl::StrFormat("radius %.6g, cone %.6g deg off its axis", h.light_radius,
                               h.cone_half_angle_deg);
      }
      if (h.face_tangent > 0) {
        return absl::StrFormat("radius %.6g, the directions |s|, |t| <= %.6g about the face's axis",
                               h.light_radius, h.face_tangent);
      }
      return absl::StrFormat("radius %.6g", h.light_radius);
    case LightShape::kSun:
      return absl::StrFormat("%.6g deg across", SunDiameterDegrees(h));
  }
  return "";
}

// One light's description: a JSON object, or lines of text under `title`.
void Describe(const InfoFlags& flags, const std::string& title, const PdsmImage* pdsm) {
  const PdsmHeader& h = pdsm->header;
  const PdsmGeometry& g = h.geometry;
  size_t max_vertices = 0, empty_pixels = 0;
  struct {
    size_t total = 0;
    size_t by_factor[4] = {0, 0, 0, 0};  // by log2 of the refinement
  } refined;
  const size_t pixels = static_cast<size_t>(g.width) * g.height;
  for (size_t p = 0; p < pixels; ++p) {
    const size_t n = pdsm->offsets[p + 1] - pdsm->offsets[p];
    max_vertices = std::max(max_vertices, n);
    empty_pixels += n == 0;
    const int f = h.max_refinement > 1 ? RefinementOf(pdsm->Function(static_cast<int>(p % g.width),
                                                                     static_cast<int>(p / g.width)))
                                       : 1;
    if (f > 1) {
      ++refined.total;
      ++refined.by_factor[f == 2 ? 1 : f == 4 ? 2 : 3];
    }
  }
  // JSON is exact (pdsm_header_json.h); the text is for people: 6 significant digits.
  const auto v3_text = [](const glm::dvec3& v) {
    return absl::StrFormat("[%.6g, %.6g, %.6g]", v.x, v.y, v.z);
  };
  const std::string projection =
      g.projection == Projection::kPerspective ? "perspective" : "orthographic";
  if (flags.json) {
    std::printf("%s",
                PdsmHeaderJson(h, absl::StrFormat(", \"vertices\": %zu, "
                                                  "\"maxVerticesPerPixel\": %zu, "
                                                  "\"emptyPixels\": %zu, \"refinedPixels\": %zu",
                                                  pdsm->vertices.size(), max_vertices, empty_pixels,
                                                  refined.total))
                    .c_str());
    return;
  }
  std::printf("%s: PDSM format %d, scene \"%s\"\n", title.c_str(), h.format_version,
              h.scene_name.c_str());
  std::printf("  light       %s, %s, centre %s, normal %s\n", LightKindName(h),
              LightSizeText(h).c_str(), v3_text(g.frame.center).c_str(),
              v3_text(g.frame.n).c_str());
  std::printf("  projection  %s, %dx%d pixels, window s [%.6g, %.6g] t [%.6g, %.6g]\n",
              projection.c_str(), g.width, g.height, g.s_min, g.s_max, g.t_min, g.t_max);
  std::printf("  depths      [%.6g, %.6g]\n", g.z_near, g.z_far);
  std::printf(
      "  bake        %d samples (%s, seed %llu), shadow maps %d, epsilon %.6g, "
      "bias %.6g + slope %.6g, tiles %d\n",
      h.samples, SamplingName(h.sampling), static_cast<unsigned long long>(h.seed),
      h.shadow_map_resolution, h.epsilon, h.depth_bias, h.slope_bias, h.tile_size);
  if (h.adaptive()) {
    const TileSampleCounts tiles = CountTileSamples(h);
    std::printf(
        "  adaptive    tolerance %.6g, first batch %d; samples per tile min %d, mean %.1f, "
        "max %d\n",
        h.adaptive_tolerance, h.adaptive_min_samples, tiles.min, tiles.mean, tiles.max);
  }
  if (h.weighting == LightWeighting::kEmitter) {
    std::printf("  weighting   emitter (each sample by cos/r^2 toward the point)\n");
  }
  if (h.surfaces_only || g.z_valid_min != 0) {
    std::printf(
        "  defined     %s%s%s\n",
        h.surfaces_only ? "only near the receiver surfaces (surfaces-only bake)" : "",
        h.surfaces_only && g.z_valid_min != 0 ? "; " : "",
        g.z_valid_min != 0 ? absl::StrFormat("from depth %.6g on", g.z_valid_min).c_str() : "");
  }
  std::printf("  functions   %zu vertices, at most %zu per pixel, %zu empty pixels (all lit)\n",
              pdsm->vertices.size(), max_vertices, empty_pixels);
  if (h.max_refinement > 1) {
    std::printf("  refined     %zu pixels (2x %zu, 4x %zu, 8x %zu), up to %dx per axis\n",
                refined.total, refined.by_factor[1], refined.by_factor[2], refined.by_factor[3],
                h.max_refinement);
  }
}

int RunInfo(const InfoFlags& flags) {
  absl::StatusOr<std::vector<PdsmImage>> read = ReadPdsmLights(flags.pdsm_path, flags.light);
  if (!read.ok()) return ReportError(read.status());
  const std::vector<PdsmImage>& lights = *read;
  // One light: its object or its lines, as they always were. Several: {"lights": [...]} in
  // file order, or a line saying how many, then each light's lines under its name.
  if (lights.size() == 1) {
    const std::string& name = lights[0].header.light_name;
    Describe(
        flags,
        name.empty() ? flags.pdsm_path : absl::StrCat(flags.pdsm_path, " light \"", name, "\""),
        &lights[0]);
    if (flags.json) std::printf("\n");
    return kExitOk;
  }
  if (flags.json) {
    std::printf("{\"lights\": [");
    for (size_t i = 0; i < lights.size(); ++i) {
      if (i > 0) std::printf(", ");
      Describe(flags, "", &lights[i]);
    }
    std::printf("]}\n");
    return kExitOk;
  }
  // A sphere's faces are parts of one light (core/pdsm/pdsm_lights.h).
  std::vector<PdsmHeader> headers;
  for (const PdsmImage& light : lights) headers.push_back(light.header);
  std::printf("%s: %s\n", flags.pdsm_path.c_str(),
              LightsText(LightsOfParts(headers).size(), lights.size()).c_str());
  for (const PdsmImage& light : lights) {
    Describe(flags, absl::StrCat("light \"", light.header.light_name, "\""), &light);
  }
  return kExitOk;
}

}  // namespace

void RegisterInfoCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<InfoFlags>();
  CLI::App* cmd = app.add_subcommand("info", "Describe a PDSM file");
  cmd->add_option("pdsm", flags->pdsm_path, "PDSM file (.exr)")->required();
  cmd->add_flag("--json", flags->json,
                "Print one JSON object (several lights: {\"lights\": [one per light]})");
  cmd->add_option("--light", flags->light, "Describe only this light of a file of several");
  cmd->callback([flags, exit_code] { *exit_code = RunInfo(*flags); });
}

}  // namespace pdsm
