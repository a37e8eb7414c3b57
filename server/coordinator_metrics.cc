#include "server/coordinator_metrics.h"

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "core/util/version.h"
#include "metrics/prometheus_text.h"
#include "server/failure_codes.h"

namespace pdsm {

std::string RenderCoordinatorMetrics(const CoordinatorMetrics& m) {
  PrometheusText out;
  out.Family("pdsm_build_info", "gauge", "The coordinator's build: always 1, labelled.");
  out.Sample("pdsm_build_info", 1,
             {{"version", std::string(ProjectVersion())}, {"commit", std::string(GitCommit())}});
  out.Gauge("pdsm_uptime_seconds", "Seconds since the coordinator started.", m.uptime_seconds);

  out.Family("pdsm_jobs", "gauge", "Jobs in the data dir, by state.");
  for (int s = pdsm::v1::QUEUED; s <= pdsm::v1::CANCELLED; ++s) {
    const auto state = static_cast<pdsm::v1::JobState>(s);
    if (!pdsm::v1::JobState_IsValid(s)) continue;
    const auto it = m.jobs.find(state);
    out.Sample("pdsm_jobs", it == m.jobs.end() ? 0.0 : static_cast<double>(it->second.jobs),
               {{"state", absl::AsciiStrToLower(pdsm::v1::JobState_Name(state))}});
  }
  const auto succeeded = m.jobs.find(pdsm::v1::SUCCEEDED);
  out.Gauge("pdsm_pdsm_bytes_stored", "Bytes of the finished PDSM files in the data dir.",
            succeeded == m.jobs.end() ? 0.0 : static_cast<double>(succeeded->second.pdsm_bytes));

  const SchedulerStats& s = m.engine.scheduler;
  out.Family("pdsm_tasks", "gauge", "Tasks of jobs in progress: waiting for a worker, or leased.");
  out.Sample("pdsm_tasks", s.tasks_pending, {{"state", "pending"}});
  out.Sample("pdsm_tasks", s.tasks_leased, {{"state", "leased"}});
  out.Gauge("pdsm_tiles_in_flight", "Tiles whose partial results the coordinator holds.",
            s.tiles_open);
  out.Gauge("pdsm_workers_active", "Workers heard from in the last 30 s, less those signed off.",
            s.workers_active);
  out.Gauge("pdsm_workers_incompatible",
            "(job, worker) pairs of jobs in progress where the worker plans the job differently "
            "(another build).",
            s.workers_incompatible);
  out.Gauge("pdsm_planned_bytes",
            "Bytes the plans of the running jobs hold (samples, surfaces-only receivers, scenes, "
            "a bit per tile and a few words per group).",
            static_cast<double>(m.planned_bytes));
  out.Gauge("pdsm_planned_bytes_limit", "--max-planned-mib, in bytes.",
            static_cast<double>(m.max_planned_bytes));
  out.Gauge("pdsm_jobs_waiting_for_memory",
            "Jobs QUEUED without their plans until these fit beside the running jobs'.",
            m.jobs_waiting_for_memory);
  out.Gauge("pdsm_workers_quarantined",
            "Workers verification outvoted since the coordinator started; they get no tasks.",
            s.workers_quarantined);
  out.Family("pdsm_verifications_total", "counter",
             "Tasks drawn for verification: agreed (two workers, same bytes), mismatch (decided "
             "against a disagreeing worker), unverified (accepted on one result: no second "
             "worker was active).");
  out.Sample("pdsm_verifications_total", static_cast<double>(s.tasks_verified),
             {{"outcome", "agreed"}});
  out.Sample("pdsm_verifications_total", static_cast<double>(s.verification_mismatches),
             {{"outcome", "mismatch"}});
  out.Sample("pdsm_verifications_total", static_cast<double>(s.tasks_unverified),
             {{"outcome", "unverified"}});
  out.Counter("pdsm_leases_issued_total", "Task leases issued.",
              static_cast<double>(s.leases_issued));
  out.Counter("pdsm_leases_expired_total", "Leases that expired (a dead or stalled worker).",
              static_cast<double>(s.leases_expired));
  out.Family("pdsm_results_total", "counter",
             "Task results, accepted or dropped (late, duplicate).");
  out.Sample("pdsm_results_total", static_cast<double>(s.results_accepted),
             {{"outcome", "accepted"}});
  out.Sample("pdsm_results_total", static_cast<double>(s.results_dropped),
             {{"outcome", "dropped"}});
  out.Family("pdsm_task_returns_total", "counter",
             "Tasks a worker gave back: failed (counts against it), handed back (stopping), "
             "incompatible (another build).");
  out.Sample("pdsm_task_returns_total", static_cast<double>(s.tasks_failed), {{"kind", "failed"}});
  out.Sample("pdsm_task_returns_total", static_cast<double>(s.tasks_handed_back),
             {{"kind", "handed_back"}});
  out.Sample("pdsm_task_returns_total", static_cast<double>(s.tasks_incompatible),
             {{"kind", "incompatible"}});
  // Every code, zeros included, so that rate() and alerts see a series from the start.
  out.Family("pdsm_task_failures_total", "counter",
             "Failed tasks (kind=\"failed\" above) by the status code the worker reported.");
  for (const absl::StatusCode c : kFailureCodes) {
    const auto it = s.tasks_failed_by_code.find(c);
    out.Sample("pdsm_task_failures_total",
               it == s.tasks_failed_by_code.end() ? 0.0 : static_cast<double>(it->second),
               {{"code", absl::AsciiStrToLower(absl::StatusCodeToString(c))}});
  }
  out.Gauge("pdsm_tasks_per_second", "Accepted task results per second, over the last minute.",
            m.engine.tasks_per_second);
  out.Gauge("pdsm_events_per_second",
            "Shadow events in accepted results per second, over the "
            "last minute.",
            m.engine.events_per_second);
  out.HistogramFamily("pdsm_task_seconds",
                      "Seconds a worker spent on a task (shadow maps and scan conversion), "
                      "accepted results.",
                      m.task_seconds);
  out.Family("pdsm_job_progress", "gauge", "Fraction of a job in progress that is done.");
  for (const auto& [job_id, progress] : m.job_progress) {
    out.Sample("pdsm_job_progress", progress, {{"job", job_id}});
  }
  return out.text();
}

}  // namespace pdsm
