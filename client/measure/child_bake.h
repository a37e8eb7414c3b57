// One bake run as a child `pdsm bake` process (fork/exec of this executable), so that each
// configuration of a sweep gets its own address space: the peak memory wait4() reports is that
// configuration's, not the high-water mark of everything before it.
#ifndef PDSM_CLIENT_MEASURE_CHILD_BAKE_H_
#define PDSM_CLIENT_MEASURE_CHILD_BAKE_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace pdsm {

struct ChildBakeResult {
  double seconds = 0;           // wall clock, fork to exit (includes loading the scene)
  uint64_t peak_rss_bytes = 0;  // the child's ru_maxrss
  uint64_t file_bytes = 0;      // the PDSM written
};

// Runs `pdsm bake SCENE -o OUTPUT --no-preview ARGS...`, the child's stdout and stderr going to
// `log_path`. Errors: INVALID_ARGUMENT when the child exits 2 (bad knob values), INTERNAL for any
// other failure; both quote the log's last line.
absl::StatusOr<ChildBakeResult> RunChildBake(const std::string& scene_path,
                                             const std::string& output_path,
                                             const std::vector<std::string>& args,
                                             const std::string& log_path);

}  // namespace pdsm

#endif  // PDSM_CLIENT_MEASURE_CHILD_BAKE_H_
