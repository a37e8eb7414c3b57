// QueryAttenuation's PDSM: the file of the job queried last, open, with its tiles read on demand
// through a bounded cache (core/pdsm/pdsm_tile_cache.h) kept for the next query of the same job
// (clients query in batches). Memory stays within the cache's budget whatever the map's size.
#ifndef PDSM_SERVER_QUERY_CACHE_H_
#define PDSM_SERVER_QUERY_CACHE_H_

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "absl/base/thread_annotations.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "core/pdsm/pdsm_tile_cache.h"

namespace pdsm {

struct QueryAnswer {
  std::vector<std::string> lights;  // the lights answered for, in file (scene) order
  // Point-major: point p's value for lights[l] is attenuation[p * lights.size() + l].
  std::vector<double> attenuation;
};

// Thread-safe; queries run in parallel (they share the cache; a tile missing is read outside
// its lock).
class QueryCache {
 public:
  explicit QueryCache(int64_t budget_bytes = kDefaultTileCacheBytes)
      : budget_bytes_(budget_bytes) {}

  // The attenuation at each world point (NaN outside a light's frustum) from the finished
  // PDSM of `job_id` at `pdsm_path`: of the light named `light`, or of every light when it is
  // empty. Errors of PdsmReader (NOT_FOUND naming the lights for no such light).
  absl::StatusOr<QueryAnswer> Query(const std::string& job_id, const std::string& pdsm_path,
                                    std::string_view light,
                                    const std::vector<glm::dvec3>& points_world);

 private:
  const int64_t budget_bytes_;
  absl::Mutex mu_;
  std::string job_id_ ABSL_GUARDED_BY(mu_);
  std::shared_ptr<PdsmTileCache> cache_ ABSL_GUARDED_BY(mu_);
};

}  // namespace pdsm

#endif  // PDSM_SERVER_QUERY_CACHE_H_
