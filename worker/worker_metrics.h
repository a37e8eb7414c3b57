// What pdsm-worker tells Prometheus (`pdsm-worker --metrics-listen ADDR`, GET /metrics;
// metrics/metrics_http_server.h): its tasks and where their time goes. Updated by the task
// threads as they finish tasks (atomics and lock-free histograms: safe from any thread); no
// job contents, no token (keep the port private, docs/service.md "Metrics").
#ifndef PDSM_WORKER_WORKER_METRICS_H_
#define PDSM_WORKER_WORKER_METRICS_H_

#include <atomic>
#include <cstdint>
#include <string>

#include "metrics/histogram.h"

namespace pdsm {

struct WorkerMetrics {
  std::atomic<int64_t> results_accepted{0};
  std::atomic<int64_t> results_dropped{0};      // the coordinator had moved on (stale)
  std::atomic<int64_t> results_undelivered{0};  // the call failed (coordinator away)
  std::atomic<int64_t> tasks_failed{0};
  std::atomic<int64_t> tasks_handed_back{0};
  std::atomic<int64_t> tasks_incompatible{0};
  std::atomic<int64_t> leases_lost{0};  // dropped mid-task: expired or the job ended
  std::atomic<int64_t> events{0};       // in delivered results
  std::atomic<int> tasks_running{0};
  Histogram task_seconds{SecondsBuckets()};        // lease to result, per task
  Histogram shadow_map_seconds{SecondsBuckets()};  // rendering + read-back, per task
  Histogram scan_seconds{SecondsBuckets()};        // scan conversion + sorting, per task
};

// The Prometheus text of `m`, with `threads` (task threads) and the build's labels.
std::string RenderWorkerMetrics(const WorkerMetrics& m, int threads);

}  // namespace pdsm

#endif  // PDSM_WORKER_WORKER_METRICS_H_
