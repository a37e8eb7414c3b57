// The load and fault suite (issue #17 item 7), loopback only and bounded in count and time:
// a real coordinator and workers while, all at once, clients flood it with SubmitBake of random
// scenes, hundreds of WatchJob streams follow the jobs, random bytes go to every RPC method,
// workers are killed (SIGKILL) and stopped (SIGTERM) in turn mid-bake and replaced, and a prober
// times GetJob. What must hold: the coordinator never dies, every job succeeds with the bytes
// of its local bake, every watcher sees its job end. The latencies are printed, not asserted
// (docs/service.md "Load" records them at benchmark scale): a test must not time a shared
// machine.
//
// Scale (environment, defaults in parentheses): PDSM_LOAD_WATCHERS (100), PDSM_LOAD_SCENES (6),
// PDSM_LOAD_GARBAGE_CALLS (200), PDSM_LOAD_WORKERS (3), PDSM_LOAD_SEED (1).
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "tests/service/service_cluster.h"

namespace pdsm::testing {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;
using Clock = std::chrono::steady_clock;

int EnvInt(const char* name, int fallback) {
  const char* value = std::getenv(name);
  return value != nullptr && *value != '\0' ? std::max(1, std::atoi(value)) : fallback;
}

// A ground, one to three boxes and a rect light, all drawn from `rng`: small enough to bake in
// well under a second, different enough that a mixed-up result cannot match.
std::string RandomSceneJson(std::mt19937& rng, int index) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto in = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };
  std::vector<std::string> meshes = {
      R"({"inline": {"positions": [-8,0,-8, 8,0,-8, 8,0,8, -8,0,8], "indices": [0,1,2, 0,2,3]},
        "role": "RECEIVER_ONLY"})"};
  const int boxes = 1 + static_cast<int>(rng() % 3);
  for (int b = 0; b < boxes; ++b) {
    const double x = in(-3, 3), z = in(-3, 3), w = in(0.3, 1.5), d = in(0.3, 1.5);
    const double y0 = in(0.5, 2.0), y1 = y0 + in(0.2, 1.5);
    std::vector<std::string> p;
    for (const double y : {y0, y1}) {
      for (const auto& [cx, cz] : std::vector<std::pair<double, double>>{
               {x - w, z - d}, {x + w, z - d}, {x + w, z + d}, {x - w, z + d}}) {
        p.push_back(absl::StrCat(cx, ",", y, ",", cz));
      }
    }
    meshes.push_back(absl::StrCat(
        R"({"inline": {"positions": [)", absl::StrJoin(p, ", "),
        R"(], "indices": [0,2,1, 0,3,2, 4,5,6, 4,6,7, 0,1,5, 0,5,4, 1,2,6, 1,6,5, 2,3,7, 2,7,6, 3,0,4, 3,4,7]}})"));
  }
  // Enough work (a few CPU-seconds a job) that workers die in the middle of it.
  const int resolution = rng() % 2 == 0 ? 64 : 96;
  const int samples = rng() % 2 == 0 ? 48 : 64;
  const double size = in(1, 3);
  return absl::StrCat(R"({"name": "load-)", index, R"(", "meshes": [)", absl::StrJoin(meshes, ", "),
                      R"(], "light": {"rect": {"center": [0,8,0], "normal": [0,-1,0], "up": [0,0,1],
                      "size": [)",
                      size, ",", size, R"(]}}, "bake": {"resolution": [)", resolution, ",",
                      resolution, R"(], "samples": )", samples,
                      R"(, "tileSize": 16, "shadowMapResolution": 512}})");
}

// Runs a shell command with its own output files (RunCommand's are shared by its folder).
CommandResult RunAlone(const std::string& command, const TempDir& dir, const std::string& tag) {
  const std::string out = dir.File(tag + ".out"), err = dir.File(tag + ".err");
  const int status = std::system((command + " >" + out + " 2>" + err).c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, ReadBytes(out), ReadBytes(err)};
}

// One WatchJob stream, read through gRPC's callback API, so that hundreds cost no thread each.
class Watcher : public grpc::ClientReadReactor<pdsm::v1::Job> {
 public:
  Watcher(pdsm::v1::PdsmJobs::Stub* stub, const std::string& job_id) {
    PrepareCall(&context_, "", seconds(600) * TestTimeScale());
    request_.set_job_id(job_id);
    stub->async()->WatchJob(&context_, &request_, this);
    StartRead(&job_);
    StartCall();
  }
  void OnReadDone(bool ok) override {
    if (!ok) return;  // the stream ended: OnDone follows
    {
      std::lock_guard<std::mutex> lock(mu_);
      ++updates_;
      last_ = job_;
    }
    StartRead(&job_);
  }
  void OnDone(const grpc::Status& status) override {
    std::lock_guard<std::mutex> lock(mu_);
    status_ = status;
    done_ = true;
    cv_.notify_all();
  }
  // False if the stream has not ended by `deadline` (it is then cancelled).
  bool Wait(Clock::time_point deadline) {
    std::unique_lock<std::mutex> lock(mu_);
    if (cv_.wait_until(lock, deadline, [&] { return done_; })) return true;
    context_.TryCancel();
    cv_.wait(lock, [&] { return done_; });
    return false;
  }
  grpc::Status status() {
    std::lock_guard<std::mutex> lock(mu_);
    return status_;
  }
  pdsm::v1::Job last() {
    std::lock_guard<std::mutex> lock(mu_);
    return last_;
  }
  int updates() {
    std::lock_guard<std::mutex> lock(mu_);
    return updates_;
  }

 private:
  grpc::ClientContext context_;
  pdsm::v1::GetJobRequest request_;
  pdsm::v1::Job job_;
  std::mutex mu_;
  std::condition_variable cv_;
  bool done_ = false;
  grpc::Status status_;
  pdsm::v1::Job last_;
  int updates_ = 0;
};

// Every method of both services: random bodies are sent to each.
const std::vector<const google::protobuf::MethodDescriptor*>& AllMethods() {
  static const std::vector<const google::protobuf::MethodDescriptor*> methods = [] {
    std::vector<const google::protobuf::MethodDescriptor*> out;
    // Through a message of each file: that builds the file's descriptors.
    for (const google::protobuf::ServiceDescriptor* service :
         {pdsm::v1::GetJobRequest::descriptor()->file()->FindServiceByName("PdsmJobs"),
          pdsm::v1::LeaseTaskRequest::descriptor()->file()->FindServiceByName("PdsmWorkers")}) {
      for (int m = 0; m < service->method_count(); ++m) {
        out.push_back(service->method(m));
      }
    }
    return out;
  }();
  return methods;
}

// Fills `message` with random values: each field set or not, numbers anywhere in their range
// (negatives, extremes), strings of random bytes, up to 4 elements per repeated field, nested
// messages to `depth`. What arrives is well-formed, so it reaches the handlers' checks.
void Randomize(google::protobuf::Message* message, std::mt19937& rng, int depth) {
  using google::protobuf::FieldDescriptor;
  const google::protobuf::Descriptor* type = message->GetDescriptor();
  const google::protobuf::Reflection* r = message->GetReflection();
  // Valid UTF-8 (proto3 refuses anything else before a handler runs): letters, digits,
  // separators, control characters and a two-byte character.
  const auto random_string = [&] {
    static const std::vector<std::string> pieces = {"a", "Z",  "7",    "-",  "_",        ".", "/",
                                                    " ", "\n", "\x1b", "\t", "\xc3\xa9", "0", ":"};
    std::string s;
    const size_t n = rng() % 3 == 0 ? rng() % 300 : rng() % 12;
    for (size_t i = 0; i < n; ++i) s += pieces[rng() % pieces.size()];
    return s;
  };
  const auto random_int = [&]() -> int64_t {
    switch (rng() % 4) {
      case 0:
        return static_cast<int64_t>(rng() % 16);
      case 1:
        return -static_cast<int64_t>(rng() % 16);
      case 2:
        return static_cast<int64_t>(rng()) << 31;
      default:
        return static_cast<int64_t>(rng());
    }
  };
  for (int f = 0; f < type->field_count(); ++f) {
    const FieldDescriptor* field = type->field(f);
    if (rng() % 2 == 0) continue;
    const int count = field->is_repeated() ? static_cast<int>(rng() % 5) : 1;
    for (int k = 0; k < count; ++k) {
      const bool add = field->is_repeated();
      switch (field->cpp_type()) {
        case FieldDescriptor::CPPTYPE_INT32:
          add ? r->AddInt32(message, field, static_cast<int32_t>(random_int()))
              : r->SetInt32(message, field, static_cast<int32_t>(random_int()));
          break;
        case FieldDescriptor::CPPTYPE_INT64:
          add ? r->AddInt64(message, field, random_int())
              : r->SetInt64(message, field, random_int());
          break;
        case FieldDescriptor::CPPTYPE_UINT32:
          add ? r->AddUInt32(message, field, static_cast<uint32_t>(random_int()))
              : r->SetUInt32(message, field, static_cast<uint32_t>(random_int()));
          break;
        case FieldDescriptor::CPPTYPE_UINT64:
          add ? r->AddUInt64(message, field, static_cast<uint64_t>(random_int()))
              : r->SetUInt64(message, field, static_cast<uint64_t>(random_int()));
          break;
        case FieldDescriptor::CPPTYPE_DOUBLE: {
          const double values[] = {0.0, -1.0, 1e30, -1e-30, std::nan(""), 3.5, 1e308};
          const double v = values[rng() % 7];
          add ? r->AddDouble(message, field, v) : r->SetDouble(message, field, v);
          break;
        }
        case FieldDescriptor::CPPTYPE_FLOAT: {
          // Each within float's range: a double out of it converts with undefined behaviour.
          const float values[] = {0.0f, -1.0f, 3e38f, -1e-30f, std::nanf(""), 3.5f, -3e38f};
          const float v = values[rng() % 7];
          add ? r->AddFloat(message, field, v) : r->SetFloat(message, field, v);
          break;
        }
        case FieldDescriptor::CPPTYPE_BOOL:
          add ? r->AddBool(message, field, rng() % 2 == 0)
              : r->SetBool(message, field, rng() % 2 == 0);
          break;
        case FieldDescriptor::CPPTYPE_ENUM:
          add ? r->AddEnumValue(message, field, static_cast<int>(random_int() % 8))
              : r->SetEnumValue(message, field, static_cast<int>(random_int() % 8));
          break;
        case FieldDescriptor::CPPTYPE_STRING:
          add ? r->AddString(message, field, random_string())
              : r->SetString(message, field, random_string());
          break;
        case FieldDescriptor::CPPTYPE_MESSAGE:
          if (depth > 0) {
            Randomize(add ? r->AddMessage(message, field) : r->MutableMessage(message, field), rng,
                      depth - 1);
          }
          break;
      }
    }
  }
}

// A random body for `method`: most often a random well-formed request of its type, else
// random bytes (which gRPC refuses before any handler runs).
std::string RandomBody(const google::protobuf::MethodDescriptor* method, std::mt19937& rng) {
  if (rng() % 4 == 0) {
    std::string bytes(rng() % 512, '\0');
    for (char& c : bytes) c = static_cast<char>(rng());
    return bytes;
  }
  std::unique_ptr<google::protobuf::Message> message(
      google::protobuf::MessageFactory::generated_factory()
          ->GetPrototype(method->input_type())
          ->New());
  Randomize(message.get(), rng, 3);
  return message->SerializeAsString();
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))];
}

TEST(LoadAndFaults, FloodWatchersGarbageAndKilledWorkersLeaveEveryJobExact) {
  const int watchers_wanted = EnvInt("PDSM_LOAD_WATCHERS", 100);
  const int scenes = EnvInt("PDSM_LOAD_SCENES", 6);
  const int garbage_calls = EnvInt("PDSM_LOAD_GARBAGE_CALLS", 200);
  const int worker_count = EnvInt("PDSM_LOAD_WORKERS", 3);
  std::mt19937 rng(EnvInt("PDSM_LOAD_SEED", 1));
  const Clock::time_point test_start = Clock::now();

  // Every SIGKILL expires its worker's leases, and random bodies can lease tasks under
  // made-up worker ids and never answer: each counts as a failure of the task, so the default
  // of 3 failing workers per task could fail a job here by design. The test is about the
  // coordinator surviving and staying exact, not that policy (SchedulerTest covers it).
  ServiceCluster cluster(
      CoordinatorArgs({"--lease-seconds", LeaseSeconds(2), "--verify-fraction", "0.1",
                       "--max-task-failures", "50", "--log-level", "warn"}));
  ASSERT_TRUE(cluster.StartCoordinator());

  // The scenes and what each must bake to.
  std::vector<std::string> paths, expected;
  for (int i = 0; i < scenes; ++i) {
    paths.push_back(cluster.dir().File(absl::StrCat("scene_", i, ".json")));
    WriteText(paths.back(), RandomSceneJson(rng, i));
    const std::string out = cluster.dir().File(absl::StrCat("local_", i, ".exr"));
    const CommandResult r = RunAlone(
        absl::StrCat(PDSM_CLI, " bake ", paths.back(), " -o ", out, " --no-preview --threads 1"),
        cluster.dir(), absl::StrCat("local_", i));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    expected.push_back(ReadBytes(out));
  }

  for (int w = 0; w < worker_count; ++w) cluster.AddWorker();

  // Workers killed and stopped in turn, each replaced at once: the first while the first tasks
  // are leased, each next one once a result has come in since the one before (so the farm is
  // never starved), and after the first two, after a random pause too. Driven by progress, not a
  // clock, so faults happen mid-bake however fast or slow the machine.
  std::atomic<bool> stop{false};
  int killed = 0, stopped = 0;
  std::thread chaos([&] {
    std::mt19937 local(rng());
    size_t next = 0;  // workers before it were already signalled
    int64_t accepted_before = -1;
    while (!stop) {
      const pdsm::v1::Stats stats = cluster.Stats();
      if (stats.tasks_leased() == 0 || stats.tasks_accepted() <= accepted_before) {
        std::this_thread::sleep_for(milliseconds(5));
        continue;
      }
      accepted_before = stats.tasks_accepted();
      const bool kill = (killed + stopped) % 2 == 0;
      cluster.worker(next++).Signal(kill ? SIGKILL : SIGTERM);
      ++(kill ? killed : stopped);
      cluster.AddWorker();
      // The first kill and stop come back to back; the rest at random moments.
      if (killed + stopped >= 2) {
        std::this_thread::sleep_for(milliseconds(local() % 300) * TestTimeScale());
      }
    }
  });

  // The flood: every scene submitted at once, one client process each.
  std::vector<std::string> job_ids(scenes);
  {
    std::vector<std::thread> submitters;
    for (int i = 0; i < scenes; ++i) {
      submitters.emplace_back([&, i] {
        const CommandResult r =
            RunAlone(absl::StrCat(PDSM_CLI, " submit ", paths[i], " --server ", cluster.address()),
                     cluster.dir(), absl::StrCat("submit_", i));
        std::istringstream lines(r.out);
        for (std::string line; std::getline(lines, line);) {
          if (!line.empty()) job_ids[i] = line;
        }
      });
    }
    for (std::thread& t : submitters) t.join();
  }
  for (int i = 0; i < scenes; ++i) {
    if (job_ids[i].empty()) {
      stop = true;
      chaos.join();
      FAIL() << "scene " << i << " was not submitted";
    }
  }

  // Watchers spread over the jobs.
  auto jobs_stub = cluster.JobsStub();
  std::vector<std::unique_ptr<Watcher>> watchers;
  for (int w = 0; w < watchers_wanted; ++w) {
    watchers.push_back(std::make_unique<Watcher>(jobs_stub.get(), job_ids[w % scenes]));
  }

  // GetJob latency, every 10 ms, round the jobs.
  std::vector<double> latencies_ms;
  std::thread prober([&] {
    auto stub = cluster.JobsStub();
    for (size_t k = 0; !stop; ++k) {
      grpc::ClientContext context;
      PrepareCall(&context, "", seconds(10) * TestTimeScale());
      pdsm::v1::GetJobRequest request;
      request.set_job_id(job_ids[k % job_ids.size()]);
      pdsm::v1::Job job;
      const Clock::time_point start = Clock::now();
      const grpc::Status status = stub->GetJob(&context, request, &job);
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
      EXPECT_TRUE(status.ok()) << status.error_message();
      latencies_ms.push_back(ms);
      std::this_thread::sleep_for(milliseconds(10));
    }
  });
  // Random bytes to every method, a few at a time.
  std::map<int, int> garbage_codes;
  std::thread garbage([&] {
    std::mt19937 local(rng());
    grpc::GenericStub stub(*MakeChannel({cluster.address(), ""}));
    for (int c = 0; c < garbage_calls; ++c) {
      const google::protobuf::MethodDescriptor* method =
          AllMethods()[local() % AllMethods().size()];
      const std::string path =
          absl::StrCat("/", method->service()->full_name(), "/", method->name());
      ++garbage_codes[GenericUnaryCall(stub, path, RandomBody(method, local)).error_code()];
      std::this_thread::sleep_for(milliseconds(local() % 10));
    }
  });
  std::vector<pdsm::v1::Job> ends;
  for (const std::string& id : job_ids) ends.push_back(cluster.WaitForEnd(id, seconds(600)));
  const Clock::time_point all_ended = Clock::now();
  stop = true;
  prober.join();
  garbage.join();
  chaos.join();

  EXPECT_TRUE(cluster.coordinator().running()) << cluster.Log("coordinator.log");
  for (int i = 0; i < scenes; ++i) {
    ASSERT_EQ(ends[i].state(), pdsm::v1::SUCCEEDED)
        << "job " << job_ids[i] << ": " << ends[i].error();
    EXPECT_TRUE(FetchBytes(cluster, job_ids[i]) == expected[i])
        << "job " << job_ids[i] << " differs from its local bake";
  }
  // Otherwise the faults were not tested: the jobs ended before any worker died.
  EXPECT_GE(killed, 1);
  EXPECT_GE(stopped, 1);
  int updates = 0;
  for (const std::unique_ptr<Watcher>& w : watchers) {
    ASSERT_TRUE(w->Wait(Clock::now() + seconds(30) * TestTimeScale())) << "a watch never ended";
    EXPECT_TRUE(w->status().ok()) << w->status().error_message();
    EXPECT_EQ(w->last().state(), pdsm::v1::SUCCEEDED);
    updates += w->updates();
  }

  const pdsm::v1::Stats stats = cluster.Stats();
  std::string codes;
  for (const auto& [code, count] : garbage_codes) absl::StrAppend(&codes, " ", code, ":", count);
  const double seconds_to_end = std::chrono::duration<double>(all_ended - test_start).count();
  std::printf(
      "load: %d jobs, %d watchers (%d updates), %d garbage calls (codes%s), %d workers killed and "
      "%d stopped, %lld leases expired; all ended after %.1f s\n"
      "GetJob latency over %zu calls: p50 %.2f ms, p99 %.2f ms, max %.2f ms\n",
      scenes, watchers_wanted, updates, garbage_calls, codes.c_str(), killed, stopped,
      static_cast<long long>(stats.leases_expired()), seconds_to_end, latencies_ms.size(),
      Percentile(latencies_ms, 0.5), Percentile(latencies_ms, 0.99), Percentile(latencies_ms, 1.0));
}

}  // namespace
}  // namespace pdsm::testing
