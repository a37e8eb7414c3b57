// `pdsm query PDSM.exr --points PTS.csv`: attenuation at world points, one output line each:
// "x,y,z,attenuation" (nan outside the PDSM frustum).
#include <cmath>
#include <cstdio>
#include <string>

#include "client/cli_common.h"
#include "client/commands.h"
#include "client/points_csv.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"

namespace pdsm {
namespace {

struct QueryFlags {
  std::string pdsm_path;
  std::string points_path;
};

int RunQuery(const QueryFlags& flags) {
  absl::StatusOr<std::vector<QueryPoint>> points = ReadPointsCsv(flags.points_path);
  if (!points.ok()) return ReportError(points.status());
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(flags.pdsm_path);
  if (!pdsm.ok()) return ReportError(pdsm.status());
  for (const QueryPoint& point : *points) {
    const double a = QueryAttenuation(*pdsm, point.world);
    if (std::isnan(a)) {
      std::printf("%s,nan\n", point.text.c_str());
    } else {
      std::printf("%s,%.6f\n", point.text.c_str(), a);
    }
  }
  return kExitOk;
}

}  // namespace

void RegisterQueryCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<QueryFlags>();
  CLI::App* cmd = app.add_subcommand("query", "Attenuation at world points from a PDSM file");
  cmd->add_option("pdsm", flags->pdsm_path, "PDSM file (.exr)")->required();
  cmd->add_option("--points", flags->points_path, "Points file: one x,y,z per line")->required();
  cmd->callback([flags, exit_code] { *exit_code = RunQuery(*flags); });
}

}  // namespace pdsm
