#include "client/measure/sweep_report.h"

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "core/util/atomic_file.h"

namespace pdsm {
namespace {

std::string ErrorCells(const ErrorStats& e) {
  return absl::StrFormat("%d,%.6f,%.6f,%.6f", e.count, e.mean, e.p95, e.max);
}

std::string RowCells(const SweepRow& row) {
  const BakeKnobs& k = row.knobs;
  return absl::StrCat(
      absl::StrFormat("%s,%d,%dx%d,%d,%g,%s,%s,", k.Label(), k.samples, k.width, k.height,
                      k.sm_resolution, k.epsilon, k.sampling,
                      k.depth_bias ? absl::StrFormat("%g", *k.depth_bias) : "auto"),
      absl::StrFormat("%.3f,%.1f,%d,%.6f,", row.bake.seconds, row.bake.peak_rss_bytes / 1048576.0,
                      row.bake.file_bytes, row.errors.all.mean),
      ErrorCells(row.errors.surface), ",", ErrorCells(row.errors.free_space), ",",
      row.pareto ? 1 : 0);
}

}  // namespace

std::string SweepCsvHeader() {
  return "config,samples,resolution,sm_resolution,epsilon,sampling,depth_bias,seconds,"
         "peak_rss_mib,file_bytes,mean_abs,surface_n,surface_mean,surface_p95,surface_max,"
         "free_n,free_mean,free_p95,free_max,pareto";
}

void MarkParetoFront(std::vector<SweepRow>* rows) {
  for (SweepRow& a : *rows) {
    a.pareto = true;
    for (const SweepRow& b : *rows) {
      const bool no_worse =
          b.bake.seconds <= a.bake.seconds && b.errors.all.mean <= a.errors.all.mean;
      const bool better = b.bake.seconds < a.bake.seconds || b.errors.all.mean < a.errors.all.mean;
      if (&a != &b && no_worse && better) {
        a.pareto = false;
        break;
      }
    }
  }
}

absl::Status WriteSweepCsv(const std::string& path, const std::vector<SweepRow>& rows,
                           FileSystem* fs) {
  std::string csv = SweepCsvHeader() + "\n";
  for (const SweepRow& row : rows) absl::StrAppend(&csv, RowCells(row), "\n");
  return WriteFileAtomically(path, csv, fs);
}

}  // namespace pdsm
