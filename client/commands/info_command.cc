// `pdsm info PDSM.exr [--json]`: what a PDSM file holds and how it was made.
#include <algorithm>
#include <cstdio>
#include <string>

#include "absl/strings/str_format.h"
#include "client/cli_common.h"
#include "client/commands.h"
#include "core/pdsm/pdsm_file.h"

namespace pdsm {
namespace {

struct InfoFlags {
  std::string pdsm_path;
  bool json = false;
};

std::string JsonString(const std::string& s) {
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

int RunInfo(const InfoFlags& flags) {
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(flags.pdsm_path);
  if (!pdsm.ok()) return ReportError(pdsm.status());
  const PdsmHeader& h = pdsm->header;
  const PdsmGeometry& g = h.geometry;
  size_t max_vertices = 0, empty_pixels = 0;
  const size_t pixels = static_cast<size_t>(g.width) * g.height;
  for (size_t p = 0; p < pixels; ++p) {
    const size_t n = pdsm->offsets[p + 1] - pdsm->offsets[p];
    max_vertices = std::max(max_vertices, n);
    empty_pixels += n == 0;
  }
  const auto v3 = [](const glm::dvec3& v) {
    return absl::StrFormat("[%.17g, %.17g, %.17g]", v.x, v.y, v.z);
  };
  const std::string projection =
      g.projection == Projection::kPerspective ? "perspective" : "orthographic";
  // Adaptive bakes: how many samples the tiles took (min, mean, max).
  int tile_min = h.samples, tile_max = 0;
  double tile_mean = 0;
  for (int n : h.tile_samples) {
    tile_min = std::min(tile_min, n);
    tile_max = std::max(tile_max, n);
    tile_mean += static_cast<double>(n) / h.tile_samples.size();
  }
  const std::string adaptive_json =
      h.adaptive()
          ? absl::StrFormat(
                ", \"adaptiveTolerance\": %.17g, \"adaptiveMinSamples\": %d, "
                "\"tileSamples\": {\"min\": %d, \"mean\": %.17g, \"max\": %d}",
                h.adaptive_tolerance, h.adaptive_min_samples, tile_min, tile_mean, tile_max)
          : "";
  // Format 2: where the file knows nothing (queries there are NaN).
  const std::string validity_json =
      absl::StrFormat(", \"surfacesOnly\": %s, \"zValidMin\": %.17g",
                      h.surfaces_only ? "true" : "false", g.z_valid_min);
  if (flags.json) {
    std::printf(
        "{\"formatVersion\": %d, \"scene\": %s, \"light\": %s, \"projection\": \"%s\", "
        "\"resolution\": [%d, %d], \"window\": [%.17g, %.17g, %.17g, %.17g], "
        "\"depthRange\": [%.17g, %.17g], \"lightCenter\": %s, \"lightNormal\": %s, "
        "\"samples\": %d, \"shadowMapResolution\": %d, \"epsilon\": %.17g, "
        "\"depthBias\": %.17g, \"slopeBias\": %.17g, \"tileSize\": %d, "
        "\"vertices\": %zu, \"maxVerticesPerPixel\": %zu, \"emptyPixels\": %zu%s%s}\n",
        h.format_version, JsonString(h.scene_name).c_str(),
        JsonString(LightShapeName(h.light_shape)).c_str(), projection.c_str(), g.width, g.height,
        g.s_min, g.s_max, g.t_min, g.t_max, g.z_near, g.z_far, v3(g.frame.center).c_str(),
        v3(g.frame.n).c_str(), h.samples, h.shadow_map_resolution, h.epsilon, h.depth_bias,
        h.slope_bias, h.tile_size, pdsm->vertices.size(), max_vertices, empty_pixels,
        adaptive_json.c_str(), validity_json.c_str());
    return kExitOk;
  }
  std::printf("%s: PDSM format %d, scene \"%s\"\n", flags.pdsm_path.c_str(), h.format_version,
              h.scene_name.c_str());
  std::printf("  light       %s, centre %s, normal %s\n", LightShapeName(h.light_shape),
              v3(g.frame.center).c_str(), v3(g.frame.n).c_str());
  std::printf("  projection  %s, %dx%d pixels, window s [%g, %g] t [%g, %g]\n", projection.c_str(),
              g.width, g.height, g.s_min, g.s_max, g.t_min, g.t_max);
  std::printf("  depths      [%g, %g]\n", g.z_near, g.z_far);
  std::printf(
      "  bake        %d samples, shadow maps %d, epsilon %g, bias %g + slope %g, "
      "tiles %d\n",
      h.samples, h.shadow_map_resolution, h.epsilon, h.depth_bias, h.slope_bias, h.tile_size);
  if (h.adaptive()) {
    std::printf(
        "  adaptive    tolerance %g, first batch %d; samples per tile min %d, mean %.1f, "
        "max %d\n",
        h.adaptive_tolerance, h.adaptive_min_samples, tile_min, tile_mean, tile_max);
  }
  if (h.surfaces_only || g.z_valid_min != 0) {
    std::printf(
        "  defined     %s%s%s\n",
        h.surfaces_only ? "only near the receiver surfaces (surfaces-only bake)" : "",
        h.surfaces_only && g.z_valid_min != 0 ? "; " : "",
        g.z_valid_min != 0 ? absl::StrFormat("from depth %g on", g.z_valid_min).c_str() : "");
  }
  std::printf("  functions   %zu vertices, at most %zu per pixel, %zu empty pixels (all lit)\n",
              pdsm->vertices.size(), max_vertices, empty_pixels);
  return kExitOk;
}

}  // namespace

void RegisterInfoCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<InfoFlags>();
  CLI::App* cmd = app.add_subcommand("info", "Describe a PDSM file");
  cmd->add_option("pdsm", flags->pdsm_path, "PDSM file (.exr)")->required();
  cmd->add_flag("--json", flags->json, "Print one JSON object");
  cmd->callback([flags, exit_code] { *exit_code = RunInfo(*flags); });
}

}  // namespace pdsm
