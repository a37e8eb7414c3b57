// DIR/sweep.png: a sweep's mean error against bake time on log-log axes, the Pareto front
// joined, each point labelled with the knobs that vary in the sweep. Drawn by gnuplot from
// DIR/sweep.csv alone, so `pdsm sweep --replot` can redraw a finished sweep.
#ifndef PDSM_CLIENT_MEASURE_SWEEP_PLOT_H_
#define PDSM_CLIENT_MEASURE_SWEEP_PLOT_H_

#include <string>

#include "absl/status/status.h"
#include "core/util/file_system.h"

namespace pdsm {

// Writes `png_path` from the CSV WriteSweepCsv wrote: gnuplot reads its script from a pipe and
// prints the PNG, which goes through WriteFileAtomically (core/util/atomic_file.h), so nothing
// but the PNG is ever written and a failed plot leaves `png_path` as it was.
// NOT_FOUND when gnuplot is not installed; INVALID_ARGUMENT naming the file when the CSV is
// not a sweep's; INTERNAL when gnuplot fails; the FileSystem's errors when writing fails.
// `fs` null means FileSystem::Default().
absl::Status PlotSweep(const std::string& csv_path, const std::string& png_path,
                       const std::string& title, FileSystem* fs = nullptr);

}  // namespace pdsm

#endif  // PDSM_CLIENT_MEASURE_SWEEP_PLOT_H_
