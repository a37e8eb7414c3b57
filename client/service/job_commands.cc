// `pdsm status | list | cancel | stats`: look at and steer jobs on a coordinator.
#include <cstdio>
#include <ctime>

#include <google/protobuf/util/json_util.h>

#include "absl/strings/str_format.h"
#include "client/cli_common.h"
#include "client/commands.h"
#include "client/service/service_connection.h"

namespace pdsm {
namespace {

struct JobFlags {
  std::string job_id;
  ServiceFlags service;
  bool json = false;
  int limit = 20;
};

std::string ToJson(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  options.always_print_primitive_fields = true;  // `progress: 0` must be there, not omitted
  std::string json;
  (void)google::protobuf::util::MessageToJsonString(message, &json, options);
  return json;
}

std::string LocalTime(int64_t unix_ms) {
  const std::time_t t = static_cast<std::time_t>(unix_ms / 1000);
  std::tm tm{};
  localtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%d %H:%M:%S", &tm);
  return text;
}

void PrintJob(const pdsm::v1::Job& job) {
  std::printf("job %s \"%s\": %s, %.1f%% (%d/%d tiles)", job.job_id().c_str(),
              job.scene_name().c_str(), pdsm::v1::JobState_Name(job.state()).c_str(),
              100 * job.progress(), job.tiles_done(), job.tiles_total());
  if (job.eta_seconds() > 0) std::printf(", ETA %.0fs", job.eta_seconds());
  if (job.lights_size() > 1) {
    std::printf("\n  %d lights, priority %d, submitted %s\n", job.lights_size(), job.priority(),
                LocalTime(job.created_unix_ms()).c_str());
    for (const pdsm::v1::LightProgress& light : job.lights()) {
      std::printf("  light %s: %dx%d, %d samples, %.1f%% (%d/%d tiles)\n", light.name().c_str(),
                  light.width(), light.height(), light.samples(), 100 * light.progress(),
                  light.tiles_done(), light.tiles_total());
    }
  } else {
    std::printf("\n  %dx%d, %d samples, priority %d, submitted %s\n", job.width(), job.height(),
                job.samples(), job.priority(), LocalTime(job.created_unix_ms()).c_str());
  }
  for (const pdsm::v1::LightProgress& light : job.lights()) {
    if (!light.has_refinement_level()) continue;
    const pdsm::v1::RefinementLevelProgress& level = light.refinement_level();
    std::printf("  %s%srefinement level %dx: %lld pixels, %.1f%% (%d/%d tiles)",
                light.name().c_str(), light.name().empty() ? "" : ": ", level.factor(),
                static_cast<long long>(level.pixels()), 100 * level.progress(), level.tiles_done(),
                level.tiles_total());
    if (level.eta_seconds() > 0) std::printf(", ETA %.0fs", level.eta_seconds());
    std::printf("\n");
  }
  if (!job.queued_reason().empty()) std::printf("  %s\n", job.queued_reason().c_str());
  if (!job.error().empty()) std::printf("  error: %s\n", job.error().c_str());
  if (job.pdsm_bytes() > 0)
    std::printf("  PDSM: %llu bytes\n", static_cast<unsigned long long>(job.pdsm_bytes()));
}

int RunStatus(const JobFlags& flags) {
  absl::StatusOr<ServiceConnection> c = Connect(flags.service);
  if (!c.ok()) return ReportError(c.status());
  pdsm::v1::GetJobRequest request;
  request.set_job_id(flags.job_id);
  pdsm::v1::Job job;
  if (grpc::Status s = c->stub->GetJob(c->Call().get(), request, &job); !s.ok()) {
    return ReportError(CallError("job " + flags.job_id, s, flags.service.server));
  }
  if (flags.json) {
    std::printf("%s\n", ToJson(job).c_str());
  } else {
    PrintJob(job);
  }
  return kExitOk;
}

int RunList(const JobFlags& flags) {
  absl::StatusOr<ServiceConnection> c = Connect(flags.service);
  if (!c.ok()) return ReportError(c.status());
  pdsm::v1::ListJobsRequest request;
  request.set_limit(flags.limit);
  pdsm::v1::ListJobsResponse response;
  if (grpc::Status s = c->stub->ListJobs(c->Call().get(), request, &response); !s.ok()) {
    return ReportError(CallError("listing jobs", s, flags.service.server));
  }
  if (flags.json) {
    std::printf("%s\n", ToJson(response).c_str());
    return kExitOk;
  }
  std::printf("%-16s  %-9s  %6s  %-19s  %s\n", "JOB", "STATE", "DONE", "SUBMITTED", "SCENE");
  for (const pdsm::v1::Job& job : response.jobs()) {
    std::printf("%-16s  %-9s  %5.1f%%  %-19s  %s\n", job.job_id().c_str(),
                pdsm::v1::JobState_Name(job.state()).c_str(), 100 * job.progress(),
                LocalTime(job.created_unix_ms()).c_str(), job.scene_name().c_str());
  }
  return kExitOk;
}

int RunCancel(const JobFlags& flags) {
  absl::StatusOr<ServiceConnection> c = Connect(flags.service);
  if (!c.ok()) return ReportError(c.status());
  pdsm::v1::GetJobRequest request;
  request.set_job_id(flags.job_id);
  pdsm::v1::Job job;
  if (grpc::Status s = c->stub->CancelJob(c->Call().get(), request, &job); !s.ok()) {
    return ReportError(CallError("cancelling job " + flags.job_id, s, flags.service.server));
  }
  std::printf("job %s: %s\n", job.job_id().c_str(), pdsm::v1::JobState_Name(job.state()).c_str());
  return kExitOk;
}

int RunStats(const JobFlags& flags) {
  absl::StatusOr<ServiceConnection> c = Connect(flags.service);
  if (!c.ok()) return ReportError(c.status());
  pdsm::v1::Stats stats;
  if (grpc::Status s = c->stub->GetStats(c->Call().get(), {}, &stats); !s.ok()) {
    return ReportError(CallError("stats", s, flags.service.server));
  }
  if (flags.json) {
    std::printf("%s\n", ToJson(stats).c_str());
    return kExitOk;
  }
  std::printf(
      "jobs: %d running, %d queued (%d of them waiting for coordinator memory)\n"
      "planned memory: %.1f of %.0f MiB\n"
      "tasks: %d pending (queue depth), %d leased; %d tiles in flight\n"
      "workers: %d active, %d (job, worker) pairs incompatible (another build)\n"
      "throughput (last 60 s): %.2f tasks/s, %.3g events/s\n"
      "since start (%.0f s): %lld results accepted, %lld dropped, %lld leases expired\n"
      "verification: %d tasks awaiting a vote; since start %lld agreed, %lld decided against "
      "a worker, %lld unverified (no second worker); %d workers quarantined\n",
      stats.jobs_running(), stats.jobs_queued(), stats.jobs_waiting_for_memory(),
      static_cast<double>(stats.planned_bytes()) / (1 << 20),
      static_cast<double>(stats.max_planned_bytes()) / (1 << 20), stats.tasks_pending(),
      stats.tasks_leased(), stats.tiles_in_flight(), stats.workers_active(),
      stats.workers_incompatible(), stats.tasks_per_second(), stats.events_per_second(),
      stats.uptime_seconds(), static_cast<long long>(stats.tasks_accepted()),
      static_cast<long long>(stats.results_dropped()),
      static_cast<long long>(stats.leases_expired()), stats.tasks_awaiting_verification(),
      static_cast<long long>(stats.tasks_verified()),
      static_cast<long long>(stats.verification_mismatches()),
      static_cast<long long>(stats.tasks_unverified()), stats.workers_quarantined());
  return kExitOk;
}

CLI::App* JobCommand(CLI::App& app, const char* name, const char* help,
                     std::shared_ptr<JobFlags> flags, bool takes_job) {
  CLI::App* cmd = app.add_subcommand(name, help);
  if (takes_job) cmd->add_option("job", flags->job_id, "Job id")->required();
  AddServiceFlags(cmd, &flags->service);
  return cmd;
}

}  // namespace

void RegisterJobCommands(CLI::App& app, int* exit_code) {
  auto status = std::make_shared<JobFlags>();
  JobCommand(app, "status", "A job's state and progress", status, true)
      ->callback([status, exit_code] { *exit_code = RunStatus(*status); })
      ->add_flag("--json", status->json, "One JSON object (fields of pdsm.v1.Job)");

  auto list = std::make_shared<JobFlags>();
  CLI::App* list_cmd =
      JobCommand(app, "list", "Jobs on the coordinator, newest first", list, false);
  list_cmd->add_flag("--json", list->json, "JSON output");
  list_cmd->add_option("--limit", list->limit, "At most this many jobs")
      ->check(CLI::Range(1, 10000));
  list_cmd->callback([list, exit_code] { *exit_code = RunList(*list); });

  auto cancel = std::make_shared<JobFlags>();
  JobCommand(app, "cancel", "Cancel a queued or running job", cancel, true)
      ->callback([cancel, exit_code] { *exit_code = RunCancel(*cancel); });

  auto stats = std::make_shared<JobFlags>();
  JobCommand(app, "stats", "Coordinator load: queue depth, workers, throughput", stats, false)
      ->callback([stats, exit_code] { *exit_code = RunStats(*stats); })
      ->add_flag("--json", stats->json, "JSON output");
}

}  // namespace pdsm
