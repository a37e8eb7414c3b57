// QueryAttenuation's PDSM: the lights of the job queried last, kept in memory for the next
// query of the same job and light (clients query in batches).
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
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

struct QueryAnswer {
  std::vector<std::string> lights;  // the lights answered for, in file (scene) order
  // Point-major: point p's value for lights[l] is attenuation[p * lights.size() + l].
  std::vector<double> attenuation;
};

// Thread-safe; queries run in parallel, a miss reads the file outside the lock.
class QueryCache {
 public:
  // The attenuation at each world point (NaN outside a light's frustum) from the finished
  // PDSM of `job_id` at `pdsm_path`: of the light named `light`, or of every light when it is
  // empty. Errors of ReadPdsmLights (NOT_FOUND naming the lights for no such light).
  absl::StatusOr<QueryAnswer> Query(const std::string& job_id, const std::string& pdsm_path,
                                    std::string_view light,
                                    const std::vector<glm::dvec3>& points_world);

 private:
  using Lights = std::vector<PdsmImage>;
  absl::Mutex mu_;
  std::string job_id_ ABSL_GUARDED_BY(mu_);
  std::string light_ ABSL_GUARDED_BY(mu_);
  std::shared_ptr<const Lights> lights_ ABSL_GUARDED_BY(mu_);
};

}  // namespace pdsm

#endif  // PDSM_SERVER_QUERY_CACHE_H_
