// The sweep's outputs: DIR/sweep.csv (one row per configuration) and DIR/sweep.png (error against
// time, the Pareto front joined), drawn by gnuplot.
#ifndef PDSM_CLIENT_SWEEP_REPORT_H_
#define PDSM_CLIENT_SWEEP_REPORT_H_

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "client/accuracy_probe.h"
#include "client/bake_knobs.h"
#include "client/child_bake.h"

namespace pdsm {

struct SweepRow {
  BakeKnobs knobs;
  ChildBakeResult bake;
  BakeErrors errors;
  bool pareto = false;  // no other row is both faster and more accurate (errors.all.mean)
};

// The CSV's header line, without the newline: the column names tests and scripts rely on.
std::string SweepCsvHeader();

// Sets `pareto` on every row: minimal in (seconds, errors.all.mean).
void MarkParetoFront(std::vector<SweepRow>* rows);

// Writes the CSV under a temporary name and renames it: never half-written.
absl::Status WriteSweepCsv(const std::string& path, const std::vector<SweepRow>& rows);

// Runs gnuplot on `csv_path` (the file WriteSweepCsv wrote from `rows`) to make `png_path` (written
// under a temporary name first). NOT_FOUND when gnuplot is not installed, INTERNAL when it fails.
absl::Status PlotSweep(const std::vector<SweepRow>& rows, const std::string& csv_path,
                       const std::string& png_path, const std::string& title);

}  // namespace pdsm

#endif  // PDSM_CLIENT_SWEEP_REPORT_H_
