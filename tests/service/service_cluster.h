// A real bake service on 127.0.0.1 for tests: a pdsm-coordinator and pdsm-worker processes
// started from the build, on a free port, with helpers to kill, stop and restart them, run
// the `pdsm` CLI against them, and call the job API directly.
#ifndef PDSM_TESTS_SERVICE_SERVICE_CLUSTER_H_
#define PDSM_TESTS_SERVICE_SERVICE_CLUSTER_H_

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <google/protobuf/util/json_util.h>
#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>

#include "pdsm/v1/jobs.grpc.pb.h"
#include "pdsm/v1/workers.grpc.pb.h"
#include "rpc/grpc_support.h"
#include "tests/test_support.h"

extern char** environ;

namespace pdsm::testing {

// A child process with its output in a log file; killed (SIGKILL) if still running at
// destruction.
class ChildProcess {
 public:
  ChildProcess(const std::vector<std::string>& argv, const std::string& log_path) {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_path.c_str(),
                                     O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    if (posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
  }
  ~ChildProcess() {
    if (running()) {
      kill(pid_, SIGKILL);
      Wait(std::chrono::seconds(10));
    }
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  bool running() const { return pid_ > 0 && !exited_; }
  void Signal(int signal) {
    if (running()) kill(pid_, signal);
  }
  // The exit status (as from waitpid), or -1 if it did not end within `timeout`.
  int Wait(std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (!exited_) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        status_ = status;
        break;
      }
      if (std::chrono::steady_clock::now() > end) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return status_;
  }

 private:
  pid_t pid_ = -1;
  bool exited_ = false;
  int status_ = 0;
};

// $PDSM_TEST_TIME_SCALE (an integer, 1 when unset): the sanitizer jobs run instrumented
// processes several times slower (scripts/sanitize.sh), so waits and lease lengths stretch by
// it. Without it a 1 s lease under ASan on a busy machine expires while its worker is alive
// and extending, and a job fails for a reason the test is not about.
inline int TestTimeScale() {
  const char* scale = std::getenv("PDSM_TEST_TIME_SCALE");
  return scale != nullptr ? std::max(1, std::atoi(scale)) : 1;
}

// The coordinator's --lease-seconds value for a lease of `seconds` at scale 1.
inline std::string LeaseSeconds(int seconds) { return std::to_string(seconds * TestTimeScale()); }

struct ClusterOptions {
  std::string client_token;  // empty: no token files
  std::string worker_token;
  std::string monitor_token;                  // empty: none (needs client_token)
  std::vector<std::string> coordinator_args;  // extra flags
  bool tls = false;  // serve TLS with a fresh self-signed certificate for 127.0.0.1
};

// A cluster without tokens whose coordinator gets `args`.
inline ClusterOptions CoordinatorArgs(std::vector<std::string> args) {
  ClusterOptions options;
  options.coordinator_args = std::move(args);
  return options;
}

// The tokens of a cluster made with WithTokens.
inline constexpr char kClientToken[] = "client-secret";
inline constexpr char kWorkerToken[] = "worker-secret";

// A cluster that checks a client token (kClientToken) and a worker token (kWorkerToken), whose
// coordinator gets `args`.
inline ClusterOptions WithTokens(std::vector<std::string> args = {}) {
  ClusterOptions options = CoordinatorArgs(std::move(args));
  options.client_token = kClientToken;
  options.worker_token = kWorkerToken;
  return options;
}

class ServiceCluster {
 public:
  explicit ServiceCluster(ClusterOptions options = {}) : options_(std::move(options)) {
    if (!options_.client_token.empty()) {
      WriteText(dir_.File("client_token"), options_.client_token + "\n");
      WriteText(dir_.File("worker_token"), options_.worker_token + "\n");
    }
    if (!options_.monitor_token.empty()) {
      WriteText(dir_.File("monitor_token"), options_.monitor_token + "\n");
    }
    if (options_.tls) {
      CommandResult r = RunCommand(
          "openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=localhost"
          " -addext subjectAltName=IP:127.0.0.1,DNS:localhost -keyout " +
              dir_.File("key.pem") + " -out " + dir_.File("cert.pem"),
          dir_);
      EXPECT_EQ(r.exit_code, 0) << r.err;
    }
  }

  // The CA file clients pass with --tls-ca ("" without TLS).
  std::string tls_ca() const { return options_.tls ? dir_.File("cert.pem") : ""; }

  const TempDir& dir() const { return dir_; }
  const std::string& address() const { return address_; }

  // Starts (or restarts, on the same port and data dir) the coordinator; waits until it
  // serves. Returns false on timeout.
  bool StartCoordinator() {
    const std::string ready = dir_.File("ready");
    std::remove(ready.c_str());
    std::vector<std::string> argv = {PDSM_COORDINATOR,
                                     "--listen",
                                     address_.empty() ? "127.0.0.1:0" : address_,
                                     "--data-dir",
                                     dir_.File("data"),
                                     "--ready-file",
                                     ready};
    if (!options_.client_token.empty()) {
      argv.insert(argv.end(), {"--client-token-file", dir_.File("client_token"),
                               "--worker-token-file", dir_.File("worker_token")});
    }
    if (!options_.monitor_token.empty()) {
      argv.insert(argv.end(), {"--monitor-token-file", dir_.File("monitor_token")});
    }
    if (options_.tls) {
      argv.insert(argv.end(),
                  {"--tls-cert", dir_.File("cert.pem"), "--tls-key", dir_.File("key.pem")});
    }
    argv.insert(argv.end(), options_.coordinator_args.begin(), options_.coordinator_args.end());
    coordinator_ = std::make_unique<ChildProcess>(argv, dir_.File("coordinator.log"));
    for (int i = 0; i < 600; ++i) {  // 60 s: a loaded CI machine can be slow to start
      std::ifstream in(ready);
      std::string line;
      if (in && std::getline(in, line) && !line.empty()) {
        address_ = line;
        return true;
      }
      if (!coordinator_->running() || coordinator_->Wait(std::chrono::milliseconds(0)) != -1) {
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return false;
  }

  ChildProcess& coordinator() { return *coordinator_; }

  // Starts a worker; returns its index. `extra`: more flags; `token_file`: instead of the
  // cluster's worker token.
  size_t AddWorker(int threads = 1, const std::vector<std::string>& extra = {},
                   std::optional<std::string> token_file = std::nullopt) {
    std::vector<std::string> argv = {PDSM_WORKER,
                                     "--coordinator",
                                     address_,
                                     "--threads",
                                     std::to_string(threads),
                                     "--cache-dir",
                                     dir_.File("cache" + std::to_string(workers_.size()))};
    if (token_file) {
      argv.insert(argv.end(), {"--token-file", *token_file});
    } else if (!options_.worker_token.empty()) {
      argv.insert(argv.end(), {"--token-file", dir_.File("worker_token")});
    }
    if (options_.tls) argv.insert(argv.end(), {"--tls-ca", tls_ca()});
    argv.insert(argv.end(), extra.begin(), extra.end());
    workers_.push_back(std::make_unique<ChildProcess>(
        argv, dir_.File("worker" + std::to_string(workers_.size()) + ".log")));
    return workers_.size() - 1;
  }
  ChildProcess& worker(size_t i) { return *workers_.at(i); }

  // Runs `pdsm ARGS --server ADDR [--token-file F]`.
  CommandResult Pdsm(const std::string& args) {
    std::string command = std::string(PDSM_CLI) + " " + args + " --server " + address_;
    if (!options_.client_token.empty()) command += " --token-file " + dir_.File("client_token");
    if (options_.tls) command += " --tls-ca " + tls_ca();
    return RunCommand(command, dir_);
  }

  // Submits and returns the job id (empty on failure, with the error in the test log).
  std::string Submit(const std::string& scene_path, const std::string& extra = "") {
    CommandResult r = Pdsm("submit " + scene_path + " " + extra);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::string last;
    std::istringstream lines(r.out);
    for (std::string line; std::getline(lines, line);) {
      if (!line.empty()) last = line;
    }
    return last;
  }

  // The job as the job API returns it.
  // `token`: the one to send instead of the cluster's client token ("" for none).
  grpc::Status GetJob(const std::string& job_id, pdsm::v1::Job* job,
                      std::optional<std::string> token = std::nullopt) {
    grpc::ClientContext context;
    PrepareCall(&context, token.value_or(options_.client_token), std::chrono::seconds(10));
    pdsm::v1::GetJobRequest request;
    request.set_job_id(job_id);
    return JobsStub()->GetJob(&context, request, job);
  }

  // Polls until the job is in a terminal state or `timeout` passes; returns the last state.
  pdsm::v1::Job WaitForEnd(const std::string& job_id,
                           std::chrono::seconds timeout = std::chrono::seconds(120)) {
    return WaitUntil(job_id, timeout, [](const pdsm::v1::Job& j) {
      return j.state() == pdsm::v1::SUCCEEDED || j.state() == pdsm::v1::FAILED ||
             j.state() == pdsm::v1::CANCELLED;
    });
  }

  // `timeout` is multiplied by TestTimeScale(). Fails the test at once, with the coordinator's
  // log, if the coordinator process ends meanwhile (a crash, or a sanitizer halting it):
  // waiting out the timeout would only hide why.
  template <typename Predicate>
  pdsm::v1::Job WaitUntil(const std::string& job_id, std::chrono::seconds timeout, Predicate done) {
    const auto end = std::chrono::steady_clock::now() + timeout * TestTimeScale();
    pdsm::v1::Job job;
    while (std::chrono::steady_clock::now() < end) {
      if (GetJob(job_id, &job).ok() && done(job)) break;
      if (coordinator_ && coordinator_->Wait(std::chrono::milliseconds(0)) != -1) {
        ADD_FAILURE() << "the coordinator exited (wait status " << coordinator_->Wait({})
                      << ") while job " << job_id << " was awaited; its log:\n"
                      << Log("coordinator.log");
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return job;
  }

  pdsm::v1::Stats Stats() {
    grpc::ClientContext context;
    PrepareCall(&context, options_.client_token, std::chrono::seconds(10));
    pdsm::v1::Stats stats;
    EXPECT_TRUE(JobsStub()->GetStats(&context, {}, &stats).ok());
    return stats;
  }

  std::unique_ptr<pdsm::v1::PdsmJobs::Stub> JobsStub() {
    return pdsm::v1::PdsmJobs::NewStub(*MakeChannel({address_, tls_ca()}));
  }
  std::unique_ptr<pdsm::v1::PdsmWorkers::Stub> WorkersStub() {
    return pdsm::v1::PdsmWorkers::NewStub(*MakeChannel({address_, tls_ca()}));
  }

  std::string Log(const std::string& name) { return ReadBytes(dir_.File(name)); }

 private:
  ClusterOptions options_;
  TempDir dir_;
  std::string address_;
  std::unique_ptr<ChildProcess> coordinator_;
  std::vector<std::unique_ptr<ChildProcess>> workers_;
};

// A scene for the service tests: the plates example with one caster read from an OBJ file
// (so mesh assets travel), written into `dir`. Returns the scene path.
inline std::string WriteServiceScene(const TempDir& dir, int resolution, int samples, int tile_size,
                                     int sm_resolution = 512) {
  WriteText(dir.File("box.obj"),
            "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n"
            "v -1 0.5 -1\nv 1 0.5 -1\nv 1 0.5 1\nv -1 0.5 1\n"
            "f 1 2 3\nf 1 3 4\nf 5 7 6\nf 5 8 7\nf 1 5 6\nf 1 6 2\nf 4 3 7\nf 4 7 8\n");
  const std::string path = dir.File("scene.json");
  WriteText(path, R"({
  "name": "service-plates",
  "meshes": [
    {"inline": {"positions": [-10,0,-10, 10,0,-10, 10,0,10, -10,0,10],
                "indices": [0,1,2, 0,2,3]}, "role": "RECEIVER_ONLY"},
    {"path": "box.obj", "transform": [1.5,0,0,-1.5, 0,1,0,4, 0,0,1.5,-1, 0,0,0,1]},
    {"inline": {"positions": [0,0,0, 2,0,0, 1,0,1.8], "indices": [0,1,2]},
     "transform": [1,0,0,0.5, 0,1,0,2, 0,0,1,0.5, 0,0,0,1]}
  ],
  "light": {"rect": {"center": [0,10,0], "normal": [0,-1,0], "up": [0,0,1], "size": [3,3]}},
  "bake": {"resolution": [)" +
                      std::to_string(resolution) + "," + std::to_string(resolution) +
                      R"(], "samples": )" + std::to_string(samples) +
                      R"(, "shadowMapResolution": )" + std::to_string(sm_resolution) +
                      R"(, "tileSize": )" + std::to_string(tile_size) + R"(, "epsilon": 0.01}
})");
  return path;
}

// A unary call of `method` ("/package.Service/Method") with `body` as the request's bytes,
// over a generic stub, without a token; its status, and the reply's bytes in `reply` (if not
// null) when it succeeded.
inline grpc::Status GenericUnaryCall(grpc::GenericStub& stub, const std::string& method,
                                     const std::string& body, std::string* reply = nullptr) {
  grpc::ClientContext context;
  PrepareCall(&context, "", std::chrono::seconds(10) * TestTimeScale());
  grpc::Slice slice(body);
  grpc::ByteBuffer request(&slice, 1), response;
  std::mutex mu;
  std::condition_variable cv;
  bool done = false;
  grpc::Status status;
  stub.UnaryCall(&context, method, grpc::StubOptions(), &request, &response, [&](grpc::Status s) {
    std::lock_guard<std::mutex> lock(mu);
    status = s;
    done = true;
    cv.notify_one();
  });
  std::unique_lock<std::mutex> lock(mu);
  cv.wait(lock, [&] { return done; });
  if (reply != nullptr) {
    reply->clear();
    std::vector<grpc::Slice> slices;
    if (status.ok() && response.Dump(&slices).ok()) {
      for (const grpc::Slice& s : slices) {
        reply->append(reinterpret_cast<const char*>(s.begin()), s.size());
      }
    }
  }
  return status;
}

// grpc.health.v1.Health/Check for `service` over a generic stub (the health proto is not in
// our schema): HealthCheckRequest.service is field 1; the reply's status SERVING is 08 01.
inline grpc::Status HealthCheck(ServiceCluster& cluster, const std::string& service,
                                std::string* reply) {
  grpc::GenericStub stub(*MakeChannel({cluster.address(), ""}));
  std::string request_bytes;
  if (!service.empty()) {
    request_bytes = std::string("\x0a", 1) + static_cast<char>(service.size()) + service;
  }
  return GenericUnaryCall(stub, "/grpc.health.v1.Health/Check", request_bytes, reply);
}

// A task leased as `worker_id` through the worker API, as a hand-made worker (a forger, a liar)
// does; asks up to 100 times (the job may not be scheduled yet). nullopt when none came.
inline std::optional<pdsm::v1::Task> LeaseOneTask(ServiceCluster& cluster,
                                                  const std::string& worker_id) {
  const auto workers = cluster.WorkersStub();
  for (int attempt = 0; attempt < 100; ++attempt) {
    grpc::ClientContext context;
    PrepareCall(&context, "", std::chrono::seconds(10));
    pdsm::v1::LeaseTaskRequest request;
    request.set_worker_id(worker_id);
    pdsm::v1::LeaseTaskResponse response;
    const grpc::Status status = workers->LeaseTask(&context, request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    if (response.has_task() && response.task().tile_indices_size() > 0) return response.task();
  }
  return std::nullopt;
}

// FetchTile of tile `index` of a one-light job: its status, and the streamed bytes in `bytes`
// (if not null).
inline grpc::Status FetchTileBytes(ServiceCluster& cluster, const std::string& job_id, int index,
                                   std::string* bytes = nullptr) {
  grpc::ClientContext context;
  PrepareCall(&context, "", std::chrono::seconds(10));
  pdsm::v1::FetchTileRequest request;
  request.set_job_id(job_id);
  request.set_tile_index(index);
  auto reader = cluster.JobsStub()->FetchTile(&context, request);
  pdsm::v1::PdsmChunk chunk;
  while (reader->Read(&chunk)) {
    if (bytes != nullptr) *bytes += chunk.data();
  }
  return reader->Finish();
}

inline bool Ended(const pdsm::v1::Job& job) {
  return job.state() == pdsm::v1::SUCCEEDED || job.state() == pdsm::v1::FAILED ||
         job.state() == pdsm::v1::CANCELLED;
}

// Fetches a finished job (`pdsm fetch`) and returns the file's bytes.
inline std::string FetchBytes(ServiceCluster& cluster, const std::string& job_id) {
  const std::string out = cluster.dir().File(job_id + ".exr");
  CommandResult r = cluster.Pdsm("fetch " + job_id + " -o " + out);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return ReadBytes(out);
}

// The local bake of a scene (written to DIR/local.exr), as bytes: what every distributed bake
// must equal. `flags`: bake flags both bakes take (`--surfaces-only`, `--weighting emitter`).
inline std::string LocalBakeBytes(const TempDir& dir, const std::string& scene_path,
                                  const std::string& flags = "") {
  const std::string out = dir.File("local.exr");
  CommandResult r = RunCommand(
      std::string(PDSM_CLI) + " bake " + scene_path + " -o " + out + " --no-preview " + flags, dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return ReadBytes(out);
}

// Submits `scene_path` to the cluster's coordinator, adds `workers` workers, waits for the job
// to end and expects it to succeed with `pdsm bake`'s bytes (LocalBakeBytes), both with bake
// `flags`. Returns the job (its id empty when it could not be submitted).
inline pdsm::v1::Job ExpectServiceBakesAsLocal(ServiceCluster& cluster,
                                               const std::string& scene_path, int workers = 2,
                                               const std::string& flags = "") {
  const std::string expected = LocalBakeBytes(cluster.dir(), scene_path, flags);
  EXPECT_FALSE(expected.empty());
  const std::string job_id = cluster.Submit(scene_path, flags);
  EXPECT_FALSE(job_id.empty());
  if (job_id.empty()) return {};
  for (int i = 0; i < workers; ++i) cluster.AddWorker();
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  EXPECT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error() << cluster.Log("coordinator.log");
  if (job.state() == pdsm::v1::SUCCEEDED) {
    EXPECT_TRUE(FetchBytes(cluster, job_id) == expected) << "fetched PDSM differs from local bake";
  }
  return job;
}

}  // namespace pdsm::testing

#endif  // PDSM_TESTS_SERVICE_SERVICE_CLUSTER_H_
