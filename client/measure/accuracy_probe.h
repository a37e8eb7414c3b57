// Measures baked PDSM files against the reference on a fixed set of accuracy points: the points and
// their reference attenuation are computed once (the expensive part), then each bake costs one
// query per point, through the same evaluation as `pdsm query`.
#ifndef PDSM_CLIENT_MEASURE_ACCURACY_PROBE_H_
#define PDSM_CLIENT_MEASURE_ACCURACY_PROBE_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/reference/accuracy_points.h"
#include "core/reference/reference_attenuation.h"
#include "core/scene/scene.h"
#include "core/util/file_system.h"

namespace pdsm {

struct BakeErrors {
  ErrorStats surface;     // points on receivers
  ErrorStats free_space;  // points in the frustum's free space
  ErrorStats band;        // points in the band above the receivers
  ErrorStats all;         // every set together: the "mean absolute error" of --target-error
  ErrorStats penumbra;    // the points of every set whose reference is strictly in (0, 1)
};

class AccuracyProbe {
 public:
  // Errors: those of MakeAccuracyPoints and ReferenceAttenuation.
  static absl::StatusOr<AccuracyProbe> Create(const Scene& scene, const AccuracyPointCounts& counts,
                                              uint64_t seed, const ReferenceOptions& reference);

  // Errors: those of ReadPdsm.
  absl::StatusOr<BakeErrors> Measure(const std::string& pdsm_path) const;

  // Writes "kind,x,y,z,attenuation" lines (kind: surface, free or band) with the reference values,
  // through WriteFileAtomically (core/util/atomic_file.h): on failure `path` is left as it
  // was. `fs` null means FileSystem::Default().
  absl::Status WriteReferenceCsv(const std::string& path, FileSystem* fs = nullptr) const;

  const AccuracyPoints& points() const { return points_; }
  double reference_seconds() const { return reference_seconds_; }
  ReferenceMethod method() const { return method_; }

 private:
  AccuracyPoints points_;
  std::vector<double> surface_reference_, free_space_reference_, band_reference_;
  double reference_seconds_ = 0;
  ReferenceMethod method_ = ReferenceMethod::kExact;
};

}  // namespace pdsm

#endif  // PDSM_CLIENT_MEASURE_ACCURACY_PROBE_H_
