#include "server/query_cache.h"

#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"

namespace pdsm {

absl::StatusOr<QueryAnswer> QueryCache::Query(const std::string& job_id,
                                              const std::string& pdsm_path, std::string_view light,
                                              const std::vector<glm::dvec3>& points_world) {
  std::shared_ptr<const Lights> lights;
  {
    absl::MutexLock lock(&mu_);
    if (job_id_ == job_id && light_ == light) lights = lights_;
  }
  if (!lights) {
    absl::StatusOr<Lights> read = ReadPdsmLights(pdsm_path, light);
    if (!read.ok()) return read.status();
    lights = std::make_shared<const Lights>(*std::move(read));
    absl::MutexLock lock(&mu_);
    job_id_ = job_id;
    light_ = std::string(light);
    lights_ = lights;
  }
  QueryAnswer answer;
  for (const PdsmImage& image : *lights) answer.lights.push_back(image.header.light_name);
  answer.attenuation.reserve(points_world.size() * lights->size());
  for (const glm::dvec3& p : points_world) {
    for (const PdsmImage& image : *lights) answer.attenuation.push_back(QueryAttenuation(image, p));
  }
  return answer;
}

}  // namespace pdsm
