// Adaptive resolution through the service (issue #15 item 2): the coordinator chooses the
// refined pixels from the stored base map, workers bake the refinement level from the pixels
// FetchRefinement hands them, and the fetched file is `pdsm bake`'s, byte for byte, also when
// the coordinator is killed while the level runs.
#include <chrono>
#include <csignal>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/refined_pixel.h"
#include "tests/box_on_plane.h"
#include "tests/service/service_cluster.h"

namespace pdsm::testing {
namespace {

constexpr char kFlags[] = "--max-refinement 4 --resolution 64x64 --samples 16";

std::string WriteBox(const ServiceCluster& cluster) {
  const std::string path = cluster.dir().File("box_on_plane.json");
  WriteText(path, kBoxOnPlaneJson);
  return path;
}

// The same scene with the box as a mesh file: `pdsm submit` uploads it as an asset, which the
// coordinator decodes again to plan the level; and the ground opted out of refinement
// (`"refine": false`), which the coordinator's choice of pixels must honour as the local one.
std::string WriteBoxAsset(const ServiceCluster& cluster) {
  WriteText(cluster.dir().File("box.obj"),
            "v -0.5 0 -0.5\nv 0.5 0 -0.5\nv 0.5 0 0.5\nv -0.5 0 0.5\n"
            "v -0.5 1 -0.5\nv 0.5 1 -0.5\nv 0.5 1 0.5\nv -0.5 1 0.5\n"
            "f 1 2 3\nf 1 3 4\nf 5 7 6\nf 5 8 7\nf 1 5 6\nf 1 6 2\n"
            "f 2 6 7\nf 2 7 3\nf 3 7 8\nf 3 8 4\nf 4 8 5\nf 4 5 1\n");
  std::string json = kBoxOnPlaneJson;
  const size_t box = json.find("    {\"inline\": {\"positions\": [-0.5");
  const size_t end = json.find("]}}\n", box) + 4;
  json.replace(box, end - box, "    {\"path\": \"box.obj\"}\n");
  const std::string ground = R"("role": "RECEIVER_ONLY"})";
  json.replace(json.find(ground), ground.size(), R"("role": "RECEIVER_ONLY", "refine": false})");
  const std::string path = cluster.dir().File("box_asset.json");
  WriteText(path, json);
  return path;
}

// Pixels of the file at `path` that hold refined sub-functions.
int RefinedPixelsOf(const std::string& path) {
  absl::StatusOr<PdsmImage> image = ReadPdsm(path);
  EXPECT_TRUE(image.ok()) << image.status();
  if (!image.ok()) return 0;
  const PdsmGeometry& g = image->header.geometry;
  int refined = 0;
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) refined += RefinementOf(image->Function(x, y)) > 1;
  }
  return refined;
}

TEST(ServiceRefined, MatchesTheLocalBakeByteForByte) {
  ServiceCluster cluster(CoordinatorArgs({"--samples-per-task", "4"}));
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  const pdsm::v1::Job job = ExpectServiceBakesAsLocal(cluster, WriteBoxAsset(cluster), 2, kFlags);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED);
  // Not a bake that refined nothing: the level ran on the workers.
  EXPECT_GT(RefinedPixelsOf(cluster.dir().File("local.exr")), 20);
  EXPECT_NE(cluster.Log("coordinator.log").find("refining"), std::string::npos);
  const bool planned =
      cluster.Log("worker0.log").find("refinement level 4x") != std::string::npos ||
      cluster.Log("worker1.log").find("refinement level 4x") != std::string::npos;
  EXPECT_TRUE(planned) << "no worker planned the level";
}

// Every light of a scene of several has its own level (three engine jobs more).
TEST(ServiceRefined, EachLightOfSeveralRefinesAsLocally) {
  ServiceCluster cluster(CoordinatorArgs({"--samples-per-task", "2"}));
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  const pdsm::v1::Job job = ExpectServiceBakesAsLocal(
      cluster, ExamplePath("courtyard"), 2, "--max-refinement 2 --resolution 64x64 --samples 8");
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED);
  const std::string log = cluster.Log("coordinator.log");
  for (const char* light : {"sun", "lamp", "spot"}) {
    EXPECT_NE(log.find(std::string("light \"") + light + "\": refining"), std::string::npos)
        << light << "\n"
        << log;
  }
}

// Killed while the level runs, the coordinator resumes the base map from its log, chooses the
// same pixels from it and bakes the level again: the same bytes.
TEST(ServiceRefined, ARestartWhileTheLevelRunsGivesTheSameBytes) {
  ServiceCluster cluster(CoordinatorArgs({"--samples-per-task", "1"}));
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  const std::string scene = WriteBox(cluster);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene, kFlags);
  ASSERT_FALSE(expected.empty());
  const std::string job_id = cluster.Submit(scene, kFlags);
  ASSERT_FALSE(job_id.empty());
  // What its plans hold before any worker came: the base map's (--max-planned-mib).
  const int64_t base_bytes = cluster.Stats().planned_bytes();
  EXPECT_GT(base_bytes, 0);
  cluster.AddWorker();
  // Until the job shows its level running (bounded: 120 s), with its progress.
  pdsm::v1::Job running;
  for (int i = 0; i < 1200; ++i) {
    if (cluster.GetJob(job_id, &running).ok() && running.lights_size() == 1 &&
        running.lights(0).has_refinement_level()) {
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_EQ(running.lights_size(), 1);
  ASSERT_TRUE(running.lights(0).has_refinement_level()) << cluster.Log("coordinator.log");
  const pdsm::v1::RefinementLevelProgress& level = running.lights(0).refinement_level();
  EXPECT_EQ(level.factor(), 4);
  EXPECT_GT(level.pixels(), 20);
  EXPECT_EQ(level.tiles_total(), 16);  // 256^2 in tiles of 64
  EXPECT_EQ(running.state(), pdsm::v1::RUNNING);
  EXPECT_EQ(running.lights(0).tiles_done(), running.lights(0).tiles_total()) << "its base map";
  // Its base maps are baked but the job is not done in 0 s: its ETA is the level's (unknown
  // until the level has a rate).
  EXPECT_NE(running.eta_seconds(), 0.0);
  if (level.eta_seconds() >= 0) EXPECT_DOUBLE_EQ(running.eta_seconds(), level.eta_seconds());
  // The level's plan and pixels are counted with the job's plans, so later jobs wait for them.
  EXPECT_GT(cluster.Stats().planned_bytes(), base_bytes);
  cluster.coordinator().Signal(SIGKILL);
  cluster.coordinator().Wait(std::chrono::seconds(10));
  pdsm::v1::Job before;
  const size_t log_before = cluster.Log("coordinator.log").size();
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  ASSERT_TRUE(cluster.GetJob(job_id, &before).ok());
  // Killed before the job could end: the restarted coordinator resumes it.
  ASSERT_NE(before.state(), pdsm::v1::SUCCEEDED) << "the level ended before the kill";
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error() << cluster.Log("coordinator.log");
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected) << "fetched PDSM differs from local bake";
  // The restarted coordinator chose the pixels again (its part of the log).
  EXPECT_NE(cluster.Log("coordinator.log").substr(log_before).find("refining"), std::string::npos);
}

// FetchRefinement is a worker call: the worker token, a well-formed job id and light name, and
// a light whose level runs.
TEST(ServiceRefined, FetchRefinementRefusesWhatItCannotServe) {
  ServiceCluster cluster(WithTokens());
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  const auto fetch = [&](const std::string& token, const std::string& job,
                         const std::string& light) {
    grpc::ClientContext context;
    PrepareCall(&context, token, std::chrono::seconds(10));
    pdsm::v1::FetchRefinementRequest request;
    request.set_job_id(job);
    request.set_light(light);
    std::unique_ptr<grpc::ClientReader<pdsm::v1::AssetData>> reader =
        cluster.WorkersStub()->FetchRefinement(&context, request);
    pdsm::v1::AssetData chunk;
    while (reader->Read(&chunk)) {
    }
    return reader->Finish().error_code();
  };
  EXPECT_EQ(fetch("", "0123abcd", ""), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(fetch(kClientToken, "0123abcd", ""), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(fetch(kWorkerToken, "no/such job", ""), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(fetch(kWorkerToken, "0123abcd", "bad name!"), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(fetch(kWorkerToken, "0123abcd", ""), grpc::StatusCode::FAILED_PRECONDITION);
}

}  // namespace
}  // namespace pdsm::testing
