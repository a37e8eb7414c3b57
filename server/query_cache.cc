#include "server/query_cache.h"

#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"

namespace pdsm {

absl::StatusOr<std::vector<double>> QueryCache::Query(const std::string& job_id,
                                                      const std::string& pdsm_path,
                                                      const std::vector<glm::dvec3>& points_world) {
  std::shared_ptr<const PdsmImage> image;
  {
    absl::MutexLock lock(&mu_);
    if (job_id_ == job_id) image = image_;
  }
  if (!image) {
    absl::StatusOr<PdsmImage> read = ReadPdsm(pdsm_path);
    if (!read.ok()) return read.status();
    image = std::make_shared<const PdsmImage>(*std::move(read));
    absl::MutexLock lock(&mu_);
    job_id_ = job_id;
    image_ = image;
  }
  std::vector<double> out;
  out.reserve(points_world.size());
  for (const glm::dvec3& p : points_world) out.push_back(QueryAttenuation(*image, p));
  return out;
}

}  // namespace pdsm
