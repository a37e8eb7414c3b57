#include "client/measure/accuracy_probe.h"

#include <chrono>

#include "absl/strings/str_format.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"
#include "core/util/atomic_file.h"

namespace pdsm {

absl::StatusOr<AccuracyProbe> AccuracyProbe::Create(const Scene& scene, int surface_points,
                                                    int free_space_points, uint64_t seed,
                                                    const ReferenceOptions& reference) {
  AccuracyProbe probe;
  absl::StatusOr<AccuracyPoints> points =
      MakeAccuracyPoints(scene, surface_points, free_space_points, seed);
  if (!points.ok()) return points.status();
  probe.points_ = *std::move(points);
  probe.method_ = ResolveReferenceMethod(reference.method, scene.light);
  const auto start = std::chrono::steady_clock::now();
  absl::StatusOr<std::vector<double>> surface =
      ReferenceAttenuation(scene, probe.points_.surface, reference);
  if (!surface.ok()) return surface.status();
  absl::StatusOr<std::vector<double>> free_space =
      ReferenceAttenuation(scene, probe.points_.free_space, reference);
  if (!free_space.ok()) return free_space.status();
  probe.reference_seconds_ =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  probe.surface_reference_ = *std::move(surface);
  probe.free_space_reference_ = *std::move(free_space);
  return probe;
}

absl::StatusOr<BakeErrors> AccuracyProbe::Measure(const std::string& pdsm_path) const {
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(pdsm_path);
  if (!pdsm.ok()) return pdsm.status();
  auto query = [&](const std::vector<glm::dvec3>& points) {
    std::vector<double> values;
    values.reserve(points.size());
    for (const glm::dvec3& p : points) values.push_back(QueryAttenuation(*pdsm, p));
    return values;
  };
  const std::vector<double> surface = query(points_.surface);
  const std::vector<double> free_space = query(points_.free_space);
  BakeErrors errors;
  errors.surface = CompareAttenuation(surface, surface_reference_);
  errors.free_space = CompareAttenuation(free_space, free_space_reference_);
  std::vector<double> all = surface, all_reference = surface_reference_;
  all.insert(all.end(), free_space.begin(), free_space.end());
  all_reference.insert(all_reference.end(), free_space_reference_.begin(),
                       free_space_reference_.end());
  errors.all = CompareAttenuation(all, all_reference);
  return errors;
}

absl::Status AccuracyProbe::WriteReferenceCsv(const std::string& path, FileSystem* fs) const {
  std::string csv = "kind,x,y,z,attenuation\n";
  auto append = [&](const char* kind, const std::vector<glm::dvec3>& points,
                    const std::vector<double>& reference) {
    for (size_t i = 0; i < points.size(); ++i) {
      absl::StrAppendFormat(&csv, "%s,%.17g,%.17g,%.17g,%.6f\n", kind, points[i].x, points[i].y,
                            points[i].z, reference[i]);
    }
  };
  append("surface", points_.surface, surface_reference_);
  append("free", points_.free_space, free_space_reference_);
  return WriteFileAtomically(path, csv, fs);
}

}  // namespace pdsm
