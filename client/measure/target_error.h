// `pdsm bake … --target-error E`: choose the bake knobs that reach a mean absolute attenuation
// error E (over accuracy points on the receivers and in a band above them where objects go,
// against the reference) at the least predicted bake time, bake, and check E on points of the
// same region that the choice never saw.
//
// How: four cheap pilot bakes, N0 = 8, 32, 128 samples at R0 = 64 pixels and 32 samples at
// 2 R0 (the shadow map follows the PDSM at 2R texels, epsilon is held at E/4), fit
//   e(N, R) = sqrt((a N^-k)^2 + (b (R / R0)^-m)^2)
// (independent errors add in quadrature: k and a from the squared differences along N, k >= 1/2;
// b and m from what sampling leaves at R0 and 2 R0) and a cost model t = f + g N (R/R0)^beta.
// The cheapest (N, R) predicted to meet E with a 25 % margin is baked and measured on the same
// points; if it misses E, the demand is raised by the miss and a costlier configuration is baked,
// at most kMaxRebakes times. Knobs the user set on the command line are kept as given.
#ifndef PDSM_CLIENT_MEASURE_TARGET_ERROR_H_
#define PDSM_CLIENT_MEASURE_TARGET_ERROR_H_

#include <optional>
#include <string>
#include <utility>

#include "absl/status/statusor.h"
#include "client/measure/accuracy_probe.h"
#include "client/measure/bake_knobs.h"

namespace pdsm {

inline constexpr int kMaxRebakes = 3;

struct TargetErrorOptions {
  std::string scene_path;
  std::string output_path;
  double target = 0.01;
  // Knobs fixed by the user (unset: chosen).
  std::optional<int> samples, sm_resolution;
  std::optional<std::pair<int, int>> resolution;
  std::optional<double> epsilon, depth_bias;
  std::string sampling;  // "" : the scene's
  int threads = 0;
  // Where E is measured: on the receivers and in the band above them (AccuracyPointCounts;
  // band_height 0: DefaultBandHeight). The chooser fits on one draw of these points; whether
  // E is met is judged on a second draw from the same region that it never saw.
  int surface_points = 300, band_points = 300;
  double band_height = 0;
};

struct TargetErrorResult {
  BakeKnobs knobs;           // of the bake left at output_path
  double predicted = 0;      // the model's error for it
  BakeErrors measured;       // on the points the chooser fitted its model on
  BakeErrors held_out;       // on points from the same region it never saw: what `met` means
  double band_height = 0;    // of both point sets, world units
  double seconds = 0;        // its bake time
  double total_seconds = 0;  // pilots, reference and every bake
  int bakes = 0;             // pilots included
  bool met = false;          // held_out.all.mean <= target
};

// Progress and the model go to stderr. The PDSM at output_path is always the last complete bake
// (also when the target was missed: met = false). Errors: those of loading the scene, the reference
// and the bakes.
absl::StatusOr<TargetErrorResult> BakeToTargetError(const TargetErrorOptions& options);

}  // namespace pdsm

#endif  // PDSM_CLIENT_MEASURE_TARGET_ERROR_H_
