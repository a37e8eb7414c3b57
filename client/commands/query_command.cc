// `pdsm query PDSM.exr --points PTS.csv` or `pdsm query --job JOB --server ADDR --points
// PTS.csv`: attenuation at world points, one output line each: "x,y,z,attenuation" (nan
// outside the PDSM frustum); a file of several lights gives one column per light in file
// (scene) order, "x,y,z,A_1,...,A_n", or the one light `--light NAME` names. The remote form
// evaluates on the coordinator with the same code, and prints the same columns.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "absl/strings/str_cat.h"
#include "client/cli_common.h"
#include "client/commands.h"
#include "client/points_csv.h"
#include "client/service/service_connection.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"
#include "core/pdsm/pdsm_tile_cache.h"

namespace pdsm {
namespace {

// Points per QueryAttenuation call: well under the message limit (24 bytes a point).
constexpr size_t kPointsPerCall = 100'000;

struct QueryFlags {
  std::string pdsm_path;
  std::string points_path;
  std::string job_id;
  std::string light;
  int64_t cache_mib = kDefaultTileCacheBytes >> 20;
  ServiceFlags service;
};

// Values per chunk of points (each chunk's points are ordered by tile): 32 MiB of answers.
constexpr size_t kValuesPerChunk = size_t{1} << 22;

// Reads only the tiles the points fall in, through a cache of --cache-mib: a map of any size
// answers in bounded memory. Points are answered in the order of their tiles (a chunk at a
// time) and printed in the order given.
absl::Status QueryLocal(const QueryFlags& flags, const std::vector<QueryPoint>& points) {
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(flags.pdsm_path);
  if (!reader.ok()) return reader.status();
  absl::StatusOr<std::vector<PdsmLightParts>> selected =
      SelectLights(reader->headers(), reader->path(), flags.light);
  if (!selected.ok()) return selected.status();
  const std::vector<PdsmLightParts> lights = *std::move(selected);
  PdsmTileCache cache(*std::move(reader), flags.cache_mib << 20);
  const size_t chunk = std::max<size_t>(4096, kValuesPerChunk / lights.size());
  std::vector<glm::dvec3> world;
  for (size_t begin = 0; begin < points.size(); begin += chunk) {
    const size_t end = std::min(points.size(), begin + chunk);
    world.clear();
    for (size_t i = begin; i < end; ++i) world.push_back(points[i].world);
    absl::StatusOr<std::vector<double>> values = AttenuationAt(cache, lights, world);
    if (!values.ok()) return values.status();
    for (size_t i = begin; i < end; ++i) {
      PrintAttenuationLine(
          points[i],
          std::span<const double>(values->data() + (i - begin) * lights.size(), lights.size()));
    }
  }
  return absl::OkStatus();
}

absl::Status QueryRemote(const QueryFlags& flags, const std::vector<QueryPoint>& points) {
  absl::StatusOr<ServiceConnection> c = Connect(flags.service);
  if (!c.ok()) return c.status();
  // The job's lights size the batches: each answer stays under a client's 4 MiB (8 bytes a
  // value, one value per light).
  size_t lights = 1;
  if (flags.light.empty()) {
    pdsm::v1::GetJobRequest request;
    request.set_job_id(flags.job_id);
    pdsm::v1::Job job;
    if (grpc::Status s = c->stub->GetJob(c->Call().get(), request, &job); !s.ok()) {
      return CallError("job " + flags.job_id, s, flags.service.server);
    }
    lights = std::max<size_t>(1, job.lights_size());
  }
  const size_t per_call = std::max<size_t>(1, kPointsPerCall / lights);
  std::vector<double> attenuation;
  for (size_t begin = 0; begin < points.size(); begin += per_call) {
    const size_t end = std::min(points.size(), begin + per_call);
    pdsm::v1::QueryAttenuationRequest request;
    request.set_job_id(flags.job_id);
    request.set_light(flags.light);
    for (size_t i = begin; i < end; ++i) {
      pdsm::v1::QueryPoint* p = request.add_points();
      p->set_x(points[i].world.x);
      p->set_y(points[i].world.y);
      p->set_z(points[i].world.z);
    }
    pdsm::v1::QueryAttenuationResponse response;
    if (grpc::Status s =
            c->stub->QueryAttenuation(c->Call(std::chrono::minutes(5)).get(), request, &response);
        !s.ok()) {
      return CallError("querying job " + flags.job_id, s, flags.service.server);
    }
    // An older coordinator names no lights: one value per point.
    const size_t columns = std::max(1, response.lights_size());
    if (static_cast<size_t>(response.attenuation_size()) != (end - begin) * columns) {
      return absl::DataLossError("the coordinator answered a different number of values");
    }
    attenuation.resize(columns);
    for (size_t i = begin; i < end; ++i) {
      for (size_t l = 0; l < columns; ++l) {
        attenuation[l] = response.attenuation(static_cast<int>((i - begin) * columns + l));
      }
      PrintAttenuationLine(points[i], attenuation);
    }
  }
  return absl::OkStatus();
}

int RunQuery(const QueryFlags& flags) {
  if (flags.pdsm_path.empty() == flags.job_id.empty()) {
    return ReportError(
        absl::InvalidArgumentError("query: give either a PDSM file or --job JOB (with --server)"));
  }
  if (!flags.job_id.empty() && flags.service.server.empty()) {
    return ReportError(absl::InvalidArgumentError("--job needs --server ADDR"));
  }
  absl::StatusOr<std::vector<QueryPoint>> points = ReadPointsCsv(flags.points_path);
  if (!points.ok()) return ReportError(points.status());
  const absl::Status s =
      flags.job_id.empty() ? QueryLocal(flags, *points) : QueryRemote(flags, *points);
  return s.ok() ? kExitOk : ReportError(s);
}

}  // namespace

void RegisterQueryCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<QueryFlags>();
  CLI::App* cmd = app.add_subcommand(
      "query", "Attenuation at world points, from a PDSM file or a coordinator's job");
  cmd->add_option("pdsm", flags->pdsm_path, "PDSM file (.exr)");
  cmd->add_option("--points", flags->points_path,
                  "Points file: one x,y,z per line (a header row x,y,z allowed; - reads stdin)")
      ->required();
  cmd->add_option("--job", flags->job_id, "A finished job on the coordinator, instead of a file");
  cmd->add_option("--light", flags->light,
                  "The one light to answer for (a file of several lights: default one column "
                  "per light, in scene order)");
  cmd->add_option("--cache-mib", flags->cache_mib,
                  "Tiles of the file kept in memory, MiB (default 256): only the tiles the "
                  "points fall in are read, so any map size fits")
      ->check(CLI::Range(1, 1 << 20));
  AddServiceFlags(cmd, &flags->service, /*required=*/false);
  cmd->callback([flags, exit_code] { *exit_code = RunQuery(*flags); });
}

}  // namespace pdsm
