// `pdsm fetch JOB -o OUT.exr`: downloads a finished job's PDSM. Written through an AtomicFile
// (DownloadPdsm), so an interrupted or failed download leaves OUT as it was.
#include <cstdio>

#include "client/cli_common.h"
#include "client/commands.h"
#include "client/service/service_connection.h"
#include "core/util/output_path.h"

namespace pdsm {
namespace {

struct FetchFlags {
  std::string job_id;
  std::string output_path;
  ServiceFlags service;
};

absl::Status Fetch(const FetchFlags& flags) {
  if (absl::Status s = CheckOutputPath("-o", flags.output_path,
                                       {flags.service.token_file, flags.service.tls_ca});
      !s.ok()) {
    return s;
  }
  absl::StatusOr<ServiceConnection> c = Connect(flags.service);
  if (!c.ok()) return c.status();
  absl::StatusOr<uint64_t> received =
      DownloadPdsm(*c, flags.service, flags.job_id, flags.output_path);
  if (!received.ok()) return received.status();
  std::printf("pdsm: %s (%llu bytes)\n", flags.output_path.c_str(),
              static_cast<unsigned long long>(*received));
  return absl::OkStatus();
}

int RunFetch(const FetchFlags& flags) {
  if (absl::Status s = Fetch(flags); !s.ok()) return ReportError(s);
  return kExitOk;
}

}  // namespace

void RegisterFetchCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<FetchFlags>();
  CLI::App* cmd = app.add_subcommand("fetch", "Download a finished job's PDSM");
  cmd->add_option("job", flags->job_id, "Job id")->required();
  cmd->add_option("-o,--output", flags->output_path, "Output PDSM (.exr)")->required();
  AddServiceFlags(cmd, &flags->service);
  cmd->callback([flags, exit_code] { *exit_code = RunFetch(*flags); });
}

}  // namespace pdsm
