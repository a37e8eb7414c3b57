// Requests an attacker or a broken client sends (issue #17, finding 8), against a real
// coordinator: what a status echoes stays short, ids and names are bounded, control
// characters cannot forge log lines, asset chunks keep to the protocol, tile indices are
// checked, and health answers per service.
#include <climits>
#include <cmath>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "core/assets/mesh_asset.h"
#include "tests/service/service_cluster.h"

namespace pdsm::testing {
namespace {

using std::chrono::seconds;

// Short enough for any client's metadata limit, whatever the request held.
constexpr size_t kShortMessage = 4096;

grpc::Status CallGetJob(ServiceCluster& cluster, const std::string& job_id) {
  pdsm::v1::Job job;
  return cluster.GetJob(job_id, &job);
}

grpc::Status Upload(ServiceCluster& cluster, const std::vector<pdsm::v1::AssetChunk>& chunks) {
  grpc::ClientContext context;
  PrepareCall(&context, "", seconds(30));
  pdsm::v1::UploadAssetResponse response;
  std::unique_ptr<grpc::ClientWriter<pdsm::v1::AssetChunk>> writer =
      cluster.JobsStub()->UploadAsset(&context, &response);
  for (const pdsm::v1::AssetChunk& chunk : chunks) {
    if (!writer->Write(chunk)) break;
  }
  writer->WritesDone();
  return writer->Finish();
}

TEST(HostileRequests, EchoedInputIsBoundedAndIdsAreChecked) {
  ServiceCluster cluster;
  ASSERT_TRUE(cluster.StartCoordinator());
  // A 1,000,000-character job_id used to come back whole in the status message.
  for (const std::string& id : {std::string(1'000'000, 'a'), std::string("a\nb"), std::string()}) {
    const grpc::Status s = CallGetJob(cluster, id);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << id.size();
    EXPECT_LT(s.error_message().size(), kShortMessage);
    EXPECT_NE(s.error_message().find("job_id"), std::string::npos) << s.error_message();
  }
  EXPECT_EQ(CallGetJob(cluster, "0123456789abcdef").error_code(), grpc::StatusCode::NOT_FOUND);
  {
    grpc::ClientContext context;
    PrepareCall(&context, "", seconds(10));
    pdsm::v1::GetJobRequest request;
    request.set_job_id(std::string(100'000, 'z'));
    auto reader = cluster.JobsStub()->WatchJob(&context, request);
    pdsm::v1::Job job;
    while (reader->Read(&job)) {
    }
    const grpc::Status s = reader->Finish();
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_LT(s.error_message().size(), kShortMessage);
  }
  // A 5 MiB scene name: refused naming the field (it made ListJobs outgrow 4 MiB).
  pdsm::v1::SubmitBakeRequest submit;
  submit.set_idempotency_key("long-name");
  submit.mutable_scene()->set_name(std::string(5 << 20, 'n'));
  {
    grpc::ClientContext context;
    PrepareCall(&context, "", seconds(30));
    pdsm::v1::Job job;
    const grpc::Status s = cluster.JobsStub()->SubmitBake(&context, submit, &job);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(s.error_message().find(": name: at most 256 bytes"), std::string::npos)
        << s.error_message().substr(0, 200);
    EXPECT_LT(s.error_message().size(), kShortMessage);
  }
}

TEST(HostileRequests, ControlCharactersCannotForgeLogLines) {
  ServiceCluster cluster;
  ASSERT_TRUE(cluster.StartCoordinator());
  const auto workers = cluster.WorkersStub();
  {
    grpc::ClientContext context;
    PrepareCall(&context, "", seconds(10));
    pdsm::v1::LeaseTaskRequest request;
    request.set_worker_id("w1\n[coordinator] [info] forged by worker_id");
    pdsm::v1::LeaseTaskResponse response;
    EXPECT_EQ(workers->LeaseTask(&context, request, &response).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT);
  }
  {
    grpc::ClientContext context;
    PrepareCall(&context, "", seconds(10));
    pdsm::v1::ReportFailureRequest request;
    request.set_worker_id("w1");
    request.set_lease_id(12345);
    request.set_reason("boom\n[2030-01-01 00:00:00.000] [coordinator] [error] forged\x1b[2J");
    pdsm::v1::ReportFailureResponse response;
    ASSERT_TRUE(workers->ReportFailure(&context, request, &response).ok());
  }
  {
    grpc::ClientContext context;
    PrepareCall(&context, "", seconds(10));
    pdsm::v1::ReportFailureRequest request;
    request.set_worker_id("w1\r\nforged by a failure's worker_id");
    pdsm::v1::ReportFailureResponse response;
    EXPECT_EQ(workers->ReportFailure(&context, request, &response).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT);
  }
  cluster.coordinator().Signal(SIGTERM);
  cluster.coordinator().Wait(std::chrono::seconds(30));
  const std::string log = cluster.Log("coordinator.log");
  ASSERT_NE(log.find("boom\\n[2030-01-01"), std::string::npos) << log;
  std::istringstream lines(log);
  for (std::string line; std::getline(lines, line);) {
    if (line.find("forged") == std::string::npos) continue;
    EXPECT_NE(line.find("boom"), std::string::npos) << "a forged line: " << line;
    EXPECT_EQ(line.find('\x1b'), std::string::npos) << "a raw escape sequence: " << line;
  }
}

TEST(HostileRequests, AssetChunksKeepToTheProtocol) {
  ServiceCluster cluster;
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string big(2'400'000, 'x');  // proto: at most 1 MiB per chunk
  pdsm::v1::AssetChunk chunk;
  chunk.set_sha256(Sha256Hex(big));
  chunk.set_total_bytes(big.size());
  chunk.set_data(big);
  grpc::Status s = Upload(cluster, {chunk});
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(s.error_message().find("at most 1048576"), std::string::npos) << s.error_message();

  pdsm::v1::AssetChunk first, second;
  first.set_sha256(std::string(64, 'a'));
  first.set_total_bytes(200);
  first.set_data(std::string(100, 'y'));
  second.set_sha256(std::string(64, 'b'));  // another blob mid-stream
  second.set_data(std::string(100, 'y'));
  s = Upload(cluster, {first, second});
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(s.error_message().find("another blob"), std::string::npos) << s.error_message();
}

TEST(HostileRequests, TileIndicesOutsideTheJobAreInvalidAndHealthIsPerService) {
  ServiceCluster cluster;
  ASSERT_TRUE(cluster.StartCoordinator());
  cluster.AddWorker();
  const std::string job_id = cluster.Submit(WriteServiceScene(cluster.dir(), 32, 4, 16));
  ASSERT_FALSE(job_id.empty());
  ASSERT_EQ(cluster.WaitForEnd(job_id).state(), pdsm::v1::SUCCEEDED);
  for (const int index : {-1, INT_MIN, 4, INT_MAX}) {  // 2 x 2 tiles
    EXPECT_EQ(FetchTileBytes(cluster, job_id, index).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT)
        << index;
  }
  EXPECT_EQ(FetchTileBytes(cluster, job_id, 3).error_code(), grpc::StatusCode::FAILED_PRECONDITION)
      << "a finished job's tiles are not served";
  EXPECT_EQ(FetchTileBytes(cluster, "0123456789abcdef", 0).error_code(),
            grpc::StatusCode::NOT_FOUND);

  std::string reply;
  for (const std::string service : {"", "pdsm.v1.PdsmJobs", "pdsm.v1.PdsmWorkers"}) {
    const grpc::Status s = HealthCheck(cluster, service, &reply);
    ASSERT_TRUE(s.ok()) << service << ": " << s.error_message();
    EXPECT_EQ(reply, std::string("\x08\x01", 2)) << service << ": not SERVING";
  }
  EXPECT_EQ(HealthCheck(cluster, "pdsm.v1.NoSuchService", &reply).error_code(),
            grpc::StatusCode::NOT_FOUND);
}

// Issue #17 finding 3: a worker that leases a real task and answers it with well-formed but
// impossible events (a count no batch has, a negative depth, NaN seconds) is refused, its
// lease stays open, and once it expires an honest worker bakes the same bytes as `pdsm bake`.
TEST(HostileRequests, ForgedResultsAreRefusedAndTheBakeStaysExact) {
  ServiceCluster cluster(CoordinatorArgs({"--lease-seconds", LeaseSeconds(2)}));
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string scene = WriteServiceScene(cluster.dir(), 64, 16, 32);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  const std::string job_id = cluster.Submit(scene);
  const auto workers = cluster.WorkersStub();

  const std::optional<pdsm::v1::Task> leased = LeaseOneTask(cluster, "forger");
  ASSERT_TRUE(leased) << "no task leased";
  const pdsm::v1::Task task = *leased;
  const int batch = task.sample_end() - task.sample_begin();

  // One pixel with events, the others none: each tile of the task is 32x32.
  const auto forged = [&](float z, int32_t count, double seconds_spent) {
    pdsm::v1::ReportResultRequest request;
    request.set_worker_id("forger");
    request.set_lease_id(task.lease_id());
    request.set_seconds(seconds_spent);
    for (int i = 0; i < task.tile_indices_size(); ++i) {
      pdsm::v1::TileEventsData* tile = request.add_tiles();
      tile->add_offsets(0);
      for (int p = 0; p < 32 * 32; ++p) tile->add_offsets(i == 0 ? 1 : 0);
      if (i == 0) {
        tile->add_z(z);
        tile->add_count(count);
      }
    }
    grpc::ClientContext context;
    PrepareCall(&context, "", seconds(10));
    pdsm::v1::ReportResultResponse response;
    return workers->ReportResult(&context, request, &response);
  };
  const grpc::Status too_many = forged(9.0f, 2147483647, 1.0);
  EXPECT_EQ(too_many.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(
      too_many.error_message().find("shadowed samples of a batch of " + std::to_string(batch)),
      std::string::npos)
      << too_many.error_message();
  EXPECT_EQ(forged(9.0f, -5, 1.0).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(forged(-1.0f, 1, 1.0).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(forged(9.0f, 1, std::nan("")).error_code(), grpc::StatusCode::INVALID_ARGUMENT);

  cluster.AddWorker();
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error();
  const std::string out = cluster.dir().File("fetched.exr");
  ASSERT_EQ(cluster.Pdsm("fetch " + job_id + " -o " + out).exit_code, 0);
  EXPECT_TRUE(ReadBytes(out) == expected) << "a forged result reached the PDSM";
}

// Issue #17 finding 1: the legal worst submit of the default limits (8192^2 pixels at tile
// size 1, one sample: 67 million tiles) is refused before anything is planned, naming the
// field and the way out; the coordinator then takes the same scene at a tile size within the
// limit (planned on its admission thread) and keeps answering.
TEST(HostileRequests, TilesPerJobAreBoundedBeforePlanning) {
  ServiceCluster cluster;
  ASSERT_TRUE(cluster.StartCoordinator());
  // 67 million tiles: past the scene format's own limit (2^20 a light), refused as it is read.
  const std::string worst = WriteServiceScene(cluster.dir(), 8192, 1, 1);
  const CommandResult invalid = cluster.Pdsm("submit " + worst);
  EXPECT_NE(invalid.exit_code, 0);
  EXPECT_NE(invalid.err.find("has 67108864 tiles, more than 1048576"), std::string::npos)
      << invalid.err;
  // 2^20 tiles: a valid scene, past this coordinator's limit, refused before planning.
  TempDir many_dir;
  const std::string many = WriteServiceScene(many_dir, 8192, 1, 8);
  const CommandResult refused = cluster.Pdsm("submit " + many);
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("bake.tileSize: 8 makes 1048576 tiles"), std::string::npos)
      << refused.err;
  EXPECT_NE(refused.err.find("limit of 262144"), std::string::npos) << refused.err;

  TempDir within_dir;
  const std::string within = WriteServiceScene(within_dir, 8192, 1, 16);
  const std::string job_id = cluster.Submit(within);
  ASSERT_FALSE(job_id.empty());
  pdsm::v1::Job job;
  ASSERT_TRUE(cluster.GetJob(job_id, &job).ok());
  EXPECT_EQ(job.tiles_total(), 262144);
  EXPECT_TRUE(cluster.Pdsm("cancel " + job_id).exit_code == 0);
}

}  // namespace
}  // namespace pdsm::testing
