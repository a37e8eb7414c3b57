// `pdsm fetch JOB -o OUT.exr`: downloads a finished job's PDSM. Written under a temporary
// name and renamed when complete, so an interrupted download leaves nothing at OUT.
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "absl/strings/str_cat.h"
#include "client/cli_common.h"
#include "client/commands.h"
#include "client/service_connection.h"

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
  std::ofstream out(temp, std::ios::binary | std::ios::trunc);
  if (!out) return absl::InvalidArgumentError(absl::StrCat("-o: cannot write \"", temp, "\""));
  pdsm::v1::GetJobRequest request;
  request.set_job_id(flags.job_id);
  auto context = c->Call(std::chrono::hours(1));
  auto reader = c->stub->FetchPdsm(context.get(), request);
  pdsm::v1::PdsmChunk chunk;
  uint64_t total = 0, received = 0;
  bool first = true;
  while (reader->Read(&chunk)) {
    if (first) total = chunk.total_bytes(), first = false;
    out.write(chunk.data().data(), static_cast<std::streamsize>(chunk.data().size()));
    received += chunk.data().size();
  }
  if (grpc::Status s = reader->Finish(); !s.ok()) {
    return CallError("fetching job " + flags.job_id, s, flags.service.server);
  }
  out.close();
  if (!out) return absl::InternalError(absl::StrCat("writing \"", temp, "\" failed"));
  if (received != total) {
    return absl::DataLossError(absl::StrCat("fetching job ", flags.job_id, ": got ", received,
                                            " of ", total, " bytes"));
  }
  std::error_code ec;
  std::filesystem::rename(temp, flags.output_path, ec);
  if (ec) return absl::InternalError(absl::StrCat("-o: ", flags.output_path, ": ", ec.message()));
  std::printf("pdsm: %s (%llu bytes)\n", flags.output_path.c_str(),
              static_cast<unsigned long long>(received));
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
