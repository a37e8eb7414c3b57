// `pdsm export-image`: a PDSM flattened into an ordinary picture that image viewers, compositors
// and engines open. One image pixel per PDSM pixel, oriented as the bake's light view (a
// camera at the light's centre looking along n with v up, so light-space u runs right to left
// on screen): image pixel (column c, row r from the top) is PDSM pixel
// (width - 1 - c, height - 1 - r).
//
// Each pixel holds the attenuation (fraction of the light hidden, [0, 1]) of one point on that
// pixel's ray through its centre: at a fixed light-space depth (a plane z = Z, perpendicular
// to n), or on the nearest receiver of the scene the ray meets. The value is the pixel's own
// function at that depth (at a pixel centre the query's bilinear blend is that pixel alone),
// so it equals `pdsm query` at the same world point. NaN where the PDSM says nothing: no
// receiver on the ray, a depth nearer than the file's z_valid_min, outside a surfaces-only
// bake's windows.
#ifndef PDSM_CLIENT_EXPORT_ATTENUATION_IMAGE_H_
#define PDSM_CLIENT_EXPORT_ATTENUATION_IMAGE_H_

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/pdsm/pdsm_image.h"
#include "core/scene/scene.h"
#include "core/util/file_system.h"

namespace pdsm {

struct AttenuationImage {
  int width = 0, height = 0;
  std::vector<float> attenuation;  // row-major, row 0 at the top; NaN: undefined
  std::vector<float> depth;        // light-space depth of each pixel's point; NaN: none

  float At(int column, int row) const {
    return attenuation[static_cast<size_t>(row) * width + column];
  }
};

// Attenuation on the plane at light-space depth `z` (world units along n from the light's
// centre). INVALID_ARGUMENT for a z that is not finite.
absl::StatusOr<AttenuationImage> AttenuationOnPlane(const PdsmImage& pdsm, double z);

// Attenuation on the receivers of `scene` (meshes whose role receives) that each pixel's ray
// meets first, traced with Embree in float and the hit depth recomputed in double on the hit
// triangle's plane. The scene should be the one baked (CheckPdsmMatchesScene). INTERNAL when
// Embree fails.
absl::StatusOr<AttenuationImage> AttenuationOnReceivers(const PdsmImage& pdsm, const Scene& scene);

// Writes the image, chosen by the extension of `path` (case-insensitive), atomically (the old
// file stays whole on any failure):
//   .exr  scanline float channels, lossless (ZIP): Y = 1 - attenuation (the light's
//         visibility: lit is white in any viewer), A = 1 where defined and 0 elsewhere
//         (Y = 0 there: premultiplied), `attenuation` (NaN where undefined) and `depth`;
//         string attribute pdsmExport says what was sampled (`what`).
//   .png  8-bit gray + alpha: gray = round(255 (1 - attenuation)), linear (not sRGB-encoded,
//         so the value reads back to within 1/510), alpha 0 where undefined.
// INVALID_ARGUMENT for another extension; the file system's errors otherwise.
absl::Status WriteAttenuationImage(const AttenuationImage& image, const std::string& what,
                                   const std::string& path, FileSystem* fs = nullptr);

}  // namespace pdsm

#endif  // PDSM_CLIENT_EXPORT_ATTENUATION_IMAGE_H_
