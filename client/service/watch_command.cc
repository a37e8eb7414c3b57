// `pdsm watch JOB`: follows a job until it ends, with a progress bar and the coordinator's
// ETA. Exits 0 when the job succeeded, 1 when it failed or was cancelled.
#include <chrono>
#include <cstdio>

#include "client/cli_common.h"
#include "client/commands.h"
#include "client/progress_reporter.h"
#include "client/service/service_connection.h"

namespace pdsm {
namespace {

struct WatchFlags {
  std::string job_id;
  ServiceFlags service;
};

int RunWatch(const WatchFlags& flags) {
  absl::StatusOr<ServiceConnection> c = Connect(flags.service);
  if (!c.ok()) return ReportError(c.status());
  pdsm::v1::GetJobRequest request;
  request.set_job_id(flags.job_id);
  auto context = c->Call(std::chrono::hours(24 * 30));  // a watch lasts as long as the job
  auto reader = c->stub->WatchJob(context.get(), request);
  const auto start = std::chrono::steady_clock::now();
  ProgressReporter progress("job " + flags.job_id, "samples");
  pdsm::v1::Job job;
  bool any = false;
  while (reader->Read(&job)) {
    any = true;
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // The job's samples count its base maps; a running refinement level's join them, so that
    // the bar does not stand at 100 % while a level runs (it steps back when one starts).
    int64_t done = job.samples_done(), total = job.samples_total();
    for (const pdsm::v1::LightProgress& light : job.lights()) {
      if (!light.has_refinement_level()) continue;
      done += light.refinement_level().samples_done();
      total += light.refinement_level().samples_total();
    }
    progress.Update(
        done, total, seconds,
        job.eta_seconds() >= 0 ? std::optional<double>(job.eta_seconds()) : std::nullopt);
  }
  progress.Finish();
  if (grpc::Status s = reader->Finish(); !s.ok()) {
    return ReportError(CallError("watching job " + flags.job_id, s, flags.service.server));
  }
  if (!any) return ReportError(absl::UnavailableError("the watch ended without news"));
  std::printf("job %s: %s\n", job.job_id().c_str(), pdsm::v1::JobState_Name(job.state()).c_str());
  if (job.state() == pdsm::v1::SUCCEEDED) return kExitOk;
  if (!job.error().empty())
    std::fprintf(stderr, "pdsm: job %s: %s\n", job.job_id().c_str(), job.error().c_str());
  return kExitFailure;
}

}  // namespace

void RegisterWatchCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<WatchFlags>();
  CLI::App* cmd = app.add_subcommand("watch", "Follow a job until it ends");
  cmd->add_option("job", flags->job_id, "Job id")->required();
  AddServiceFlags(cmd, &flags->service);
  cmd->callback([flags, exit_code] { *exit_code = RunWatch(*flags); });
}

}  // namespace pdsm
