// `pdsm shadowmask`: the baked attenuation as textures over the receivers' lightmap UVs, the
// per-texel light occlusion engines consume (Unity's shadowmask, Godot's lightmaps).
//
// For every receiver object (client/export/receiver_objects.h) a square texture: each texel the
// object's UV charts touch holds the attenuation (the fraction of the light hidden, as
// `pdsm query` answers it) at the surface point the texel's centre maps to (a texel a chart
// only grazes: the chart's point nearest its centre; client/export/uv_raster.h); then the
// charts are dilated by `dilate` texels so that bilinear filtering at seams stays on the
// chart's values. One channel per light, in the file's light order, four lights to a texture
// as Unity packs them: textures OBJECT-shadowmaskG.exr and .png for G = 0, 1, ...
//   .exr  float channels R, G, B, A (as many as the texture's lights), ZIP; string attributes
//         pdsmShadowmask "R=sun G=lamp ..." (which light each channel holds) and pdsmStores
//         ("attenuation" or "visibility").
//   .png  8-bit, linear (not sRGB): gray for one light, RGB for two or three (unused 0), RGBA
//         for four.
// A point outside a light's PDSM (NaN in a query: the light does not reach there, and an
// engine's own falloff decides) counts as not hidden: attenuation 0. With `visibility` every
// value is 1 - attenuation (lit = 1, as Unity's and Godot's masks are). Texels no chart reaches
// (after dilation) hold 0 in either case.
// Also writes shadowmask.json: the lights, and per object its source, UV set, size, files and
// channels.
#ifndef PDSM_CLIENT_EXPORT_SHADOWMASK_H_
#define PDSM_CLIENT_EXPORT_SHADOWMASK_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/pdsm/pdsm_tile_cache.h"

namespace pdsm {

struct ShadowmaskOptions {
  double texels_per_unit = 16;  // texture density over the charts, texels per world unit
  int max_size = 4096;          // texels a side at most (a denser request is clamped)
  int dilate = 2;               // texels the charts are grown by
  bool visibility = false;      // store 1 - attenuation
  std::string light;            // one light (as `pdsm query --light`); empty: every light
  int64_t cache_bytes = kDefaultTileCacheBytes;  // the PDSM's tiles kept in memory
  bool allow_mismatch = false;  // a PDSM of another scene (by name): a warning, not an error
};

inline constexpr int kMaxShadowmaskSize = 16384;
inline constexpr int kLightsPerShadowmask = 4;

struct ShadowmaskFile {
  std::string exr, png;             // file names in the output folder
  std::vector<std::string> lights;  // channel order: R, G, B, A
};

struct ShadowmaskTexture {
  std::string object;  // ReceiverObject::name
  std::string source;  // where the object comes from, for messages
  int uv_set = 0;
  int size = 0;                // texels a side
  bool clamped = false;        // `max_size` cut the density texels_per_unit asked for
  int64_t texels_covered = 0;  // texels the charts touch
  int64_t texels_dilated = 0;  // texels filled by dilation
  int64_t texels_outside = 0;  // covered texels outside some light's PDSM (written as 0)
  std::vector<ShadowmaskFile> files;
};

struct ShadowmaskReport {
  std::vector<std::string> lights;  // the file's lights written, in order ("" unnamed)
  std::vector<ShadowmaskTexture> textures;
  std::vector<std::string> without_uvs;   // receivers given no texture: no UVs
  std::vector<std::string> without_area;  // receivers given no texture: charts of no area
};

// Writes the textures of the scene (or world file) at `scene_path` from the PDSM at
// `pdsm_path` into the folder `out_dir` (created if missing), each file atomically, then
// shadowmask.json. Errors name the file and field: those of LoadReceiverObjects, of reading
// the PDSM (only the tiles the texels fall in are read, through a cache of cache_bytes), a
// light the file does not have, FAILED_PRECONDITION for a PDSM baked from a scene of another
// name (unless allow_mismatch: then a line in `warnings`), INVALID_ARGUMENT for options out of
// range (texels_per_unit not finite and > 0, max_size outside [1, kMaxShadowmaskSize], dilate < 0)
// or no receiver with UVs, and the file system's.
absl::StatusOr<ShadowmaskReport> WriteShadowmasks(const std::string& scene_path,
                                                  const std::string& pdsm_path,
                                                  const std::string& out_dir,
                                                  const ShadowmaskOptions& options,
                                                  std::vector<std::string>* warnings);

// The name of an object's texture of lights [4 group, 4 group + 4) without its extension:
// "ground-shadowmask0".
std::string ShadowmaskFileStem(const std::string& object, int group);

// A shadowmask EXR read back (for pdsm-view and tests): `channels` floats a texel, row 0 at the
// top, and the light each channel holds. INVALID_ARGUMENT naming `path` for a file that is not
// one (no pdsmShadowmask attribute), NOT_FOUND for no file.
struct ShadowmaskImage {
  int width = 0, height = 0;
  std::vector<std::string> lights;  // one per channel
  bool visibility = false;          // pdsmStores "visibility"
  std::vector<float> values;        // width * height * lights.size()
};
absl::StatusOr<ShadowmaskImage> ReadShadowmaskExr(const std::string& path);

}  // namespace pdsm

#endif  // PDSM_CLIENT_EXPORT_SHADOWMASK_H_
