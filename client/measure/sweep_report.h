// The sweep's table: DIR/sweep.csv, one row per configuration, its Pareto front marked.
#ifndef PDSM_CLIENT_MEASURE_SWEEP_REPORT_H_
#define PDSM_CLIENT_MEASURE_SWEEP_REPORT_H_

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "client/measure/accuracy_probe.h"
#include "client/measure/bake_knobs.h"
#include "client/measure/child_bake.h"
#include "core/util/file_system.h"

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

// Writes the CSV through WriteFileAtomically (core/util/atomic_file.h): never half-written; on
// failure `path` is left as it was. `fs` null means FileSystem::Default().
absl::Status WriteSweepCsv(const std::string& path, const std::vector<SweepRow>& rows,
                           FileSystem* fs = nullptr);

}  // namespace pdsm

#endif  // PDSM_CLIENT_MEASURE_SWEEP_REPORT_H_
