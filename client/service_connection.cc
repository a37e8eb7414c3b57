#include "client/service_connection.h"

#include "absl/strings/str_cat.h"
#include "proto/grpc_support.h"

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

}  // namespace pdsm
