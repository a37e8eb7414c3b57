// pdsm-view --server --job: waits for a job on a real coordinator and worker, fetches its PDSM
// and shows the same image as the local bake of the same scene.
#include <algorithm>
#include <chrono>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "client/view/frame_renderer.h"
#include "client/view/image_io.h"
#include "tests/service/service_cluster.h"
#include "tests/view/view_test_support.h"

namespace pdsm::testing {
namespace {

constexpr char kHolder[] = "view-server-test-holder";  // TaskHolder's worker id

// examples/plates with a bake small enough for a test (48x48 pixels, 8 samples).
std::string WriteSmallPlates(const TempDir& dir) {
  std::string scene = ReadBytes(ExamplePath("plates"));
  const std::string from = "\"resolution\": [256,256], \"samples\": 64";
  EXPECT_NE(scene.find(from), std::string::npos);
  scene.replace(scene.find(from), from.size(), "\"resolution\": [48,48], \"samples\": 8");
  WriteText(dir.File("plates.json"), scene);
  return dir.File("plates.json");
}

TEST(ViewServer, JobOnTheServiceLooksLikeTheLocalBake) {
  ServiceCluster cluster(WithTokens());
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  cluster.AddWorker();
  const std::string scene = WriteSmallPlates(cluster.dir());
  const std::string job_id = cluster.Submit(scene);
  ASSERT_EQ(job_id.size(), 16u);

  // Started at once: the viewer waits for the job to finish (WatchJob), then fetches.
  const std::string view_args = " --headless --size 96x72 --screenshot ";
  CommandResult remote =
      RunCommand(std::string(PDSM_VIEW) + " " + scene + " --server " + cluster.address() +
                     " --job " + job_id + " --token-file " + cluster.dir().File("client_token") +
                     view_args + cluster.dir().File("remote.png") + " --save-attenuation " +
                     cluster.dir().File("remote.pfm"),
                 cluster.dir());
  ASSERT_EQ(remote.exit_code, 0) << remote.err << cluster.Log("coordinator.log");
  EXPECT_NE(remote.err.find("SUCCEEDED"), std::string::npos) << remote.err;

  CommandResult bake = RunCommand(std::string(PDSM_CLI) + " bake " + scene + " -o " +
                                      cluster.dir().File("local.exr") + " --no-preview",
                                  cluster.dir());
  ASSERT_EQ(bake.exit_code, 0) << bake.err;
  CommandResult local =
      RunCommand(std::string(PDSM_VIEW) + " " + scene + " --pdsm " +
                     cluster.dir().File("local.exr") + view_args + cluster.dir().File("local.png") +
                     " --save-attenuation " + cluster.dir().File("local.pfm"),
                 cluster.dir());
  ASSERT_EQ(local.exit_code, 0) << local.err;
  // The service's PDSM has the local bake's bytes, so the renders are identical.
  EXPECT_TRUE(ReadBytes(cluster.dir().File("remote.pfm")) ==
              ReadBytes(cluster.dir().File("local.pfm")));

  // A wrong token is refused before anything is drawn.
  WriteText(cluster.dir().File("bad_token"), "nope\n");
  CommandResult refused =
      RunCommand(std::string(PDSM_VIEW) + " " + scene + " --server " + cluster.address() +
                     " --job " + job_id + " --token-file " + cluster.dir().File("bad_token") +
                     view_args + cluster.dir().File("refused.png"),
                 cluster.dir());
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_FALSE(std::filesystem::exists(cluster.dir().File("refused.png")));
}

// A worker that never works: it leases tasks of a job and sits on them.
class TaskHolder {
 public:
  // `token`: the worker token the coordinator wants ("" for none).
  explicit TaskHolder(ServiceCluster* cluster, std::string token = "")
      : cluster_(cluster), token_(std::move(token)) {}

  // Leases tasks until it holds one of every tile in `tiles`, then hands the others back. The
  // coordinator has tasks only once the job is planned: until the first one it asks again.
  // False if the queue runs dry first, or after a minute.
  bool HoldOneTaskOfEach(const std::string& job_id, std::set<int> tiles) {
    std::vector<pdsm::v1::Task> others;
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (!tiles.empty() && std::chrono::steady_clock::now() < end) {
      grpc::ClientContext context;
      PrepareCall(&context, token_, std::chrono::seconds(10));
      pdsm::v1::LeaseTaskRequest request;
      request.set_worker_id(kHolder);
      pdsm::v1::LeaseTaskResponse response;
      const grpc::Status status = cluster_->WorkersStub()->LeaseTask(&context, request, &response);
      if (!status.ok() || !response.has_task()) {
        if (!held_.empty() || !others.empty()) break;  // leased some, and now none is left
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
        continue;
      }
      EXPECT_EQ(response.task().job_id(), job_id);
      // One tile per group here: a task's tiles are its group's one tile.
      EXPECT_EQ(response.task().tile_indices_size(), 1);
      if (tiles.erase(response.task().tile_indices(0)) > 0) {
        held_.push_back(response.task());
      } else {
        others.push_back(response.task());
      }
    }
    for (const pdsm::v1::Task& task : others) HandBack(task);
    return tiles.empty();
  }

  // Returns every held task to the queue (not a failure: nothing is held against anyone).
  void HandBackAll() {
    for (const pdsm::v1::Task& task : held_) HandBack(task);
    held_.clear();
  }

 private:
  void HandBack(const pdsm::v1::Task& task) {
    grpc::ClientContext context;
    PrepareCall(&context, token_, std::chrono::seconds(10));
    pdsm::v1::ReportFailureRequest request;
    request.set_worker_id(kHolder);
    request.set_lease_id(task.lease_id());
    request.set_reason("view_server_test: held to keep the job running");
    request.set_handed_back(true);
    pdsm::v1::ReportFailureResponse response;
    EXPECT_TRUE(cluster_->WorkersStub()->ReportFailure(&context, request, &response).ok());
  }

  ServiceCluster* cluster_;
  const std::string token_;
  std::vector<pdsm::v1::Task> held_;
};

// --partial: a running job's finished tiles are shown (the rest flagged pending) and they are
// already the final PDSM's pixels.
//
// The job is kept from finishing without racing the worker: before any worker starts, the
// test itself leases one task of each of five tiles in a checkerboard (0, 2, 4, 6, 8 of the
// 3x3) and sits on them (leases of 10 minutes, longer than the test), so those tiles cannot
// complete, nor the job, until the test hands the tasks back. The worker bakes the four other
// tiles and then has nothing to lease: the partial state is fixed (4 of 9 tiles, RUNNING)
// while the viewer looks at it, and the view has baked and pending tiles side by side.
TEST(ViewServer, RunningJobShowsItsFinishedTilesAsTheyWillBe) {
  ServiceCluster cluster(CoordinatorArgs({"--samples-per-task", "4", "--lease-seconds", "600"}));
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  // 96x96 pixels in tiles of 32, each tile its own group: 9 tiles of 8 tasks each.
  std::string text = ReadBytes(WriteSmallPlates(cluster.dir()));
  const std::string from = "\"resolution\": [48,48], \"samples\": 8";
  ASSERT_NE(text.find(from), std::string::npos);
  text.replace(text.find(from), from.size(),
               "\"resolution\": [96,96], \"samples\": 32, \"tileSize\": 32, "
               "\"tileGroupSize\": 1");
  const std::string scene = cluster.dir().File("tiled.json");
  WriteText(scene, text);
  const std::string job_id = cluster.Submit(scene);
  ASSERT_EQ(job_id.size(), 16u);
  TaskHolder holder(&cluster);
  ASSERT_TRUE(holder.HoldOneTaskOfEach(job_id, {0, 2, 4, 6, 8}))
      << "could not lease the tasks to hold" << cluster.Log("coordinator.log");
  cluster.AddWorker();
  pdsm::v1::Job job =
      cluster.WaitUntil(job_id, std::chrono::seconds(120), [](const pdsm::v1::Job& j) {
        return j.tiles_done() >= 4 || j.state() == pdsm::v1::SUCCEEDED ||
               j.state() == pdsm::v1::FAILED || j.state() == pdsm::v1::CANCELLED;
      });
  ASSERT_EQ(job.state(), pdsm::v1::RUNNING) << cluster.Log("coordinator.log");
  ASSERT_EQ(job.tiles_total(), 9);
  ASSERT_EQ(job.tiles_done(), 4) << cluster.Log("coordinator.log");
  const std::string view = std::string(PDSM_VIEW) + " " + scene + " --server " + cluster.address() +
                           " --job " + job_id +
                           " --headless --size 128x96 --camera 4,7,6,0,1,0,40 --screenshot ";
  CommandResult partial =
      RunCommand(view + cluster.dir().File("partial.png") + " --partial --save-attenuation " +
                     cluster.dir().File("partial.pfm"),
                 cluster.dir());
  // The CPU evaluation of the same partial PDSM flags the same pixels as not baked yet.
  CommandResult partial_cpu = RunCommand(view + cluster.dir().File("partial_cpu.png") +
                                             " --partial --mode cpu --save-attenuation " +
                                             cluster.dir().File("partial_cpu.pfm"),
                                         cluster.dir());
  ASSERT_EQ(partial.exit_code, 0) << partial.err;
  ASSERT_EQ(partial_cpu.exit_code, 0) << partial_cpu.err;
  EXPECT_NE(partial.err.find("RUNNING"), std::string::npos) << partial.err;
  // Nothing moved while the viewer looked: the held tile is still the one missing.
  pdsm::v1::Job after;
  ASSERT_TRUE(cluster.GetJob(job_id, &after).ok());
  EXPECT_EQ(after.state(), pdsm::v1::RUNNING);
  EXPECT_EQ(after.tiles_done(), job.tiles_done());
  holder.HandBackAll();  // the worker does the held tasks and the job ends
  ASSERT_EQ(cluster.WaitForEnd(job_id).state(), pdsm::v1::SUCCEEDED);
  CommandResult final_run = RunCommand(view + cluster.dir().File("final.png") +
                                           " --save-attenuation " + cluster.dir().File("final.pfm"),
                                       cluster.dir());
  ASSERT_EQ(final_run.exit_code, 0) << final_run.err;

  absl::StatusOr<view::FloatImage> a = view::ReadPfm(cluster.dir().File("partial.pfm"));
  absl::StatusOr<view::FloatImage> b = view::ReadPfm(cluster.dir().File("final.pfm"));
  absl::StatusOr<view::FloatImage> c = view::ReadPfm(cluster.dir().File("partial_cpu.pfm"));
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  ASSERT_EQ(a->values.size(), b->values.size());
  ASSERT_EQ(a->values.size(), c->values.size());
  size_t pending_mismatch = 0;
  for (size_t i = 0; i < a->values.size(); ++i) {
    pending_mismatch += (a->values[i] == view::kPending) != (c->values[i] == view::kPending);
  }
  // Fragments on a pending tile's edge may round to the other side on the GPU (float32).
  EXPECT_LE(pending_mismatch, a->values.size() / 1000) << "pdsm and cpu disagree on pending";
  size_t pending = 0, shown = 0;
  for (size_t i = 0; i < a->values.size(); ++i) {
    if (a->values[i] == view::kPending) {
      ++pending;
      EXPECT_GE(b->values[i], -1.0f) << i;  // the final PDSM covers it
      continue;
    }
    if (a->values[i] >= 0) ++shown;
    ASSERT_EQ(a->values[i], b->values[i]) << "pixel " << i;
  }
  std::printf("partial: %d/%d tiles, %zu pixels pending, %zu shown (equal to the final)\n",
              job.tiles_done(), job.tiles_total(), pending, shown);
  EXPECT_GT(pending, 0u);
  EXPECT_GT(shown, 0u);
}

// The README's farm sequence with overrides: `pdsm submit SCENE --samples …` and then
// `pdsm-view SCENE --server … --job $job`. The scene file says 48x48 x 8 samples (one tile);
// the submit says 96x96 x 32 in 32-pixel tiles. The viewer takes the job's settings
// from GetJob, headless with --partial while the job runs and in a window (Xvfb) that
// follows it to the end, and shows what the local bake with the same overrides shows.
TEST(ViewServer, ReadmeSequenceWithOverridesInAWindowAndHeadless) {
  ServiceCluster cluster(WithTokens({"--samples-per-task", "4", "--lease-seconds", "600"}));
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  // Each tile its own group (the file's, kept by the submit), so that tasks hold one tile each.
  std::string text = ReadBytes(WriteSmallPlates(cluster.dir()));
  const std::string samples = "\"samples\": 8";
  ASSERT_NE(text.find(samples), std::string::npos);
  text.replace(text.find(samples), samples.size(), "\"samples\": 8, \"tileGroupSize\": 1");
  const std::string scene = cluster.dir().File("plates_groups.json");
  WriteText(scene, text);
  const std::string overrides = "--samples 32 --resolution 96x96 --tile-size 32";
  const std::string job_id = cluster.Submit(scene, overrides);
  ASSERT_EQ(job_id.size(), 16u);
  pdsm::v1::Job job;
  ASSERT_TRUE(cluster.GetJob(job_id, &job).ok());
  // The effective settings: the overrides, and the defaults as the coordinator resolved them.
  EXPECT_EQ(job.bake().samples(), 32u);
  ASSERT_EQ(job.bake().resolution_size(), 2);
  EXPECT_EQ(job.bake().resolution(0), 96u);
  EXPECT_EQ(job.bake().tile_size(), 32u);
  EXPECT_NE(job.bake().sampling(), pdsm::v1::SAMPLING_DEFAULT);  // resolved, not left to the viewer
  EXPECT_EQ(job.bake().shadow_map_resolution(), 512u);           // the file's, kept
  EXPECT_EQ(job.bake().tile_group_size(), 1u);                   // the file's, kept
  EXPECT_EQ(job.plan_fingerprint().size(), 64u);

  TaskHolder holder(&cluster, kWorkerToken);
  ASSERT_TRUE(holder.HoldOneTaskOfEach(job_id, {0, 2, 4, 6, 8})) << cluster.Log("coordinator.log");
  cluster.AddWorker();
  job = cluster.WaitUntil(job_id, std::chrono::seconds(120),
                          [](const pdsm::v1::Job& j) { return j.tiles_done() >= 4; });
  ASSERT_EQ(job.state(), pdsm::v1::RUNNING) << cluster.Log("coordinator.log");
  const std::string view = std::string(PDSM_VIEW) + " " + scene + " --server " + cluster.address() +
                           " --job " + job_id + " --token-file " +
                           cluster.dir().File("client_token") +
                           " --size 160x120 --camera 4,7,6,0,1,0,40";
  CommandResult partial =
      RunCommand(view + " --headless --partial --screenshot " + cluster.dir().File("partial.png") +
                     " --save-attenuation " + cluster.dir().File("partial.pfm"),
                 cluster.dir());
  ASSERT_EQ(partial.exit_code, 0) << partial.err;
  EXPECT_NE(partial.err.find("RUNNING: 4/9 tiles"), std::string::npos) << partial.err;

  // A scene file edited since the submit plans another PDSM: refused, not shown wrong.
  std::string edited = ReadBytes(scene);
  const std::string from = "\"transform\": [1.5,0,0,-1.5";
  ASSERT_NE(edited.find(from), std::string::npos);
  edited.replace(edited.find(from), from.size(), "\"transform\": [1.5,0,0,-1.25");
  WriteText(cluster.dir().File("edited.json"), edited);
  CommandResult refused =
      RunCommand(std::string(PDSM_VIEW) + " " + cluster.dir().File("edited.json") + " --server " +
                     cluster.address() + " --job " + job_id + " --token-file " +
                     cluster.dir().File("client_token") + " --headless --partial --screenshot " +
                     cluster.dir().File("edited.png"),
                 cluster.dir());
  EXPECT_EQ(refused.exit_code, 2) << refused.err;
  EXPECT_NE(refused.err.find("plans another PDSM than the job's"), std::string::npos)
      << refused.err;

  // The window: opened while the job runs, it follows it; --frames counts once the final PDSM
  // is in, then it writes its screenshot.
  const bool have_xvfb = RunCommand("command -v xvfb-run", cluster.dir()).exit_code == 0;
  std::unique_ptr<ChildProcess> window;
  if (have_xvfb) {
    // Under ASan (scripts/sanitize.sh) leaks are not checked in this one child: the X server's
    // GL driver leaks and is unloaded before LeakSanitizer reports, so no suppression can name
    // it (as for the view_window_xvfb test). Memory errors stay fatal; elsewhere it is a no-op.
    window = std::make_unique<ChildProcess>(
        std::vector<std::string>{"/bin/sh", "-c",
                                 "ASAN_OPTIONS=\"${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0\" "
                                 "xvfb-run -a -s '-screen 0 640x480x24' " +
                                     view + " --frames 2 --screenshot " +
                                     cluster.dir().File("window.png")},
        cluster.dir().File("window.log"));
    std::this_thread::sleep_for(std::chrono::seconds(1));  // it shows the running job first
  }
  holder.HandBackAll();
  ASSERT_EQ(cluster.WaitForEnd(job_id).state(), pdsm::v1::SUCCEEDED);
  CommandResult final_run =
      RunCommand(view + " --headless --screenshot " + cluster.dir().File("final.png") +
                     " --save-attenuation " + cluster.dir().File("final.pfm"),
                 cluster.dir());
  ASSERT_EQ(final_run.exit_code, 0) << final_run.err;

  // What the local bake with the same overrides shows, pixel for pixel.
  CommandResult bake =
      RunCommand(std::string(PDSM_CLI) + " bake " + scene + " -o " +
                     cluster.dir().File("local.exr") + " --no-preview " + overrides,
                 cluster.dir());
  ASSERT_EQ(bake.exit_code, 0) << bake.err;
  CommandResult local = RunCommand(std::string(PDSM_VIEW) + " " + scene + " --pdsm " +
                                       cluster.dir().File("local.exr") +
                                       " --size 160x120 --camera 4,7,6,0,1,0,40 --headless "
                                       "--screenshot " +
                                       cluster.dir().File("local.png") + " --save-attenuation " +
                                       cluster.dir().File("local.pfm"),
                                   cluster.dir());
  ASSERT_EQ(local.exit_code, 0) << local.err;
  EXPECT_TRUE(ReadBytes(cluster.dir().File("final.pfm")) ==
              ReadBytes(cluster.dir().File("local.pfm")));
  absl::StatusOr<view::FloatImage> a = view::ReadPfm(cluster.dir().File("partial.pfm"));
  absl::StatusOr<view::FloatImage> b = view::ReadPfm(cluster.dir().File("final.pfm"));
  ASSERT_TRUE(a.ok() && b.ok());
  size_t pending = 0, shown = 0;
  for (size_t i = 0; i < a->values.size(); ++i) {
    if (a->values[i] == view::kPending) {
      ++pending;
    } else {
      shown += a->values[i] >= 0;
      ASSERT_EQ(a->values[i], b->values[i]) << "pixel " << i;
    }
  }
  EXPECT_GT(pending, 0u);
  EXPECT_GT(shown, 0u);

  if (!have_xvfb) {
    // Reported as skipped, not passed: the window half did not run.
    GTEST_SKIP() << "xvfb-run not installed (deploy/install_deps.sh installs it): the headless "
                    "half passed, the window half did not run";
  }
  const int status = window->Wait(std::chrono::seconds(120));
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0)
      << status << ": " << cluster.Log("window.log");
  absl::StatusOr<view::RgbImage> shot = view::ReadPng(cluster.dir().File("window.png"));
  absl::StatusOr<view::RgbImage> headless = view::ReadPng(cluster.dir().File("final.png"));
  ASSERT_TRUE(shot.ok() && headless.ok()) << cluster.Log("window.log");
  ASSERT_EQ(shot->rgb.size(), headless->rgb.size());
  size_t differing = 0;
  for (size_t i = 0; i < shot->rgb.size(); i += 3) {
    int d = 0;
    for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(shot->rgb[i + c] - headless->rgb[i + c]));
    differing += d > 8;
  }
  EXPECT_LE(differing, shot->rgb.size() / 3 / 100) << "the window shows another image";
}

}  // namespace
}  // namespace pdsm::testing
