#include "server/query_cache.h"

#include <utility>

#include "core/pdsm/pdsm_file.h"

namespace pdsm {

absl::StatusOr<QueryAnswer> QueryCache::Query(const std::string& job_id,
                                              const std::string& pdsm_path, std::string_view light,
                                              const std::vector<glm::dvec3>& points_world) {
  std::shared_ptr<PdsmTileCache> cache;
  {
    absl::MutexLock lock(&mu_);
    if (job_id_ == job_id) cache = cache_;
  }
  if (!cache) {
    absl::StatusOr<PdsmReader> reader = PdsmReader::Open(pdsm_path);
    if (!reader.ok()) return reader.status();
    cache = std::make_shared<PdsmTileCache>(*std::move(reader), budget_bytes_);
    absl::MutexLock lock(&mu_);
    job_id_ = job_id;
    cache_ = cache;
  }
  const PdsmReader& reader = cache->reader();
  absl::StatusOr<std::vector<PdsmLightParts>> lights =
      SelectLights(reader.headers(), reader.path(), light);
  if (!lights.ok()) return lights.status();
  QueryAnswer answer;
  for (const PdsmLightParts& l : *lights) answer.lights.push_back(l.name);
  absl::StatusOr<std::vector<double>> values = AttenuationAt(*cache, *lights, points_world);
  if (!values.ok()) return values.status();
  answer.attenuation = *std::move(values);
  return answer;
}

}  // namespace pdsm
