// A PDSM header in the words users read it in: the names `pdsm info` prints and the JSON
// object `pdsm info --json` writes, which the Python module's `header` is too (one
// vocabulary for the CLI and for tools). JSON numbers are exact: 17 significant digits, so
// each reads back to the same double.
#ifndef PDSM_CORE_PDSM_PDSM_HEADER_JSON_H_
#define PDSM_CORE_PDSM_PDSM_HEADER_JSON_H_

#include <string>
#include <string_view>

#include "core/pdsm/pdsm_image.h"

namespace pdsm {

// A JSON string literal of `s` (quotes, backslashes and control characters escaped).
std::string JsonString(std::string_view s);

// The sampling pattern as `--sampling` takes it ("blue-noise").
const char* SamplingName(SamplingPattern pattern);

// "rect", "disk", "spot" (a disk with a cone), "sphere-face" (a disk, one face of a sphere
// light), "sun".
const char* LightKindName(const PdsmHeader& header);

// A sun's angular diameter, degrees (0 for other lights).
double SunDiameterDegrees(const PdsmHeader& header);

// How many samples an adaptive bake's tiles took (header.tile_samples): the least, the
// most and the mean. With no list: min is header.samples, max and mean 0.
struct TileSampleCounts {
  int min = 0, max = 0;
  double mean = 0;
};
TileSampleCounts CountTileSamples(const PdsmHeader& header);

// The header as one JSON object: formatVersion, scene, name (named lights only), light,
// projection, resolution, window, depthRange, lightCenter, lightNormal, samples,
// shadowMapResolution, epsilon, depthBias, slopeBias, tileSize, sampling, seed (a string:
// 64 bits), the light's size (lightSize, lightRadius [+ coneHalfAngleDeg] or
// angularDiameterDeg), then `extra_members` (", \"key\": value" pairs, or ""), then the
// adaptive members (adaptiveTolerance, adaptiveMinSamples, tileSamples {min, mean, max}) when
// adaptive, surfacesOnly, zValidMin and weighting ("unweighted" or "emitter").
std::string PdsmHeaderJson(const PdsmHeader& header, std::string_view extra_members = {});

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_PDSM_HEADER_JSON_H_
