// The service bakes every light of a scene in one job: a sun, a rect and a spot with its own
// samples, their tasks in one queue, one multipart file byte-identical to `pdsm bake`'s, the
// progress, tiles and queries of each light by its name, a sphere light's faces, and a
// restart mid-job.
#include <algorithm>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/pdsm/pdsm_file.h"
#include "tests/service/service_cluster.h"

namespace pdsm::testing {
namespace {

using std::chrono::seconds;

// examples/courtyard made small: 3 lights (sun, rect "lamp", spot with 8 samples of its own),
// `resolution`² at tile size 16, `samples` samples for the other two.
std::string WriteCourtyard(const TempDir& dir, int resolution, int samples) {
  std::string text = ReadBytes(ExamplePath("courtyard"));
  const auto replace = [&](const std::string& from, const std::string& to) {
    const size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
  };
  replace(R"("bake": {"samples": 32})", R"("bake": {"samples": 8})");
  replace(R"("resolution": [256,256], "samples": 64, "shadowMapResolution": 512)",
          "\"resolution\": [" + std::to_string(resolution) + "," + std::to_string(resolution) +
              "], \"samples\": " + std::to_string(samples) +
              ", \"shadowMapResolution\": 256, \"tileSize\": 16");
  const std::string path = dir.File("courtyard.json");
  WriteText(path, text);
  return path;
}

grpc::Status ListTiles(ServiceCluster& cluster, const std::string& job_id, const std::string& light,
                       pdsm::v1::FinishedTiles* tiles) {
  grpc::ClientContext context;
  PrepareCall(&context, "", seconds(10));
  pdsm::v1::ListFinishedTilesRequest request;
  request.set_job_id(job_id);
  request.set_light(light);
  return cluster.JobsStub()->ListFinishedTiles(&context, request, tiles);
}

grpc::Status FetchTile(ServiceCluster& cluster, const std::string& job_id, const std::string& light,
                       int index) {
  grpc::ClientContext context;
  PrepareCall(&context, "", seconds(10));
  pdsm::v1::FetchTileRequest request;
  request.set_job_id(job_id);
  request.set_light(light);
  request.set_tile_index(index);
  auto reader = cluster.JobsStub()->FetchTile(&context, request);
  pdsm::v1::PdsmChunk chunk;
  while (reader->Read(&chunk)) {
  }
  return reader->Finish();
}

// `pdsm query --job` prints what `pdsm query` of the local bake (LocalBakeBytes' local.exr)
// prints, with each of `flags` (" --light NAME", or none).
void ExpectJobAnswersAsTheLocalFile(ServiceCluster& cluster, const std::string& job_id,
                                    const std::string& points,
                                    const std::vector<std::string>& flags) {
  const std::string local = cluster.dir().File("local.exr");
  for (const std::string& flag : flags) {
    CommandResult from_file = cluster.Pdsm("query " + local + " --points " + points + flag);
    CommandResult from_job = cluster.Pdsm("query --job " + job_id + " --points " + points + flag);
    ASSERT_EQ(from_file.exit_code, 0) << from_file.err;
    ASSERT_EQ(from_job.exit_code, 0) << from_job.err;
    EXPECT_EQ(from_job.out, from_file.out) << flag;
  }
}

TEST(ServiceLights, EveryLightOfAJobMatchesTheLocalBakeAndAnswersByName) {
  ServiceCluster cluster(CoordinatorArgs({"--samples-per-task", "4"}));
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string scene = WriteCourtyard(cluster.dir(), 64, 16);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  ASSERT_FALSE(expected.empty());

  // Queued (no worker yet): each light's size and progress, its tiles by its name.
  const std::string job_id = cluster.Submit(scene);
  ASSERT_FALSE(job_id.empty());
  pdsm::v1::Job queued;
  ASSERT_TRUE(cluster.GetJob(job_id, &queued).ok());
  ASSERT_EQ(queued.lights_size(), 3);
  const std::vector<std::string> names = {"sun", "lamp", "spot"};
  const std::vector<int> samples = {16, 16, 8};
  int tiles = 0;
  int64_t work = 0;
  for (int i = 0; i < 3; ++i) {
    const pdsm::v1::LightProgress& l = queued.lights(i);
    EXPECT_EQ(l.name(), names[i]);
    EXPECT_EQ(l.width(), 64);
    EXPECT_EQ(l.samples(), samples[i]);
    EXPECT_EQ(l.bake().samples(), static_cast<uint32_t>(samples[i]));
    EXPECT_EQ(l.tiles_total(), 16);
    // Only the tiles no caster reaches are stored before a worker comes: all lit, no task.
    EXPECT_LT(l.tiles_done(), l.tiles_total());
    EXPECT_FALSE(l.plan_fingerprint().empty());
    tiles += l.tiles_total();
    work += l.samples_total();
  }
  EXPECT_NE(queued.lights(0).plan_fingerprint(), queued.lights(1).plan_fingerprint());
  EXPECT_EQ(queued.tiles_total(), tiles);
  EXPECT_EQ(queued.samples_total(), work);
  pdsm::v1::FinishedTiles listed;
  grpc::Status s = ListTiles(cluster, job_id, "", &listed);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(s.error_message().find("\"sun\", \"lamp\", \"spot\""), std::string::npos)
      << s.error_message();
  s = ListTiles(cluster, job_id, "moon", &listed);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND) << s.error_message();
  ASSERT_TRUE(ListTiles(cluster, job_id, "lamp", &listed).ok());
  EXPECT_EQ(listed.tile_indices_size(), queued.lights(1).tiles_done());
  const std::set<int> stored(listed.tile_indices().begin(), listed.tile_indices().end());
  for (int t = 0; t < 16; ++t) {
    EXPECT_EQ(FetchTile(cluster, job_id, "lamp", t).error_code(),
              stored.count(t) ? grpc::StatusCode::OK : grpc::StatusCode::NOT_FOUND)
        << t;
  }
  EXPECT_EQ(FetchTile(cluster, job_id, "lamp", 16).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(FetchTile(cluster, job_id, "sun/..", 0).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);

  // Two workers share the three lights' tasks; the file is the local bake's, byte for byte.
  cluster.AddWorker();
  cluster.AddWorker();
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error() << cluster.Log("coordinator.log");
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected) << "fetched PDSM differs from local bake";
  EXPECT_EQ(job.tile_assemblies(), job.tiles_total());
  for (const pdsm::v1::LightProgress& l : job.lights()) {
    EXPECT_EQ(l.tiles_done(), l.tiles_total()) << l.name();
    EXPECT_DOUBLE_EQ(l.progress(), 1.0) << l.name();
  }
  CommandResult status = cluster.Pdsm("status " + job_id);
  EXPECT_NE(status.out.find("light spot: 64x64, 8 samples, 100.0% (16/16 tiles)"),
            std::string::npos)
      << status.out;

  // The coordinator's queries print what `pdsm query` of the local file prints: one column
  // per light, or the one named.
  const std::string points = cluster.dir().File("points.csv");
  std::ostringstream csv;
  for (int i = 0; i < 40; ++i) csv << (-9 + 0.45 * i) << ",0.01," << (4 - 0.2 * i) << "\n";
  WriteText(points, csv.str());
  ExpectJobAnswersAsTheLocalFile(cluster, job_id, points, {"", " --light spot"});
  CommandResult first = cluster.Pdsm("query --job " + job_id + " --points " + points);
  EXPECT_EQ(std::count(first.out.begin(), first.out.begin() + first.out.find('\n'), ','), 5)
      << "x,y,z and one column per light";
  CommandResult moon =
      cluster.Pdsm("query --job " + job_id + " --points " + points + " --light moon");
  EXPECT_NE(moon.exit_code, 0);
  EXPECT_NE(moon.err.find("no light \"moon\""), std::string::npos) << moon.err;
}

// A sphere light is six lights to the service, its faces: every worker turns a group's
// samples the same way (core/bake/face_samples.h), so the file is `pdsm bake`'s, and the
// coordinator answers the sphere by its name with one value per point.
TEST(ServiceLights, ASphereLightsFacesMatchTheLocalBakeAndAnswerAsOneLight) {
  ServiceCluster cluster(CoordinatorArgs({"--samples-per-task", "4"}));
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string scene = cluster.dir().File("sphere.json");
  WriteText(scene,
            R"({"name": "bulb", "meshes": [)"
            R"({"inline": {"positions": [-8,0,-8, 8,0,-8, 8,0,8, -8,0,8],)"
            R"( "indices": [0,1,2, 0,2,3]}, "role": "RECEIVER_ONLY"},)"
            R"( {"inline": {"positions": [-1,2,-1, 1,2,-1, 1,2,1, -1,2,1],)"
            R"( "indices": [0,1,2, 0,2,3]}, "role": "CASTER_ONLY"},)"
            R"( {"inline": {"positions": [4,0,-1, 4,0,1, 4,2,1, 4,2,-1],)"
            R"( "indices": [0,1,2, 0,2,3]}, "role": "CASTER_ONLY"}],)"
            R"( "lights": [{"name": "lamp", "sphere": {"center": [0.5,4,0], "radius": 0.3}}],)"
            R"( "bake": {"resolution": [64, 64], "samples": 8, "tileSize": 16}})");
  const pdsm::v1::Job job = ExpectServiceBakesAsLocal(cluster, scene);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED);
  const std::string& job_id = job.job_id();
  ASSERT_EQ(job.lights_size(), 6);
  EXPECT_EQ(job.lights(0).name(), "lamp@+x");
  const std::string points = cluster.dir().File("points.csv");
  WriteText(points, "0,0,0\n7,0,0\n-6,0,-5\n0.5,3,0\n");
  ExpectJobAnswersAsTheLocalFile(cluster, job_id, points,
                                 {"", " --light lamp", " --light lamp@+x"});
  CommandResult sphere = cluster.Pdsm("query --job " + job_id + " --points " + points);
  EXPECT_EQ(sphere.out.substr(0, sphere.out.find('\n')), "0,0,0,1.000000")
      << "one column, the sphere's: under the plate";
}

// A coordinator killed while the lights are under way resumes each with only its missing
// tiles, and the file is the same.
TEST(ServiceLights, CoordinatorKilledMidJobResumesEveryLight) {
  ServiceCluster cluster(
      CoordinatorArgs({"--samples-per-task", "8", "--lease-seconds", LeaseSeconds(2)}));
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string scene = WriteCourtyard(cluster.dir(), 128, 256);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  cluster.AddWorker();
  const std::string job_id = cluster.Submit(scene);
  const pdsm::v1::Job partial = cluster.WaitUntil(
      job_id, seconds(120), [](const auto& j) { return j.tiles_done() >= 80 || Ended(j); });
  ASSERT_FALSE(Ended(partial)) << "the job ended before the coordinator could be killed";
  cluster.coordinator().Signal(SIGKILL);
  cluster.coordinator().Wait(seconds(10));
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  pdsm::v1::Job resumed;
  ASSERT_TRUE(cluster.GetJob(job_id, &resumed).ok());
  int done = 0;
  for (const pdsm::v1::LightProgress& l : resumed.lights()) done += l.tiles_done();
  EXPECT_EQ(done, resumed.tiles_done());
  EXPECT_GE(done, 80);
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error();
  EXPECT_EQ(job.tile_assemblies(), job.tiles_total());
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected);
}

}  // namespace
}  // namespace pdsm::testing
