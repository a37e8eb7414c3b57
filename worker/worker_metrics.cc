#include "worker/worker_metrics.h"

#include "core/util/version.h"
#include "metrics/prometheus_text.h"

namespace pdsm {

std::string RenderWorkerMetrics(const WorkerMetrics& m, int threads) {
  const auto d = [](const std::atomic<int64_t>& v) { return static_cast<double>(v.load()); };
  PrometheusText out;
  out.Family("pdsm_worker_build_info", "gauge", "The worker's build: always 1, labelled.");
  out.Sample("pdsm_worker_build_info", 1,
             {{"version", std::string(ProjectVersion())}, {"commit", std::string(GitCommit())}});
  out.Gauge("pdsm_worker_threads", "Task threads (one OSMesa context each).", threads);
  out.Gauge("pdsm_worker_tasks_running", "Tasks being rendered now.", m.tasks_running.load());
  out.Family("pdsm_worker_results_total", "counter",
             "Task results: accepted, dropped as stale by the coordinator, or undelivered.");
  out.Sample("pdsm_worker_results_total", d(m.results_accepted), {{"outcome", "accepted"}});
  out.Sample("pdsm_worker_results_total", d(m.results_dropped), {{"outcome", "dropped"}});
  out.Sample("pdsm_worker_results_total", d(m.results_undelivered), {{"outcome", "undelivered"}});
  out.Family("pdsm_worker_task_returns_total", "counter",
             "Tasks given back: failed here, handed back (stopping), incompatible (another "
             "build).");
  out.Sample("pdsm_worker_task_returns_total", d(m.tasks_failed), {{"kind", "failed"}});
  out.Sample("pdsm_worker_task_returns_total", d(m.tasks_handed_back), {{"kind", "handed_back"}});
  out.Sample("pdsm_worker_task_returns_total", d(m.tasks_incompatible), {{"kind", "incompatible"}});
  out.Counter("pdsm_worker_leases_lost_total",
              "Tasks dropped mid-way because the lease was lost (expired, job ended).",
              d(m.leases_lost));
  out.Counter("pdsm_worker_events_total", "Shadow events in delivered results.", d(m.events));
  out.HistogramFamily("pdsm_worker_task_seconds", "Seconds from lease to result, per task.",
                      m.task_seconds.Read());
  out.HistogramFamily("pdsm_worker_shadow_map_seconds",
                      "Seconds rendering and reading back shadow maps, per task.",
                      m.shadow_map_seconds.Read());
  out.HistogramFamily("pdsm_worker_scan_seconds",
                      "Seconds of scan conversion and per-pixel sorting, per task.",
                      m.scan_seconds.Read());
  return out.text();
}

}  // namespace pdsm
