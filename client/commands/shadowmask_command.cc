// `pdsm shadowmask SCENE --pdsm FILE.exr -o DIR`: the baked attenuation as textures over the
// receivers' lightmap UVs, for engines (client/export/shadowmask.h).
#include <cstdio>
#include <string>
#include <vector>

#include "absl/strings/str_join.h"
#include "client/cli_common.h"
#include "client/commands.h"
#include "client/export/shadowmask.h"

namespace pdsm {
namespace {

struct ShadowmaskFlags {
  std::string scene_path;
  std::string pdsm_path;
  std::string out_dir;
  int64_t cache_mib = kDefaultTileCacheBytes >> 20;
  ShadowmaskOptions options;
};

int RunShadowmask(ShadowmaskFlags flags) {
  flags.options.cache_bytes = flags.cache_mib << 20;
  std::vector<std::string> warnings;
  absl::StatusOr<ShadowmaskReport> report =
      WriteShadowmasks(flags.scene_path, flags.pdsm_path, flags.out_dir, flags.options, &warnings);
  for (const std::string& w : warnings) std::fprintf(stderr, "pdsm: warning: %s\n", w.c_str());
  if (!report.ok()) return ReportError(report.status());
  for (const ShadowmaskTexture& t : report->textures) {
    std::vector<std::string> files;
    for (const ShadowmaskFile& f : t.files) {
      std::vector<std::string> channels;
      const char* names = "RGBA";
      for (size_t c = 0; c < f.lights.size(); ++c) {
        channels.push_back(std::string(1, names[c]) + "=" +
                           (f.lights[c].empty() ? "(the light)" : f.lights[c]));
      }
      files.push_back(f.exr + " + .png (" + absl::StrJoin(channels, " ") + ")");
    }
    std::printf("%s: %dx%d%s, UV set %d, %lld texels covered + %lld dilated -> %s\n",
                t.object.c_str(), t.size, t.size, t.clamped ? " (clamped by --max-size)" : "",
                t.uv_set, static_cast<long long>(t.texels_covered),
                static_cast<long long>(t.texels_dilated), absl::StrJoin(files, ", ").c_str());
    if (t.texels_outside > 0) {
      std::fprintf(stderr,
                   "pdsm: warning: %s: %lld texels lie outside a light's PDSM; written as 0 "
                   "(not hidden)\n",
                   t.object.c_str(), static_cast<long long>(t.texels_outside));
    }
  }
  for (const std::string& s : report->without_uvs) {
    std::fprintf(stderr, "pdsm: warning: %s has no UVs: no texture\n", s.c_str());
  }
  for (const std::string& s : report->without_area) {
    std::fprintf(stderr, "pdsm: warning: %s: its UV charts have no area: no texture\n", s.c_str());
  }
  std::printf("%zu texture(s) of %zu light(s), manifest %s/shadowmask.json\n",
              report->textures.size(), report->lights.size(),
              flags.out_dir.empty() ? "." : flags.out_dir.c_str());
  return kExitOk;
}

}  // namespace

void RegisterShadowmaskCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<ShadowmaskFlags>();
  CLI::App* cmd = app.add_subcommand(
      "shadowmask",
      "Textures of the baked attenuation over the receivers' lightmap UVs (TEXCOORD_1, else the "
      "first set): one channel per light, four to a texture, EXR and PNG");
  cmd->add_option("scene", flags->scene_path, "Scene file (JSON) or world file of the bake")
      ->required();
  cmd->add_option("--pdsm", flags->pdsm_path, "The baked PDSM file (.exr)")->required();
  cmd->add_option("-o,--output", flags->out_dir, "Output folder (created if missing)")->required();
  cmd->add_option("--texels-per-unit", flags->options.texels_per_unit,
                  "Texture density over the UV charts, texels per world unit (default 16)");
  cmd->add_option("--max-size", flags->options.max_size,
                  "Texels a side at most; denser requests are clamped (default 4096)");
  cmd->add_option("--dilate", flags->options.dilate,
                  "Texels the charts are grown by, so that filtering at seams stays on the "
                  "chart (default 2)");
  cmd->add_flag("--visibility", flags->options.visibility,
                "Store 1 - attenuation (lit = 1, as Unity's and Godot's masks are)");
  cmd->add_option("--light", flags->options.light, "Only this light (default: every light)");
  cmd->add_option("--cache-mib", flags->cache_mib,
                  "Tiles of the PDSM kept in memory, MiB (default 256)")
      ->check(CLI::Range(1, 1 << 20));
  cmd->add_flag("--allow-mismatch", flags->options.allow_mismatch,
                "Warn instead of failing when the PDSM was baked from a scene of another name");
  cmd->callback([flags, exit_code] { *exit_code = RunShadowmask(*flags); });
}

}  // namespace pdsm
