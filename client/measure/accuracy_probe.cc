#include "client/measure/accuracy_probe.h"

#include <chrono>

#include "absl/strings/str_format.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"
#include "core/util/atomic_file.h"

namespace pdsm {

absl::StatusOr<AccuracyProbe> AccuracyProbe::Create(const Scene& scene,
                                                    const AccuracyPointCounts& counts,
                                                    uint64_t seed,
                                                    const ReferenceOptions& reference) {
  AccuracyProbe probe;
  absl::StatusOr<AccuracyPoints> points = MakeAccuracyPoints(scene, counts, seed);
  if (!points.ok()) return points.status();
  probe.points_ = *std::move(points);
  probe.method_ = ResolveReferenceMethod(reference.method, scene);
  const auto start = std::chrono::steady_clock::now();
  for (auto [set, values] : {std::pair{&probe.points_.surface, &probe.surface_reference_},
                             std::pair{&probe.points_.free_space, &probe.free_space_reference_},
                             std::pair{&probe.points_.band, &probe.band_reference_}}) {
    absl::StatusOr<std::vector<double>> reference_values =
        ReferenceAttenuation(scene, *set, reference);
    if (!reference_values.ok()) return reference_values.status();
    *values = *std::move(reference_values);
  }
  probe.reference_seconds_ =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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
  const std::vector<double> band = query(points_.band);
  BakeErrors errors;
  errors.surface = CompareAttenuation(surface, surface_reference_);
  errors.free_space = CompareAttenuation(free_space, free_space_reference_);
  errors.band = CompareAttenuation(band, band_reference_);
  std::vector<double> all, all_reference, penumbra, penumbra_reference;
  for (auto [values, reference] :
       {std::pair{&surface, &surface_reference_}, std::pair{&free_space, &free_space_reference_},
        std::pair{&band, &band_reference_}}) {
    all.insert(all.end(), values->begin(), values->end());
    all_reference.insert(all_reference.end(), reference->begin(), reference->end());
    for (size_t k = 0; k < values->size(); ++k) {
      if ((*reference)[k] > 0.0 && (*reference)[k] < 1.0) {
        penumbra.push_back((*values)[k]);
        penumbra_reference.push_back((*reference)[k]);
      }
    }
  }
  errors.all = CompareAttenuation(all, all_reference);
  errors.penumbra = CompareAttenuation(penumbra, penumbra_reference);
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
  append("band", points_.band, band_reference_);
  return WriteFileAtomically(path, csv, fs);
}

}  // namespace pdsm
