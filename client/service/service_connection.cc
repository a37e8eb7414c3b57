#include "client/service/service_connection.h"

#include <memory>

#include "absl/strings/str_cat.h"
#include "core/util/atomic_file.h"
#include "rpc/grpc_support.h"

namespace pdsm {

void AddServiceFlags(CLI::App* command, ServiceFlags* flags, bool required) {
  command->add_option("--server", flags->server, "Coordinator address host:port")
      ->envname("PDSM_SERVER")
      ->required(required);
  command
      ->add_option("--token-file", flags->token_file,
                   "File holding the client token (status, list, watch and stats also take the "
                   "coordinator's monitoring token)")
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
                                      const std::string& job_id, const std::string& path,
                                      FileSystem* fs) {
  pdsm::v1::GetJobRequest request;
  request.set_job_id(job_id);
  auto context = c.Call(std::chrono::hours(1));
  auto reader = c.stub->FetchPdsm(context.get(), request);
  return ReceivePdsm(context.get(), reader.get(), job_id, service.server, path, fs);
}

absl::StatusOr<uint64_t> ReceivePdsm(grpc::ClientContext* context,
                                     grpc::ClientReaderInterface<pdsm::v1::PdsmChunk>* reader,
                                     const std::string& job_id, const std::string& server,
                                     const std::string& path, FileSystem* fs) {
  absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(path, fs);
  if (!file.ok()) {
    // Nothing to write to: end the call rather than let the coordinator stream into the void.
    context->TryCancel();
    static_cast<void>(reader->Finish());  // CANCELLED: the error to report is ours
    return file.status();
  }
  pdsm::v1::PdsmChunk chunk;
  uint64_t total = 0, received = 0;
  bool first = true;
  while (reader->Read(&chunk)) {
    if (first) total = chunk.total_bytes(), first = false;
    const absl::string_view data(chunk.data().data(), chunk.data().size());
    if (absl::Status s = (*file)->Append(data); !s.ok()) {
      context->TryCancel();
      static_cast<void>(reader->Finish());
      return s;
    }
    received += chunk.data().size();
  }
  if (grpc::Status s = reader->Finish(); !s.ok()) {
    return CallError("fetching job " + job_id, s, server);
  }
  if (received != total) {
    return absl::DataLossError(
        absl::StrCat("fetching job ", job_id, ": got ", received, " of ", total, " bytes"));
  }
  if (absl::Status s = (*file)->Commit(); !s.ok()) return s;
  return received;
}

}  // namespace pdsm
