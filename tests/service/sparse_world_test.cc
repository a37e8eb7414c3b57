// Tiles no caster reaches on the service (core/pipeline/unreached_tile.h): a sparse world's
// empty tiles are done at once without a task, and the coordinator stores nothing of them (a
// 2^18-tile job used to write 2^18 files, one fsync'd commit each); it makes them again when
// it writes the PDSM, and when a client fetches one.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/pipeline/tile_file.h"
#include "tests/service/service_cluster.h"

namespace pdsm::testing {
namespace {

using std::chrono::seconds;

// Bytes of the job's tile log past its 16-byte header: its records (server/tile_log.h).
uint64_t TileRecordBytes(ServiceCluster& cluster, const std::string& job_id) {
  const std::filesystem::path log =
      std::filesystem::path(cluster.dir().File("data")) / "jobs" / job_id / "tiles.log";
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(log, ec);
  return ec || size < 16 ? 0 : size - 16;
}

TEST(SparseWorld, TilesNoCasterReachesAreNeverStoredYetServedAndBakedExactly) {
  ServiceCluster cluster;
  ASSERT_TRUE(cluster.StartCoordinator());
  // A 40 x 40 ground under one 1 x 1 square: at 256^2 in 16-pixel tiles, few of the 256 tiles
  // are reached.
  const std::string scene = cluster.dir().File("sparse.json");
  WriteText(scene, R"({
  "name": "sparse",
  "meshes": [
    {"inline": {"positions": [-20,0,-20, 20,0,-20, 20,0,20, -20,0,20], "indices": [0,1,2, 0,2,3]},
     "role": "RECEIVER_ONLY"},
    {"inline": {"positions": [-0.5,2,-0.5, 0.5,2,-0.5, 0.5,2,0.5, -0.5,2,0.5],
                "indices": [0,1,2, 0,2,3]}}
  ],
  "light": {"rect": {"center": [0,10,0], "normal": [0,-1,0], "up": [0,0,1], "size": [1,1]}},
  "bake": {"resolution": [256,256], "samples": 16, "tileSize": 16}
})");
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  const std::string job_id = cluster.Submit(scene);

  // No worker yet: only tiles no caster reaches can be finished, and they are at once.
  pdsm::v1::FinishedTiles finished;
  for (int attempt = 0; attempt < 100 && finished.tile_indices_size() == 0; ++attempt) {
    grpc::ClientContext context;
    PrepareCall(&context, "", seconds(10));
    pdsm::v1::ListFinishedTilesRequest request;
    request.set_job_id(job_id);
    ASSERT_TRUE(cluster.JobsStub()->ListFinishedTiles(&context, request, &finished).ok());
  }
  ASSERT_GT(finished.tile_indices_size(), 200) << "the scene should leave most tiles unreached";
  ASSERT_LT(finished.tile_indices_size(), 256);
  const pdsm::v1::Job waiting = cluster.WaitUntil(job_id, seconds(60), [&](const pdsm::v1::Job& j) {
    return j.tiles_done() == finished.tile_indices_size();
  });
  EXPECT_EQ(waiting.tiles_done(), finished.tile_indices_size());
  EXPECT_EQ(TileRecordBytes(cluster, job_id), 0u) << "a tile no caster reaches was stored";

  // A client fetching one gets it all lit, made on request.
  const int unreached = finished.tile_indices(finished.tile_indices_size() / 2);
  {
    std::string bytes;
    ASSERT_TRUE(FetchTileBytes(cluster, job_id, unreached, &bytes).ok());
    absl::StatusOr<PdsmTile> tile = DecodeTileFile(bytes, "the fetched tile");
    ASSERT_TRUE(tile.ok()) << tile.status();
    EXPECT_TRUE(tile->vertices.empty());
    EXPECT_EQ(tile->width * tile->height + 1, static_cast<int>(tile->offsets.size()));
  }
  EXPECT_EQ(TileRecordBytes(cluster, job_id), 0u) << "a tile made on request was stored";

  cluster.AddWorker();
  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error();
  EXPECT_EQ(job.tiles_done(), 256);
  EXPECT_EQ(job.tile_assemblies(), job.tiles_total());  // each tile counted once
  EXPECT_TRUE(FetchBytes(cluster, job_id) == expected) << "the file differs from pdsm bake's";
}

}  // namespace
}  // namespace pdsm::testing
