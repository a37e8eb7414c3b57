// `pdsm fetch JOB -o OUT.exr`: downloads a finished job's PDSM. Written under a temporary
// name and renamed when complete, so an interrupted download leaves nothing at OUT.
#include <cstdio>
#include <filesystem>

#include "absl/strings/str_cat.h"
#include "client/cli_common.h"
#include "client/commands.h"
#include "client/service/service_connection.h"

namespace pdsm {
namespace {

struct FetchFlags {
  std::string job_id;
  std::string output_path;
  ServiceFlags service;
};

absl::Status Fetch(const FetchFlags& flags, const std::string& temp) {
  absl::StatusOr<ServiceConnection> c = Connect(flags.service);
  if (!c.ok()) return c.status();
  absl::StatusOr<uint64_t> received = DownloadPdsm(*c, flags.service, flags.job_id, temp);
  if (!received.ok()) return received.status();
  std::error_code ec;
  std::filesystem::rename(temp, flags.output_path, ec);
  if (ec) return absl::InternalError(absl::StrCat("-o: ", flags.output_path, ": ", ec.message()));
  std::printf("pdsm: %s (%llu bytes)\n", flags.output_path.c_str(),
              static_cast<unsigned long long>(*received));
  return absl::OkStatus();
}

int RunFetch(const FetchFlags& flags) {
  const std::string temp = flags.output_path + ".part";
  absl::Status s = Fetch(flags, temp);
  if (!s.ok()) {
    std::error_code ec;
    std::filesystem::remove(temp, ec);
    return ReportError(s);
  }
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
