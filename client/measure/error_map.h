// Where a bake's error lives, not only its mean (issue #15 item 7): |PDSM − reference| at the
// receiver point each PDSM pixel's ray meets first — the points `pdsm export-image --surface`
// shows, so the map is that image's error — as numbers and as a picture with a colour scale.
// `pdsm compare` writes it for one file, `pdsm sweep` for its most accurate configuration.
//
// Both values at a point are what users get there: the PDSM's is `pdsm query`'s (a pixel
// centre's bilinear blend is that pixel alone), the reference's is `pdsm reference`'s. The
// point is the receiver's, moved toward the light along its ray by a millionth of its depth:
// exactly on a tilted receiver, rounding puts it behind its own triangle half the time, and
// the exact reference then says the receiver hides it (measured on the dragon: most of its
// light-facing surface read 1 there, in a salt-and-pepper pattern).
#ifndef PDSM_CLIENT_MEASURE_ERROR_MAP_H_
#define PDSM_CLIENT_MEASURE_ERROR_MAP_H_

#include <cmath>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/pdsm/pdsm_image.h"
#include "core/reference/reference_attenuation.h"
#include "core/scene/scene.h"
#include "core/util/file_system.h"

namespace pdsm {

// Image pixels in the light view of `pdsm export-image` (row 0 at the top; image pixel (c, r)
// of a step-1 map is PDSM pixel (width - 1 - c, height - 1 - r)). With `step` K, image pixel
// (c, r) is the step-1 map's pixel (K c, K r): every K-th ray in each direction.
struct ErrorMap {
  int width = 0, height = 0, step = 1;
  std::vector<float> pdsm;        // the PDSM's attenuation; NaN: no receiver, or undefined
  std::vector<float> reference;   // the reference's at the same point; NaN where pdsm is
  std::vector<glm::dvec3> point;  // that point, in world space; NaN where pdsm is
  ReferenceMethod method = ReferenceMethod::kExact;  // what the reference resolved to
  int reference_samples = 0;                         // its samples per point: Embree only

  double Error(size_t pixel) const {
    return std::abs(static_cast<double>(pdsm[pixel]) - static_cast<double>(reference[pixel]));
  }
};

struct ErrorStats99 {
  size_t count = 0;
  double mean = 0, p95 = 0, p99 = 0, max = 0;  // of |PDSM − reference|; 0 when count is 0
};

// `all`: every pixel with both values. `penumbra`: those whose reference is strictly between
// 0 and 1 (what the tables call penumbra texels; umbra and lit points are elsewhere).
struct ErrorMapSummary {
  ErrorStats99 all, penumbra;
};

// The map of `pdsm` (one light's image) against `scene` (its one light: OneLight). `step` >= 1
// bounds the reference's cost, which dominates: it is computed for (width / step) x
// (height / step) points. INVALID_ARGUMENT for step < 1; otherwise the errors of
// AttenuationOnReceivers and ReferenceAttenuation (UNIMPLEMENTED: exact on a sun).
absl::StatusOr<ErrorMap> MeasureErrorMap(const PdsmImage& pdsm, const Scene& scene,
                                         const ReferenceOptions& reference, int step);

ErrorMapSummary SummarizeErrorMap(const ErrorMap& map);

// The colour scale: |error| 0 -> dark purple ... `max_error` and above -> yellow (viridis,
// perceptually ordered and readable by the colour-blind), as 8-bit RGB. Pixels without a
// value are mid grey, which the scale never takes.
inline constexpr unsigned char kNoValueGrey = 96;
void ErrorColour(double error, double max_error, unsigned char rgb[3]);

// An 8-bit RGB PNG: the map, magnified by a whole factor to about 512 pixels across when it is
// smaller, above a legend (the colour bar from 0 to max_error, `title`, the summary). Written
// atomically. INVALID_ARGUMENT for max_error <= 0 or not finite; the file system's errors.
absl::Status WriteErrorMapPng(const ErrorMap& map, const ErrorMapSummary& summary, double max_error,
                              const std::string& title, const std::string& path,
                              FileSystem* fs = nullptr);

// The top of the colour scale unless asked otherwise: fixed, so that maps compare by eye.
inline constexpr double kDefaultErrorMapScale = 0.1;

// "|pdsm - exact| on the receivers, every pixel" (or "embree 4096 samples", "1 of 4x4 pixels").
std::string ErrorMapTitle(const ErrorMap& map);

// "mean 0.0031  p95 0.012  p99 0.021  max 0.14 (65536 px)" for logs and the legend.
std::string FormatErrorStats(const ErrorStats99& stats);

}  // namespace pdsm

#endif  // PDSM_CLIENT_MEASURE_ERROR_MAP_H_
