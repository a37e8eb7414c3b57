// pdsm-coordinator: the bake service. Serves the job API and the worker API on one port,
// keeps job state under --data-dir, and resumes unfinished jobs on start.
#include <csignal>
#include <fstream>
#include <sstream>
#include <thread>

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include "absl/strings/str_cat.h"
#include "core/util/atomic_file.h"
#include "core/util/process_log.h"
#include "core/util/process_log_flags.h"
#include "core/util/version.h"
#include "metrics/metrics_http_server.h"
#include "rpc/grpc_support.h"
#include "server/caller_auth.h"
#include "server/coordinator.h"
#include "server/coordinator_metrics.h"
#include "server/jobs_service.h"
#include "server/workers_service.h"

namespace pdsm {
namespace {

struct Flags {
  std::string listen = "0.0.0.0:50051";
  std::string data_dir;
  std::string client_token_file, worker_token_file, monitor_token_file;
  std::string tls_cert, tls_key;
  std::string ready_file;
  std::string metrics_listen;  // empty: no /metrics
  std::string log_level = "info";
  std::string log_format = "text";  // --log-format: kLogFormatNames
  double lease_seconds = 30;
  int64_t event_memory_mib = kDefaultEventMemoryBudget >> 20;
  int64_t query_cache_mib = kDefaultTileCacheBytes >> 20;
  int max_message_bytes = kDefaultMaxMessageBytes;
  int64_t max_planned_mib = pdsm::kDefaultMaxPlannedBytes >> 20;
  CoordinatorOptions options;
};

absl::StatusOr<std::string> ReadWholeFile(const std::string& flag, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::InvalidArgumentError(absl::StrCat(flag, ": cannot read \"", path, "\""));
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> Credentials(const Flags& flags) {
  if (flags.tls_cert.empty() != flags.tls_key.empty()) {
    return absl::InvalidArgumentError("--tls-cert and --tls-key go together");
  }
  if (flags.tls_cert.empty()) return grpc::InsecureServerCredentials();
  absl::StatusOr<std::string> cert = ReadWholeFile("--tls-cert", flags.tls_cert);
  if (!cert.ok()) return cert.status();
  absl::StatusOr<std::string> key = ReadWholeFile("--tls-key", flags.tls_key);
  if (!key.ok()) return key.status();
  grpc::SslServerCredentialsOptions ssl;
  ssl.pem_key_cert_pairs.push_back({*key, *cert});
  return grpc::SslServerCredentials(ssl);
}

absl::StatusOr<std::string> OptionalToken(const std::string& flag, const std::string& path) {
  if (path.empty()) {
    spdlog::warn("{} not given: that API is open to anyone who can reach the port", flag);
    return std::string();
  }
  return ReadTokenFile(flag, path);
}

// Blocks until SIGTERM or SIGINT. The signals are blocked in every thread (set before any
// thread starts), so sigwait is the only place they arrive.
void WaitForStopSignal(const sigset_t& signals) {
  int signal = 0;
  sigwait(&signals, &signal);
  spdlog::info("signal {}: shutting down", signal);
}

int Run(Flags& flags, const sigset_t& signals) {
  // One named logger per process: every line says which component wrote it.
  SetUpProcessLog("coordinator", flags.log_level, flags.log_format);
  flags.options.lease_ms = static_cast<int64_t>(flags.lease_seconds * 1000);
  flags.options.event_memory_budget_bytes = flags.event_memory_mib << 20;
  flags.options.query_cache_bytes = flags.query_cache_mib << 20;
  absl::StatusOr<std::string> client_token =
      OptionalToken("--client-token-file", flags.client_token_file);
  absl::StatusOr<std::string> worker_token =
      OptionalToken("--worker-token-file", flags.worker_token_file);
  // The monitoring token is the one secret whose absence is normal: no warning for it.
  absl::StatusOr<std::string> monitor_token =
      flags.monitor_token_file.empty()
          ? std::string()
          : ReadTokenFile("--monitor-token-file", flags.monitor_token_file);
  absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> credentials = Credentials(flags);
  for (const absl::Status& s : {client_token.status(), worker_token.status(),
                                monitor_token.status(), credentials.status()}) {
    if (!s.ok()) {
      spdlog::error("{}", std::string(s.message()));
      return 2;
    }
  }
  if (!client_token->empty() && *client_token == *worker_token) {
    spdlog::error("--client-token-file and --worker-token-file must hold different secrets");
    return 2;
  }
  if (!monitor_token->empty()) {
    if (client_token->empty()) {
      spdlog::error(
          "--monitor-token-file needs --client-token-file: without a client token the whole job "
          "API is open, so a read-only token would restrict nothing");
      return 2;
    }
    if (*monitor_token == *client_token || *monitor_token == *worker_token) {
      spdlog::error(
          "--monitor-token-file must hold a secret of its own, not the client's or the worker's");
      return 2;
    }
  }
  flags.options.limits.max_planned_bytes = flags.max_planned_mib << 20;
  absl::StatusOr<std::unique_ptr<Coordinator>> coordinator = Coordinator::Start(flags.options);
  if (!coordinator.ok()) {
    spdlog::error("{}", std::string(coordinator.status().message()));
    return 1;
  }
  std::unique_ptr<MetricsHttpServer> metrics;
  if (!flags.metrics_listen.empty()) {
    Coordinator* c = coordinator->get();
    absl::StatusOr<std::unique_ptr<MetricsHttpServer>> started = MetricsHttpServer::Start(
        flags.metrics_listen, [c] { return RenderCoordinatorMetrics(c->Metrics()); });
    if (!started.ok()) {
      spdlog::error("{}", std::string(started.status().message()));
      return 2;
    }
    metrics = *std::move(started);
  }
  CallerAuth auth({.client = *client_token, .monitor = *monitor_token, .worker = *worker_token});
  JobsService jobs(coordinator->get(), &auth);
  WorkersService workers(coordinator->get(), &auth);

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(flags.listen, *credentials, &port);
  builder.SetMaxReceiveMessageSize(flags.max_message_bytes);
  builder.SetMaxSendMessageSize(kDefaultMaxMessageBytes);
  builder.RegisterService(&jobs);
  builder.RegisterService(&workers);
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (!server || port == 0) {
    spdlog::error("--listen: cannot listen on {}", flags.listen);
    return 1;
  }
  // Per service as well as for the whole server (""), so a probe can ask for either API.
  if (grpc::HealthCheckServiceInterface* health = server->GetHealthCheckService()) {
    for (const char* service :
         {pdsm::v1::PdsmJobs::service_full_name(), pdsm::v1::PdsmWorkers::service_full_name()}) {
      health->SetServingStatus(service, true);
    }
  }
  const std::string address =
      absl::StrCat(flags.listen.substr(0, flags.listen.rfind(':')), ":", port);
  spdlog::info("listening on {} ({}), data in {}", address,
               flags.tls_cert.empty() ? "plaintext" : "TLS", flags.options.data_dir);
  int exit_code = 0;
  if (!flags.ready_file.empty()) {
    // Atomically, so a reader never sees half an address. A service whose readiness cannot be
    // announced is of no use to whoever waits for it: stop.
    // Line 1: the gRPC address; line 2, with --metrics-listen: "metrics HOST:PORT".
    const std::string ready = absl::StrCat(
        address, "\n", metrics ? absl::StrCat("metrics ", metrics->address(), "\n") : "");
    if (absl::Status s = WriteFileAtomically(flags.ready_file, ready); !s.ok()) {
      spdlog::error("--ready-file: {}", std::string(s.message()));
      exit_code = 1;
    }
  }

  if (exit_code == 0) WaitForStopSignal(signals);
  // NOT_SERVING for every service while the calls in flight finish.
  if (grpc::HealthCheckServiceInterface* health = server->GetHealthCheckService()) {
    health->Shutdown();
  }
  jobs.Shutdown();
  server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(5));
  server->Wait();
  metrics.reset();  // its scrapes read the coordinator
  coordinator->reset();
  spdlog::info("stopped");
  return exit_code;
}

}  // namespace
}  // namespace pdsm

int main(int argc, char** argv) {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  pdsm::Flags flags;
  pdsm::CoordinatorOptions& o = flags.options;
  CLI::App app{"pdsm-coordinator: the PDSM bake service (job API and worker API)"};
  app.add_option("--listen", flags.listen, "host:port to serve on (port 0: any free port)")
      ->capture_default_str();
  app.add_option("--data-dir", o.data_dir, "Job state, assets and finished PDSMs")->required();
  app.add_option("--client-token-file", flags.client_token_file,
                 "Secret the job API requires (Bearer token)");
  app.add_option("--worker-token-file", flags.worker_token_file,
                 "Secret the worker API requires (Bearer token)");
  app.add_option("--monitor-token-file", flags.monitor_token_file,
                 "Secret that may only read job state and stats (GetJob, ListJobs, WatchJob, "
                 "GetStats: pdsm status, list, watch, stats); needs --client-token-file");
  app.add_option("--tls-cert", flags.tls_cert, "PEM certificate chain: serve TLS");
  app.add_option("--tls-key", flags.tls_key, "PEM private key of --tls-cert");
  app.add_option("--ready-file", flags.ready_file, "Write the listening address here once serving");
  app.add_option("--metrics-listen", flags.metrics_listen,
                 "host:port for Prometheus metrics over HTTP (GET /metrics; no token: keep it "
                 "private)");
  app.add_option("--samples-per-task", o.samples_per_task,
                 "Light samples per task (0: the job's samples / 8, within [1, 64])")
      ->check(CLI::Range(0, 65536))
      ->capture_default_str();
  app.add_option("--lease-seconds", flags.lease_seconds,
                 "Lease length; a silent worker's task is re-issued after it")
      ->check(CLI::Range(0.1, 3600.0))
      ->capture_default_str();
  app.add_option("--max-open-tiles", o.max_open_tiles,
                 "Tiles whose partial results may be open at once")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  app.add_option("--event-memory-mib", flags.event_memory_mib,
                 "Partial results kept in memory before they move to a scratch file in the data "
                 "dir (the PDSM does not change)")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  app.add_option("--query-cache-mib", flags.query_cache_mib,
                 "Tiles of a finished PDSM kept in memory for QueryAttenuation (read on demand)")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  app.add_option("--max-task-failures", o.max_task_failures,
                 "Distinct workers a task may fail on before its job fails")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--max-worker-failures", o.max_worker_failures,
                 "Failures after which a worker gets no more tasks of a job")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--verify-fraction", o.verify_fraction,
                 "Fraction of tasks run by a second worker and compared bit for bit; a worker "
                 "outvoted two to one is quarantined and what it computed is redone (0: off)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--assembly-threads", o.assembly_threads,
                 "Threads merging and compressing finished tiles")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  app.add_option("--max-message-bytes", flags.max_message_bytes,
                 "Largest request accepted (RESOURCE_EXHAUSTED above)")
      ->check(CLI::Range(1 << 16, 1 << 30))
      ->capture_default_str();
  app.add_option("--max-job-pixels", o.limits.max_job_pixels, "Largest PDSM (width x height)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--max-job-tiles", o.limits.max_job_tiles,
                 "Most tiles per job (resolution / tileSize, squared)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--max-samples", o.limits.max_samples, "Most light samples per job")
      ->check(CLI::Range(1, 65536))
      ->capture_default_str();
  app.add_option("--max-triangles", o.limits.max_triangles, "Most triangles per job")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--max-planned-mib", flags.max_planned_mib,
                 "Memory the plans of the jobs this coordinator runs may hold (surfaces-only "
                 "receivers, scenes, a bit per tile): a job needing more alone is refused, one "
                 "that does not fit beside the running ones waits QUEUED")
      ->check(CLI::Range(int64_t{1}, int64_t{1} << 30))
      ->capture_default_str();
  app.add_option("--max-asset-bytes", o.max_asset_bytes, "Largest mesh asset")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  pdsm::AddProcessLogFlags(app, &flags.log_level, &flags.log_format);
  app.set_version_flag("--version", pdsm::VersionLine("pdsm-coordinator"));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  return pdsm::Run(flags, signals);
}
