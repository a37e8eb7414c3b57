// QueryAttenuation's PDSM: the file of the job queried last, kept in memory for the next
// query of the same job (clients query in batches).
#ifndef PDSM_SERVER_QUERY_CACHE_H_
#define PDSM_SERVER_QUERY_CACHE_H_

#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "absl/base/thread_annotations.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

// Thread-safe; queries run in parallel, a miss reads the file outside the lock.
class QueryCache {
 public:
  // The attenuation at each world point (NaN outside the frustum) from the finished PDSM of
  // `job_id` at `pdsm_path`. Errors of ReadPdsm.
  absl::StatusOr<std::vector<double>> Query(const std::string& job_id, const std::string& pdsm_path,
                                            const std::vector<glm::dvec3>& points_world);

 private:
  absl::Mutex mu_;
  std::string job_id_ ABSL_GUARDED_BY(mu_);
  std::shared_ptr<const PdsmImage> image_ ABSL_GUARDED_BY(mu_);
};

}  // namespace pdsm

#endif  // PDSM_SERVER_QUERY_CACHE_H_
