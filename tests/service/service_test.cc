// The distributed service end to end: real coordinator and worker processes on 127.0.0.1.
// Every bake is compared byte for byte with `pdsm bake` of the same scene.
#include <algorithm>
#include <atomic>
#include <sstream>
#include <thread>

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/pdsm/pdsm_file.h"
#include "tests/service/service_cluster.h"

namespace pdsm::testing {
namespace {

using std::chrono::seconds;

// `pdsm submit` validates the scene before it connects: errors name the file and field.
TEST(Service, SubmitRefusesBadScenesBeforeSendingAnything) {
  TempDir dir;
  const std::string text = ReadBytes(WriteServiceScene(dir, 64, 16, 32));
  const std::string bad = dir.File("bad.json");
  const auto submit_with = [&](const std::string& from, const std::string& to) {
    std::string edited = text;
    edited.replace(edited.find(from), from.size(), to);
    WriteText(bad, edited);
    // Nothing listens on port 1: a refusal can only come from the local validation.
    return RunCommand(std::string(PDSM_CLI) + " submit " + bad + " --server 127.0.0.1:1", dir);
  };
  CommandResult r = submit_with("\"size\": [3,3]", "\"size\": [3,-3]");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(bad + ": light.rect.size[1]"), std::string::npos) << r.err;

  r = submit_with(
      R"("light": {"rect": {"center": [0,10,0], "normal": [0,-1,0], "up": [0,0,1], "size": [3,3]}},)",
      R"("lights": [{"name": "sun", "sun": {"direction": [0,-1,0], "angularDiameterDeg": 1}},)"
      R"( {"name": "sun", "sun": {"direction": [0,-1,1], "angularDiameterDeg": 1}}],)");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(bad + ": lights[1].name"), std::string::npos) << r.err;

  r = submit_with("\"path\": \"box.obj\"", "\"path\": \"missing.obj\"");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(bad + ": meshes[1].path"), std::string::npos) << r.err;

  r = submit_with("\"path\": \"box.obj\"", "\"assetSha256\": \"" + std::string(64, 'a') + "\"");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("meshes[1].assetSha256"), std::string::npos) << r.err;
}

TEST(Service, ThreeWorkersMatchTheLocalBakeByteForByte) {
  // The scene has exactly 11 triangles (8 from box.obj, 3 inline): each counted once fits.
  ServiceCluster cluster(CoordinatorArgs({"--samples-per-task", "16", "--max-triangles", "11"}));
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  for (int i = 0; i < 3; ++i) cluster.AddWorker();
  const std::string scene = WriteServiceScene(cluster.dir(), 128, 64, 32);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  ASSERT_FALSE(expected.empty());

  const std::string job_id = cluster.Submit(scene);
  ASSERT_EQ(job_id.size(), 16u);
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error() << cluster.Log("coordinator.log");
  EXPECT_EQ(job.tiles_done(), 16);
  EXPECT_DOUBLE_EQ(job.progress(), 1.0);
  EXPECT_EQ(job.tile_assemblies(), job.tiles_total());
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected) << "fetched PDSM differs from local bake";

  // `status --json` is the documented contract: state and progress.
  CommandResult status = cluster.Pdsm("status " + job_id + " --json");
  ASSERT_EQ(status.exit_code, 0) << status.err;
  EXPECT_NE(status.out.find("\"state\":\"SUCCEEDED\""), std::string::npos) << status.out;
  EXPECT_NE(status.out.find("\"progress\":1"), std::string::npos) << status.out;

  // Remote queries evaluate the same file with the same code as local ones.
  WriteText(cluster.dir().File("points.csv"), "0,0,0\n1.2,0.01,-0.3\n-1.5,2,-1\n50,0,50\n");
  CommandResult remote =
      cluster.Pdsm("query --job " + job_id + " --points " + cluster.dir().File("points.csv"));
  CommandResult local =
      RunCommand(std::string(PDSM_CLI) + " query " + cluster.dir().File("local.exr") +
                     " --points " + cluster.dir().File("points.csv"),
                 cluster.dir());
  ASSERT_EQ(remote.exit_code, 0) << remote.err;
  EXPECT_EQ(remote.out, local.out);

  // The same idempotency key returns the same job instead of a new one.
  const std::string first = cluster.Submit(scene, "--idempotency-key retry-1");
  const std::string again = cluster.Submit(scene, "--idempotency-key retry-1");
  EXPECT_EQ(first, again);
  EXPECT_EQ(cluster.WaitForEnd(first).state(), pdsm::v1::SUCCEEDED);
}

// Turns the service scene into an adaptive one; returns its path.
std::string MakeAdaptive(const std::string& scene, double tolerance, int min_samples) {
  std::string text = ReadBytes(scene);
  const std::string from = "\"epsilon\": 0.01";
  text.replace(text.find(from), from.size(),
               "\"epsilon\": 0.01, \"adaptiveTolerance\": " + std::to_string(tolerance) +
                   ", \"adaptiveMinSamples\": " + std::to_string(min_samples));
  WriteText(scene, text);
  return scene;
}

// Adaptive sampling on the farm: the coordinator issues a tile's next stage only after
// merging and judging the previous one, and the file equals the local bake's bytes.
TEST(Service, AdaptiveJobMatchesTheLocalBakeByteForByte) {
  ServiceCluster cluster(CoordinatorArgs({"--samples-per-task", "5"}));
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  for (int i = 0; i < 2; ++i) cluster.AddWorker();
  const std::string scene = MakeAdaptive(WriteServiceScene(cluster.dir(), 64, 64, 16), 0.05, 8);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  ASSERT_FALSE(expected.empty());
  absl::StatusOr<PdsmHeader> header = ReadPdsmHeader(cluster.dir().File("local.exr"));
  ASSERT_TRUE(header.ok()) << header.status();
  ASSERT_EQ(header->tile_samples.size(), 16u);
  // Some tiles stop at the pilot, some go further: the stages really are judged.
  EXPECT_EQ(*std::min_element(header->tile_samples.begin(), header->tile_samples.end()), 8);
  EXPECT_GT(*std::max_element(header->tile_samples.begin(), header->tile_samples.end()), 8);

  const std::string job_id = cluster.Submit(scene);
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error() << cluster.Log("coordinator.log");
  EXPECT_EQ(job.tiles_done(), 16);
  EXPECT_DOUBLE_EQ(job.progress(), 1.0);
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected) << "fetched PDSM differs from local bake";
}

// A one-light scene in the `lights` form, a named spot light with its own bake: the service
// plans it as the local bake does (its own samples, its cone, its name in the file) and
// reports the light's effective settings.
TEST(Service, NamedSpotLightWithItsOwnBakeMatchesTheLocalBake) {
  ServiceCluster cluster(CoordinatorArgs({"--samples-per-task", "8"}));
  ASSERT_TRUE(cluster.StartCoordinator());
  std::string text = ReadBytes(WriteServiceScene(cluster.dir(), 64, 64, 32));
  const std::string light =
      R"("light": {"rect": {"center": [0,10,0], "normal": [0,-1,0], "up": [0,0,1], "size": [3,3]}})";
  const size_t at = text.find(light);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, light.size(),
               R"("lights": [{"name": "key", "spot": {"center": [0,10,0], "normal": [0,-1,0],)"
               R"( "radius": 1, "coneHalfAngleDeg": 20}, "bake": {"samples": 24}}])");
  const std::string scene = cluster.dir().File("spot.json");
  WriteText(scene, text);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  cluster.AddWorker();
  const std::string job_id = cluster.Submit(scene);
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error() << cluster.Log("coordinator.log");
  EXPECT_EQ(job.bake().samples(), 24u);
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected) << "fetched PDSM differs from local bake";
  absl::StatusOr<PdsmHeader> header = ReadPdsmHeader(cluster.dir().File("local.exr"), "key");
  ASSERT_TRUE(header.ok()) << header.status();
  EXPECT_EQ(header->samples, 24);
  EXPECT_DOUBLE_EQ(header->cone_half_angle_deg, 20);
  EXPECT_LE(header->geometry.s_max, std::tan(20 * std::numbers::pi / 180) * 1.01);
}

TEST(Service, KilledWorkersDoNotChangeTheBytes) {
  ServiceCluster cluster(
      CoordinatorArgs({"--samples-per-task", "8", "--lease-seconds", LeaseSeconds(1)}));
  ASSERT_TRUE(cluster.StartCoordinator());
  // 384 samples: enough work that the second kill still finds the job running on a quiet
  // machine (with 128 a CI run once saw it end first: "the job ended before worker 1").
  const std::string scene = WriteServiceScene(cluster.dir(), 128, 384, 32, 1024);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  const std::string job_id = cluster.Submit(scene);
  cluster.AddWorker();
  cluster.AddWorker();
  // Kill -9 one worker, then another, each while the job is under way.
  for (size_t victim = 0; victim < 2; ++victim) {
    cluster.WaitUntil(job_id, seconds(60), [](const pdsm::v1::Job& j) {
      return j.state() == pdsm::v1::RUNNING || Ended(j);
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    pdsm::v1::Job now;
    ASSERT_TRUE(cluster.GetJob(job_id, &now).ok());
    ASSERT_FALSE(Ended(now)) << "the job ended before worker " << victim << " was killed";
    cluster.worker(victim).Signal(SIGKILL);
    cluster.AddWorker();
  }
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error();
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected);
}

TEST(Service, StalledWorkerLosesItsLeaseAndItsLateResultChangesNothing) {
  ServiceCluster cluster(
      CoordinatorArgs({"--samples-per-task", "32", "--lease-seconds", LeaseSeconds(1)}));
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string scene = WriteServiceScene(cluster.dir(), 128, 128, 64, 1024);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  const size_t stalled = cluster.AddWorker();
  const std::string job_id = cluster.Submit(scene);
  cluster.WaitUntil(job_id, seconds(60), [](const pdsm::v1::Job& j) {
    return j.state() == pdsm::v1::RUNNING || Ended(j);
  });
  cluster.worker(stalled).Signal(SIGSTOP);
  cluster.AddWorker();
  // Past the lease (1 s at scale 1).
  std::this_thread::sleep_for(std::chrono::milliseconds(2500) * TestTimeScale());
  cluster.worker(stalled).Signal(SIGCONT);
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error();
  EXPECT_GE(cluster.Stats().leases_expired(), 1);
  EXPECT_EQ(job.tile_assemblies(), job.tiles_total());
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected);
}

// Issue #17: a lone worker whose leases expired three times was excluded from its job, which
// then failed ("no worker can run the job"). An expiry is not held against the worker now.
TEST(Service, ALoneWorkerStoppedPastItsLeaseThreeTimesStillFinishesTheJob) {
  ServiceCluster cluster(
      CoordinatorArgs({"--samples-per-task", "8", "--lease-seconds", LeaseSeconds(1)}));
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string scene = WriteServiceScene(cluster.dir(), 128, 256, 32, 1024);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  const size_t worker = cluster.AddWorker();
  const std::string job_id = cluster.Submit(scene);
  for (int round = 0; round < 3; ++round) {
    // Stopped while it holds a task, for longer than the lease.
    const auto leased_by = std::chrono::steady_clock::now() + seconds(60) * TestTimeScale();
    while (cluster.Stats().tasks_leased() == 0 && std::chrono::steady_clock::now() < leased_by) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ASSERT_GT(cluster.Stats().tasks_leased(), 0) << "round " << round;
    cluster.worker(worker).Signal(SIGSTOP);
    const int64_t expired = cluster.Stats().leases_expired();
    const auto expired_by = std::chrono::steady_clock::now() + seconds(30) * TestTimeScale();
    while (cluster.Stats().leases_expired() == expired &&
           std::chrono::steady_clock::now() < expired_by) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    cluster.worker(worker).Signal(SIGCONT);
    ASSERT_GT(cluster.Stats().leases_expired(), expired) << "round " << round;
  }
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error();
  EXPECT_GE(cluster.Stats().leases_expired(), 3);
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected);
}

TEST(Service, TerminatedWorkerHandsBackItsTaskAndExitsZero) {
  // Leases of 30 s: a task that was not handed back would sit out its lease, and the expiry
  // would show in the stats.
  ServiceCluster cluster(CoordinatorArgs({"--samples-per-task", "64"}));
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string scene = WriteServiceScene(cluster.dir(), 128, 256, 32, 1024);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  const size_t leaving = cluster.AddWorker();
  const std::string job_id = cluster.Submit(scene);
  const pdsm::v1::Job running = cluster.WaitUntil(
      job_id, seconds(60), [](const auto& j) { return j.samples_done() > 0 || Ended(j); });
  ASSERT_FALSE(Ended(running));
  // The first result has just been accepted, so the worker may be between tasks: wait until
  // it holds its next lease, or there would be nothing to hand back (a TSan run hit that).
  const auto leased_by = std::chrono::steady_clock::now() + seconds(10) * TestTimeScale();
  while (cluster.Stats().tasks_leased() == 0 && std::chrono::steady_clock::now() < leased_by) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_GT(cluster.Stats().tasks_leased(), 0);
  cluster.worker(leaving).Signal(SIGTERM);
  const int status = cluster.worker(leaving).Wait(std::chrono::seconds(20));
  ASSERT_TRUE(WIFEXITED(status)) << status;
  EXPECT_EQ(WEXITSTATUS(status), 0);
  // It signed off: no longer active at once (not 30 s after its last call).
  EXPECT_EQ(cluster.Stats().workers_active(), 0);
  EXPECT_NE(cluster.Log("coordinator.log").find("signed off"), std::string::npos);
  cluster.AddWorker();
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error();
  EXPECT_EQ(cluster.Stats().leases_expired(), 0);
  EXPECT_NE(cluster.Log("coordinator.log").find("handed the task back"), std::string::npos);
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected);
}

// A rolling upgrade: a worker of another build (its plan fingerprints salted) reports the
// job incompatible instead of failing it. With one failure allowed per task the job would
// die at the first counted failure; it waits instead, the coordinator says so once, and a
// worker of the coordinator's build finishes it with the local bake's bytes. The other
// build's worker keeps running (it may be fine for other jobs).
TEST(Service, WorkerOfAnotherBuildNeverFailsAJob) {
  ServiceCluster cluster(CoordinatorArgs({"--samples-per-task", "16", "--max-task-failures", "1"}));
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string scene = WriteServiceScene(cluster.dir(), 128, 128, 32, 512);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  const size_t other_build =
      cluster.AddWorker(/*threads=*/2, {"--test-only-fingerprint-salt", "-another-build"});
  const std::string job_id = cluster.Submit(scene);
  const auto deadline = std::chrono::steady_clock::now() + seconds(60);
  while (cluster.Stats().workers_incompatible() == 0 &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_EQ(cluster.Stats().workers_incompatible(), 1) << cluster.Log("coordinator.log");
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // both threads asked again
  pdsm::v1::Job waiting;
  ASSERT_TRUE(cluster.GetJob(job_id, &waiting).ok());
  EXPECT_FALSE(Ended(waiting)) << waiting.error();
  EXPECT_EQ(cluster.Stats().tasks_accepted(), 0);
  const std::string log = cluster.Log("coordinator.log");
  const size_t first = log.find("plans it differently");
  ASSERT_NE(first, std::string::npos) << log;
  EXPECT_EQ(log.find("plans it differently", first + 1), std::string::npos) << "logged twice";
  EXPECT_EQ(log.find("failed:"), std::string::npos) << log;

  cluster.AddWorker();
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error();
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected);
  EXPECT_TRUE(cluster.worker(other_build).running());
  EXPECT_EQ(cluster.worker(other_build).Wait(std::chrono::milliseconds(0)), -1);
  EXPECT_EQ(cluster.Stats().workers_incompatible(), 0);  // the job is no longer in progress
}

// A worker with a wrong token exits within seconds, with one line saying what to fix, and a
// non-zero status (so Slurm marks the task failed and Kubernetes shows a crash loop) instead
// of retrying forever.
TEST(Service, WorkerWithAWrongTokenExitsAtOnceSayingWhatToFix) {
  ServiceCluster cluster(WithTokens());
  ASSERT_TRUE(cluster.StartCoordinator());
  WriteText(cluster.dir().File("wrong_token"), "not-the-worker-secret\n");
  const size_t worker = cluster.AddWorker(1, {}, cluster.dir().File("wrong_token"));
  const auto start = std::chrono::steady_clock::now();
  const int status = cluster.worker(worker).Wait(std::chrono::seconds(20));
  ASSERT_NE(status, -1) << "still running: " << cluster.Log("worker0.log");
  EXPECT_LT(std::chrono::steady_clock::now() - start, seconds(10));
  ASSERT_TRUE(WIFEXITED(status)) << status;
  EXPECT_EQ(WEXITSTATUS(status), 2);
  const std::string log = cluster.Log("worker0.log");
  EXPECT_NE(log.find("UNAUTHENTICATED"), std::string::npos) << log;
  EXPECT_NE(log.find("check --token-file"), std::string::npos) << log;
  EXPECT_EQ(log.find("retrying"), std::string::npos) << log;
}

// --log-format json: every line either process writes is one JSON object with the four
// documented fields, whatever the message holds (here a refused token, quoted text and all).
TEST(Service, JsonLogsAreOneParsableObjectPerLine) {
  ServiceCluster cluster(WithTokens({"--log-format", "json"}));
  ASSERT_TRUE(cluster.StartCoordinator());
  WriteText(cluster.dir().File("wrong_token"), "not-the-worker-secret\n");
  const size_t worker =
      cluster.AddWorker(1, {"--log-format", "json"}, cluster.dir().File("wrong_token"));
  ASSERT_NE(cluster.worker(worker).Wait(std::chrono::seconds(20)), -1);
  cluster.coordinator().Signal(SIGTERM);  // its shutdown lines too
  ASSERT_NE(cluster.coordinator().Wait(std::chrono::seconds(20)), -1);
  for (const std::string name : {"coordinator.log", "worker0.log"}) {
    const std::string log = cluster.Log(name);
    std::istringstream lines(log);
    int parsed = 0;
    std::string last_message;
    for (std::string line; std::getline(lines, line);) {
      google::protobuf::Struct object;
      ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(line, &object).ok())
          << name << ": " << line;
      const auto& fields = object.fields();
      for (const char* key : {"time", "level", "component", "message"}) {
        ASSERT_TRUE(fields.contains(key)) << name << ": " << line;
      }
      EXPECT_EQ(fields.at("component").string_value(),
                name == "worker0.log" ? "worker" : "coordinator");
      EXPECT_EQ(fields.at("time").string_value().back(), 'Z') << line;  // UTC
      last_message = fields.at("message").string_value();
      ++parsed;
    }
    EXPECT_GT(parsed, 0) << name;
    if (name == "worker0.log") {
      EXPECT_NE(last_message.find("UNAUTHENTICATED"), std::string::npos) << log;
    }
  }
}

TEST(Service, CoordinatorKilledMidJobResumesWithoutRecomputingFinishedTiles) {
  ServiceCluster cluster(
      CoordinatorArgs({"--samples-per-task", "32", "--lease-seconds", LeaseSeconds(2)}));
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string scene = WriteServiceScene(cluster.dir(), 128, 256, 16, 1024);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  const std::string done_before = cluster.Submit(scene);  // a finished job must survive too
  cluster.AddWorker();
  ASSERT_EQ(cluster.WaitForEnd(done_before).state(), pdsm::v1::SUCCEEDED);

  const std::string job_id = cluster.Submit(scene);
  const pdsm::v1::Job partial = cluster.WaitUntil(
      job_id, seconds(60), [](const auto& j) { return j.tiles_done() >= 8 || Ended(j); });
  ASSERT_FALSE(Ended(partial)) << "the job ended before the coordinator could be killed";
  cluster.coordinator().Signal(SIGKILL);
  cluster.coordinator().Wait(seconds(10));
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");

  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error();
  // Every tile assembled exactly once over both lifetimes: none finished before was redone.
  EXPECT_EQ(job.tile_assemblies(), job.tiles_total());
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected);
  EXPECT_TRUE(FetchBytes(cluster, done_before) == expected);
}

// A restarted coordinator reopens an adaptive job's unfinished tiles at their pilot; the
// decisions come out the same, and so do the bytes.
TEST(Service, CoordinatorKilledMidAdaptiveJobGivesTheSameBytes) {
  ServiceCluster cluster(
      CoordinatorArgs({"--samples-per-task", "16", "--lease-seconds", LeaseSeconds(2)}));
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string scene =
      MakeAdaptive(WriteServiceScene(cluster.dir(), 128, 256, 16, 1024), 0.02, 16);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  cluster.AddWorker();
  const std::string job_id = cluster.Submit(scene);
  const pdsm::v1::Job partial = cluster.WaitUntil(
      job_id, seconds(60), [](const auto& j) { return j.tiles_done() >= 8 || Ended(j); });
  ASSERT_FALSE(Ended(partial)) << "the job ended before the coordinator could be killed";
  cluster.coordinator().Signal(SIGKILL);
  cluster.coordinator().Wait(seconds(10));
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error();
  EXPECT_EQ(job.tile_assemblies(), job.tiles_total());
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected);
}

TEST(Service, CancelStopsTheJobAndFreesTheWorkers) {
  ServiceCluster cluster(
      CoordinatorArgs({"--samples-per-task", "64", "--lease-seconds", LeaseSeconds(1)}));
  ASSERT_TRUE(cluster.StartCoordinator());
  cluster.AddWorker();
  const std::string big = WriteServiceScene(cluster.dir(), 512, 1024, 32, 2048);
  const std::string job_id = cluster.Submit(big);
  cluster.WaitUntil(job_id, seconds(60),
                    [](const pdsm::v1::Job& j) { return j.samples_done() > 0 || Ended(j); });
  CommandResult cancel = cluster.Pdsm("cancel " + job_id);
  ASSERT_EQ(cancel.exit_code, 0) << cancel.err;
  EXPECT_EQ(cluster.WaitForEnd(job_id, seconds(5)).state(), pdsm::v1::CANCELLED);
  // The worker learns at its next lease extension and is free well within a few seconds.
  const auto end = std::chrono::steady_clock::now() + seconds(10);
  while (cluster.Stats().tasks_leased() > 0 && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_EQ(cluster.Stats().tasks_leased(), 0);
  CommandResult fetch = cluster.Pdsm("fetch " + job_id + " -o " + cluster.dir().File("x.exr"));
  EXPECT_EQ(fetch.exit_code, 2);
  EXPECT_FALSE(std::filesystem::exists(cluster.dir().File("x.exr")));

  // The freed worker takes the next job.
  TempDir small_dir;
  const std::string small = WriteServiceScene(small_dir, 64, 16, 32);
  const std::string next = cluster.Submit(small);
  EXPECT_EQ(cluster.WaitForEnd(next).state(), pdsm::v1::SUCCEEDED);
}

TEST(Service, BadCallersAndBadJobsGetTheRightStatusAndDisturbNothing) {
  ServiceCluster cluster(
      WithTokens({"--max-job-pixels", "70000", "--max-message-bytes", "1048576"}));
  ASSERT_TRUE(cluster.StartCoordinator());
  cluster.AddWorker();
  const std::string scene = WriteServiceScene(cluster.dir(), 128, 32, 64);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  const std::string good = cluster.Submit(scene);
  ASSERT_FALSE(good.empty());

  pdsm::v1::Job job;
  EXPECT_EQ(cluster.GetJob(good, &job, "").error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(cluster.GetJob(good, &job, "wrong").error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(cluster.GetJob(good, &job, kWorkerToken).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  {
    grpc::ClientContext context;
    PrepareCall(&context, kClientToken, seconds(10));
    pdsm::v1::LeaseTaskRequest request;
    request.set_worker_id("intruder");
    pdsm::v1::LeaseTaskResponse response;
    EXPECT_EQ(cluster.WorkersStub()->LeaseTask(&context, request, &response).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);
  }
  const auto submit = [&](const pdsm::v1::Scene& s) {
    grpc::ClientContext context;
    PrepareCall(&context, kClientToken, seconds(30));
    pdsm::v1::SubmitBakeRequest request;
    request.set_idempotency_key("bad-" + std::to_string(rand()));
    *request.mutable_scene() = s;
    pdsm::v1::Job out;
    return cluster.JobsStub()->SubmitBake(&context, request, &out);
  };
  pdsm::v1::Scene bad;
  bad.mutable_light()->mutable_rect()->add_center(0);  // 1 number, needs 3
  grpc::Status status = submit(bad);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("light.rect.center"), std::string::npos)
      << status.error_message();

  pdsm::v1::Scene path_scene;
  path_scene.add_meshes()->set_path("/etc/passwd");
  auto* rect = path_scene.mutable_light()->mutable_rect();
  for (double x : {0.0, 10.0, 0.0}) rect->add_center(x);
  for (double x : {0.0, -1.0, 0.0}) rect->add_normal(x);
  for (double x : {0.0, 0.0, 1.0}) rect->add_up(x);
  for (double x : {1.0, 1.0}) rect->add_size(x);
  status = submit(path_scene);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("meshes[0].path"), std::string::npos);

  // Several lights: each within the limits, the one that is not named by its index and name.
  pdsm::v1::Scene several;
  auto* triangle = several.add_meshes()->mutable_inline_();
  for (double x : {0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0}) triangle->add_positions(x);
  for (int i : {0, 1, 2}) triangle->add_indices(i);
  for (const char* name : {"a", "b"}) {
    pdsm::v1::Light* light = several.add_lights();
    light->set_name(name);
    *light->mutable_rect() = path_scene.light().rect();
  }
  several.mutable_lights(0)->mutable_bake()->add_resolution(64);
  several.mutable_lights(0)->mutable_bake()->add_resolution(64);
  status = submit(several);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(status.error_message().find("lights[1] \"b\": bake.resolution"), std::string::npos)
      << status.error_message();

  pdsm::v1::Scene unknown_asset = path_scene;
  unknown_asset.mutable_meshes(0)->set_asset_sha256(std::string(64, 'a'));
  EXPECT_EQ(submit(unknown_asset).error_code(), grpc::StatusCode::FAILED_PRECONDITION);

  pdsm::v1::Scene too_big = unknown_asset;
  auto* mesh = too_big.mutable_meshes(0)->mutable_inline_();
  for (int i = 0; i < 9; ++i) mesh->add_positions(i % 3);
  for (int i = 0; i < 3; ++i) mesh->add_indices(i);
  too_big.mutable_bake()->add_resolution(512);
  too_big.mutable_bake()->add_resolution(512);
  EXPECT_EQ(submit(too_big).error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);

  pdsm::v1::Scene oversized = too_big;
  oversized.mutable_bake()->clear_resolution();
  for (int i = 0; i < 200'000; ++i)
    mesh = oversized.mutable_meshes(0)->mutable_inline_(), mesh->add_positions(0.5);
  EXPECT_EQ(submit(oversized).error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);

  // The CLI without a token says what is missing and exits non-zero.
  CommandResult no_token = RunCommand(
      std::string(PDSM_CLI) + " status " + good + " --server " + cluster.address(), cluster.dir());
  EXPECT_NE(no_token.exit_code, 0);
  EXPECT_NE(no_token.err.find("--token-file"), std::string::npos) << no_token.err;

  // None of it disturbed the good job.
  job = cluster.WaitForEnd(good);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error();
  EXPECT_TRUE(FetchBytes(cluster, good) == expected);
}

// The monitoring token follows the farm (job state, lists, watches, stats) and can do nothing
// else: no submit, cancel, fetch, query or tile read, and nothing on the worker API.
TEST(Service, MonitoringTokenReadsJobStateAndNothingElse) {
  ClusterOptions options = WithTokens();
  options.monitor_token = "monitor-secret";
  ServiceCluster cluster(options);
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string scene = WriteServiceScene(cluster.dir(), 64, 16, 32);
  const std::string job_id = cluster.Submit(scene);  // no worker: it stays queued
  ASSERT_FALSE(job_id.empty());
  const std::string monitor = "monitor-secret";
  const auto call = [&]() {
    auto context = std::make_unique<grpc::ClientContext>();
    PrepareCall(context.get(), monitor, seconds(10));
    return context;
  };
  auto jobs = cluster.JobsStub();
  pdsm::v1::GetJobRequest by_id;
  by_id.set_job_id(job_id);

  // Allowed: the read-only state calls.
  pdsm::v1::Job job;
  ASSERT_TRUE(cluster.GetJob(job_id, &job, monitor).ok());
  EXPECT_EQ(job.state(), pdsm::v1::QUEUED);
  pdsm::v1::ListJobsResponse listed;
  EXPECT_TRUE(jobs->ListJobs(call().get(), {}, &listed).ok());
  EXPECT_EQ(listed.jobs_size(), 1);
  pdsm::v1::Stats stats;
  EXPECT_TRUE(jobs->GetStats(call().get(), {}, &stats).ok());
  EXPECT_EQ(stats.jobs_queued(), 1);
  {
    auto context = call();
    auto watch = jobs->WatchJob(context.get(), by_id);
    pdsm::v1::Job first;
    EXPECT_TRUE(watch->Read(&first));
    EXPECT_EQ(first.job_id(), job_id);
    context->TryCancel();
    watch->Finish();
  }

  // Refused: everything that changes a job or reads its contents, and the worker API.
  const auto denied = [](const grpc::Status& s) {
    return s.error_code() == grpc::StatusCode::PERMISSION_DENIED &&
           s.error_message().find("monitoring token") != std::string::npos;
  };
  pdsm::v1::SubmitBakeRequest submit;
  submit.set_idempotency_key("from-a-monitor");
  EXPECT_TRUE(denied(jobs->SubmitBake(call().get(), submit, &job)));
  EXPECT_TRUE(denied(jobs->CancelJob(call().get(), by_id, &job)));
  pdsm::v1::FinishedTiles tiles;
  pdsm::v1::ListFinishedTilesRequest list;
  list.set_job_id(job_id);
  EXPECT_TRUE(denied(jobs->ListFinishedTiles(call().get(), list, &tiles)));
  pdsm::v1::QueryAttenuationRequest query;
  query.set_job_id(job_id);
  pdsm::v1::QueryAttenuationResponse answer;
  EXPECT_TRUE(denied(jobs->QueryAttenuation(call().get(), query, &answer)));
  {
    auto context = call();
    auto fetch = jobs->FetchPdsm(context.get(), by_id);
    pdsm::v1::PdsmChunk chunk;
    EXPECT_FALSE(fetch->Read(&chunk));
    EXPECT_TRUE(denied(fetch->Finish()));
  }
  pdsm::v1::LeaseTaskRequest lease;
  lease.set_worker_id("monitor");
  pdsm::v1::LeaseTaskResponse leased;
  EXPECT_TRUE(denied(cluster.WorkersStub()->LeaseTask(call().get(), lease, &leased)));

  // The CLI: `pdsm status` works with the monitoring token, `pdsm cancel` says why it cannot.
  CommandResult status =
      RunCommand(std::string(PDSM_CLI) + " status " + job_id + " --server " + cluster.address() +
                     " --token-file " + cluster.dir().File("monitor_token"),
                 cluster.dir());
  EXPECT_EQ(status.exit_code, 0) << status.err;
  EXPECT_NE(status.out.find("QUEUED"), std::string::npos) << status.out;
  CommandResult cancel =
      RunCommand(std::string(PDSM_CLI) + " cancel " + job_id + " --server " + cluster.address() +
                     " --token-file " + cluster.dir().File("monitor_token"),
                 cluster.dir());
  EXPECT_NE(cancel.exit_code, 0);
  EXPECT_NE(cancel.err.find("monitoring token"), std::string::npos) << cancel.err;
  ASSERT_TRUE(cluster.GetJob(job_id, &job).ok());
  EXPECT_EQ(job.state(), pdsm::v1::QUEUED);
}

// A monitoring token needs a client token (else it restricts nothing) and a secret of its own.
TEST(Service, CoordinatorRefusesAMonitoringTokenThatWouldRestrictNothing) {
  TempDir dir;
  WriteText(dir.File("a"), "secret-a\n");
  WriteText(dir.File("b"), "secret-b\n");
  const std::string base = std::string(PDSM_COORDINATOR) + " --listen 127.0.0.1:0 --data-dir " +
                           dir.File("data") + " --monitor-token-file " + dir.File("a");
  CommandResult alone = RunCommand(base, dir);
  EXPECT_EQ(alone.exit_code, 2);
  EXPECT_NE(alone.err.find("needs --client-token-file"), std::string::npos) << alone.err;
  CommandResult same = RunCommand(
      base + " --client-token-file " + dir.File("b") + " --worker-token-file " + dir.File("a"),
      dir);
  EXPECT_EQ(same.exit_code, 2);
  EXPECT_NE(same.err.find("a secret of its own"), std::string::npos) << same.err;
}

TEST(Service, TlsCarriesTheWholeBakeAndPlaintextClientsAreRefused) {
  ClusterOptions options = WithTokens();
  options.tls = true;
  ServiceCluster cluster(options);
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  cluster.AddWorker();
  const std::string scene = WriteServiceScene(cluster.dir(), 64, 16, 32);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  const std::string job_id = cluster.Submit(scene);
  ASSERT_EQ(cluster.WaitForEnd(job_id).state(), pdsm::v1::SUCCEEDED) << cluster.Log("worker0.log");
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected);

  // A client that does not speak TLS gets no answer, let alone a job.
  auto plaintext = pdsm::v1::PdsmJobs::NewStub(*MakeChannel({cluster.address(), ""}));
  grpc::ClientContext context;
  PrepareCall(&context, kClientToken, seconds(5));
  pdsm::v1::GetJobRequest request;
  request.set_job_id(job_id);
  pdsm::v1::Job job;
  EXPECT_EQ(plaintext->GetJob(&context, request, &job).error_code(), grpc::StatusCode::UNAVAILABLE);
}

// grpc.health.v1.Health/Check over a generic stub (the health proto is not in our schema):
// an empty HealthCheckRequest asks about the whole server; SERVING is field 1 = 1.
TEST(Service, AnswersTheStandardHealthCheckWithoutAToken) {
  ServiceCluster cluster(WithTokens());
  ASSERT_TRUE(cluster.StartCoordinator());
  std::string bytes;
  const grpc::Status status = HealthCheck(cluster, "", &bytes);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(bytes, std::string("\x08\x01", 2));  // status: SERVING
}

TEST(Service, FiftyWatchersFollowTwoJobsToTheEnd) {
  ServiceCluster cluster(CoordinatorArgs({"--samples-per-task", "16"}));
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string scene = WriteServiceScene(cluster.dir(), 128, 64, 32);
  const std::string jobs[2] = {cluster.Submit(scene), cluster.Submit(scene)};
  std::atomic<int> saw_success{0}, monotone{0};
  std::vector<std::thread> watchers;
  for (int w = 0; w < 50; ++w) {
    watchers.emplace_back([&, w] {
      auto stub = cluster.JobsStub();
      grpc::ClientContext context;
      PrepareCall(&context, "", seconds(120));
      pdsm::v1::GetJobRequest request;
      request.set_job_id(jobs[w % 2]);
      auto reader = stub->WatchJob(&context, request);
      pdsm::v1::Job job;
      int64_t last_done = -1;
      bool ordered = true;
      while (reader->Read(&job)) {
        ordered = ordered && job.samples_done() >= last_done;
        last_done = job.samples_done();
      }
      if (reader->Finish().ok() && job.state() == pdsm::v1::SUCCEEDED) ++saw_success;
      if (ordered) ++monotone;
    });
  }
  cluster.AddWorker();
  cluster.AddWorker();
  for (std::thread& t : watchers) t.join();
  EXPECT_EQ(saw_success.load(), 50);
  EXPECT_EQ(monotone.load(), 50);
}

}  // namespace
}  // namespace pdsm::testing
