// The coordinator's Prometheus metrics (`pdsm-coordinator --metrics-listen ADDR`, GET
// /metrics; metrics/metrics_http_server.h): what a farm operator graphs and alerts on. Job
// ids label the per-job progress; nothing else of a job (no scene, no names, no errors) is
// exposed, and no token is asked: keep the port private (docs/service.md, "Metrics").
#ifndef PDSM_SERVER_COORDINATOR_METRICS_H_
#define PDSM_SERVER_COORDINATOR_METRICS_H_

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/pipeline/bake_engine.h"
#include "metrics/histogram.h"
#include "pdsm/v1/jobs.pb.h"
#include "server/job_store.h"

namespace pdsm {

struct CoordinatorMetrics {
  EngineStats engine;
  std::map<pdsm::v1::JobState, JobStore::StateTotals> jobs;  // every job of the data dir
  Histogram::Snapshot task_seconds;  // worker-reported seconds of accepted results
  std::vector<std::pair<std::string, double>> job_progress;  // jobs in progress: id, [0, 1]
  double uptime_seconds = 0;
  // --max-planned-mib (server/plan_budget.h): held by the jobs running, the limit, and the
  // jobs waiting until theirs fit.
  int64_t planned_bytes = 0;
  int64_t max_planned_bytes = 0;
  int jobs_waiting_for_memory = 0;
};

// The Prometheus text of `m` (metric names: docs/service.md, "Metrics").
std::string RenderCoordinatorMetrics(const CoordinatorMetrics& m);

}  // namespace pdsm

#endif  // PDSM_SERVER_COORDINATOR_METRICS_H_
