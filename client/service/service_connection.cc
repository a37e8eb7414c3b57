#include "client/service/service_connection.h"

#include <fstream>

#include "absl/strings/str_cat.h"
#include "rpc/grpc_support.h"

namespace pdsm {

void AddServiceFlags(CLI::App* command, ServiceFlags* flags, bool required) {
  command->add_option("--server", flags->server, "Coordinator address host:port")
      ->envname("PDSM_SERVER")
      ->required(required);
  command->add_option("--token-file", flags->token_file, "File holding the client token")
      ->envname("PDSM_TOKEN_FILE");
  command->add_option("--tls-ca", flags->tls_ca, "PEM roots to trust: connect with TLS");
}

std::unique_ptr<grpc::ClientContext> ServiceConnection::Call(
    std::chrono::milliseconds timeout) const {
  auto context = std::make_unique<grpc::ClientContext>();
  PrepareCall(context.get(), token, timeout);
  return context;
}

absl::StatusOr<ServiceConnection> Connect(const ServiceFlags& flags) {
  ServiceConnection connection;
  if (!flags.token_file.empty()) {
    absl::StatusOr<std::string> token = ReadTokenFile("--token-file", flags.token_file);
    if (!token.ok()) return token.status();
    connection.token = *token;
  }
  absl::StatusOr<std::shared_ptr<grpc::Channel>> channel =
      MakeChannel({flags.server, flags.tls_ca});
  if (!channel.ok()) return channel.status();
  connection.stub = pdsm::v1::PdsmJobs::NewStub(*channel);
  return connection;
}

absl::Status CallError(const std::string& what, const grpc::Status& status,
                       const std::string& server) {
  std::string hint;
  switch (status.error_code()) {
    case grpc::StatusCode::UNAVAILABLE:
      hint = absl::StrCat(" (is pdsm-coordinator running at ", server, "?)");
      break;
    case grpc::StatusCode::UNAUTHENTICATED:
      hint = " (pass the client token with --token-file)";
      break;
    default:
      break;
  }
  return absl::Status(static_cast<absl::StatusCode>(status.error_code()),
                      absl::StrCat(what, ": ", status.error_message(), hint));
}

absl::StatusOr<uint64_t> DownloadPdsm(const ServiceConnection& c, const ServiceFlags& service,
                                      const std::string& job_id, const std::string& path) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return absl::InvalidArgumentError(absl::StrCat("cannot write \"", path, "\""));
  pdsm::v1::GetJobRequest request;
  request.set_job_id(job_id);
  auto context = c.Call(std::chrono::hours(1));
  auto reader = c.stub->FetchPdsm(context.get(), request);
  pdsm::v1::PdsmChunk chunk;
  uint64_t total = 0, received = 0;
  bool first = true;
  while (reader->Read(&chunk)) {
    if (first) total = chunk.total_bytes(), first = false;
    out.write(chunk.data().data(), static_cast<std::streamsize>(chunk.data().size()));
    received += chunk.data().size();
  }
  if (grpc::Status s = reader->Finish(); !s.ok()) {
    return CallError("fetching job " + job_id, s, service.server);
  }
  out.close();
  if (!out) return absl::InternalError(absl::StrCat("writing \"", path, "\" failed"));
  if (received != total) {
    return absl::DataLossError(
        absl::StrCat("fetching job ", job_id, ": got ", received, " of ", total, " bytes"));
  }
  return received;
}

}  // namespace pdsm
