// pdsm-worker: renders shadow maps and scan-converts tiles for a pdsm-coordinator.
// SIGTERM or SIGINT: running tasks stop at their next light sample and are handed back.
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <thread>

#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include "absl/strings/str_format.h"
#include "core/util/process_log.h"
#include "core/util/process_log_flags.h"
#include "core/util/version.h"
#include "metrics/metrics_http_server.h"
#include "rpc/grpc_support.h"
#include "worker/coordinator_client.h"
#include "worker/remote_worker.h"
#include "worker/worker_metrics.h"

namespace pdsm {
namespace {

struct Flags {
  std::string coordinator;
  std::string token_file;
  std::string tls_ca;
  std::string cache_dir;
  std::string log_level = "info";
  std::string log_format = "text";  // --log-format: kLogFormatNames
  int threads = 0;
  std::string test_fingerprint_salt;  // hidden; tests only (RemoteWorkerOptions)
  std::string metrics_listen;         // empty: no /metrics
};

// Unique per process, readable in the coordinator's logs: host, pid, random suffix.
std::string MakeWorkerId() {
  char host[256] = {};
  gethostname(host, sizeof(host) - 1);
  std::random_device random;
  return absl::StrFormat("%s-%d-%04x", host, getpid(), random() & 0xffff);
}

std::string DefaultCacheDir() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) {
    return (std::filesystem::path(xdg) / "pdsm-worker").string();
  }
  if (const char* home = std::getenv("HOME"); home && *home) {
    return (std::filesystem::path(home) / ".cache" / "pdsm-worker").string();
  }
  return (std::filesystem::temp_directory_path() / "pdsm-worker-cache").string();
}

int Run(const Flags& flags, const sigset_t& signals) {
  // One named logger per process: every line says which component wrote it.
  SetUpProcessLog("worker", flags.log_level, flags.log_format);
  std::string token;
  if (!flags.token_file.empty()) {
    absl::StatusOr<std::string> read = ReadTokenFile("--token-file", flags.token_file);
    if (!read.ok()) {
      spdlog::error("{}", std::string(read.status().message()));
      return 2;
    }
    token = *read;
  }
  absl::StatusOr<std::shared_ptr<grpc::Channel>> channel =
      MakeChannel({flags.coordinator, flags.tls_ca});
  if (!channel.ok()) {
    spdlog::error("{}", std::string(channel.status().message()));
    return 2;
  }
  CoordinatorClient client(*channel, token, MakeWorkerId());
  RemoteWorkerOptions options;
  options.threads =
      flags.threads > 0 ? flags.threads : std::max(1u, std::thread::hardware_concurrency());
  options.cache_dir = flags.cache_dir.empty() ? DefaultCacheDir() : flags.cache_dir;
  options.test_fingerprint_salt = flags.test_fingerprint_salt;
  absl::StatusOr<std::unique_ptr<RemoteWorker>> worker = RemoteWorker::Create(&client, options);
  if (!worker.ok()) {
    spdlog::error("{}", std::string(worker.status().message()));
    return 1;
  }
  std::unique_ptr<MetricsHttpServer> metrics;
  if (!flags.metrics_listen.empty()) {
    const RemoteWorker* w = worker->get();
    const int threads = options.threads;
    absl::StatusOr<std::unique_ptr<MetricsHttpServer>> started = MetricsHttpServer::Start(
        flags.metrics_listen, [w, threads] { return RenderWorkerMetrics(w->metrics(), threads); });
    if (!started.ok()) {
      spdlog::error("{}", std::string(started.status().message()));
      return 2;
    }
    metrics = *std::move(started);
  }
  spdlog::info("worker {}: {} threads, coordinator {}, cache {}", client.worker_id(),
               options.threads, flags.coordinator, options.cache_dir);

  std::atomic<bool> stop{false}, returned{false};
  std::thread signal_thread([&] {
    int signal = 0;
    sigwait(&signals, &signal);
    if (returned) return;  // our own wake-up below
    spdlog::info("signal {}: handing back running tasks and stopping", signal);
    stop = true;
  });
  absl::Status status = (*worker)->Run(stop);
  returned = true;
  if (!stop) kill(getpid(), SIGTERM);  // wakes the signal thread's sigwait (blocked elsewhere)
  signal_thread.join();
  if (!status.ok()) {
    // A wrong token or an incompatible coordinator: exit at once, as a misconfigured
    // process (Slurm marks the task failed, Kubernetes shows CrashLoopBackOff).
    spdlog::error("{}", std::string(status.message()));
    return 2;
  }
  spdlog::info("stopped");
  return 0;
}

}  // namespace
}  // namespace pdsm

int main(int argc, char** argv) {
  // Blocked before any thread starts, so only the signal thread's sigwait receives them.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  pdsm::Flags flags;
  CLI::App app{"pdsm-worker: renders PDSM bake tasks for a pdsm-coordinator"};
  app.add_option("--coordinator", flags.coordinator, "host:port of the coordinator")->required();
  app.add_option("--token-file", flags.token_file, "File holding the worker token");
  app.add_option("--tls-ca", flags.tls_ca, "PEM roots to trust: connect with TLS");
  app.add_option("--threads", flags.threads, "Task threads (0: one per core)")
      ->check(CLI::Range(0, 1024));
  app.add_option("--cache-dir", flags.cache_dir, "Where mesh assets are cached by hash");
  app.add_option("--metrics-listen", flags.metrics_listen,
                 "host:port for Prometheus metrics over HTTP (GET /metrics; no token: keep it "
                 "private)");
  pdsm::AddProcessLogFlags(app, &flags.log_level, &flags.log_format);
  // Hidden (no group): a test makes this worker plan every job "differently", as a worker of
  // another build would, to exercise rolling upgrades.
  app.add_option("--test-only-fingerprint-salt", flags.test_fingerprint_salt)->group("");
  app.set_version_flag("--version", pdsm::VersionLine("pdsm-worker"));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  return pdsm::Run(flags, signals);
}
