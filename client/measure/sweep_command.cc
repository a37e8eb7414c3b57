// `pdsm sweep SCENE.json --out DIR [--samples 4,16,...] [--resolution ...] [--sm-resolution ...]
// [--epsilon ...] [--sampling ...] [--depth-bias ...]`: bakes every combination of the knob lists
// (each as a child `pdsm bake`, so its peak memory is its own), measures each PDSM against the
// reference on fixed accuracy points, and writes DIR/sweep.csv, DIR/sweep.png and DIR/error.png
// (where the most accurate configuration's error lives, error_map.h).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "client/bake_overrides.h"
#include "client/cli_common.h"
#include "client/commands.h"
#include "client/measure/accuracy_probe.h"
#include "client/measure/bake_knobs.h"
#include "client/measure/child_bake.h"
#include "client/measure/error_map.h"
#include "client/measure/sweep_plot.h"
#include "client/measure/sweep_report.h"
#include "client/measure/target_error.h"
#include "client/progress_reporter.h"
#include "core/pdsm/pdsm_file.h"
#include "core/scene/scene_loader.h"
#include "core/util/output_path.h"

namespace pdsm {
namespace {

// The error map's rays along the longer side (DrawBestErrorMap).
constexpr int kSweepErrorMapRays = 256;

struct SweepFlags {
  std::string scene_path;
  std::string out_dir;
  std::vector<int> samples, sm_resolution;
  std::vector<std::string> resolution, sampling;
  std::vector<double> epsilon, depth_bias;
  int surface_points = 2000, free_space_points = 2000;
  uint64_t points_seed = 1;
  std::string reference_method = "auto";
  int reference_samples = kDefaultReferenceSamples;
  int threads = 0;
  bool keep_bakes = false;
  bool replot = false;
  std::optional<double> target_error;
};

// Every combination of the lists; an empty list keeps the scene's value.
absl::StatusOr<std::vector<BakeKnobs>> MakeGrid(const SweepFlags& flags, const BakeKnobs& base) {
  std::vector<std::pair<int, int>> resolutions;
  for (const std::string& r : flags.resolution) {
    absl::StatusOr<std::pair<int, int>> wh = ParseResolution(r, "--resolution");
    if (!wh.ok()) return wh.status();
    resolutions.push_back(*wh);
  }
  for (const std::string& name : flags.sampling) {
    if (absl::StatusOr<pdsm::v1::Sampling> s = ParseSamplingName(name, "--sampling"); !s.ok()) {
      return s.status();
    }
  }
  std::vector<std::optional<double>> biases(flags.depth_bias.begin(), flags.depth_bias.end());
  std::vector<std::string> samplings = flags.sampling;
  std::vector<int> sms = flags.sm_resolution, counts = flags.samples;
  std::vector<double> epsilons = flags.epsilon;
  if (samplings.empty()) samplings.push_back(base.sampling);
  if (resolutions.empty()) resolutions.emplace_back(base.width, base.height);
  if (sms.empty()) sms.push_back(base.sm_resolution);
  if (epsilons.empty()) epsilons.push_back(base.epsilon);
  if (biases.empty()) biases.push_back(base.depth_bias);
  if (counts.empty()) counts.push_back(base.samples);
  std::vector<BakeKnobs> grid;
  for (const std::string& sampling : samplings) {
    for (const auto& [w, h] : resolutions) {
      for (int sm : sms) {
        for (double eps : epsilons) {
          for (const std::optional<double>& bias : biases) {
            for (int n : counts) grid.push_back(BakeKnobs{n, w, h, sm, eps, sampling, bias});
          }
        }
      }
    }
  }
  return grid;
}

// The most accurate row (lowest mean error over the probe's points; the faster of equals).
bool MoreAccurate(const SweepRow& a, const SweepRow& b) {
  if (a.errors.all.mean != b.errors.all.mean) return a.errors.all.mean < b.errors.all.mean;
  return a.bake.seconds < b.bake.seconds;
}

// Where a configuration's bake goes: DIR/bakes/LABEL.exr.
std::string BakePath(const SweepFlags& flags, const BakeKnobs& knobs) {
  return (std::filesystem::path(flags.out_dir) / "bakes" / (knobs.Label() + ".exr")).string();
}

// The bakes in DIR/bakes; the most accurate one's (`*best`, an index into `rows`) is kept until
// the sweep has drawn its error map, the others go unless --keep-bakes.
absl::Status RunGrid(const SweepFlags& flags, const std::vector<BakeKnobs>& grid,
                     const AccuracyProbe& probe, std::vector<SweepRow>* rows, size_t* best) {
  const std::filesystem::path bakes = std::filesystem::path(flags.out_dir) / "bakes";
  ProgressReporter progress("sweep", "bakes");
  const auto start = std::chrono::steady_clock::now();
  for (size_t i = 0; i < grid.size(); ++i) {
    progress.Update(
        static_cast<int64_t>(i), static_cast<int64_t>(grid.size()),
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    const std::string label = grid[i].Label();
    const std::string exr = BakePath(flags, grid[i]);
    std::vector<std::string> args = grid[i].BakeArgs();
    if (flags.threads > 0) args.insert(args.end(), {"--threads", std::to_string(flags.threads)});
    absl::StatusOr<ChildBakeResult> bake =
        RunChildBake(flags.scene_path, exr, args, (bakes / (label + ".log")).string());
    if (!bake.ok()) return bake.status();
    absl::StatusOr<BakeErrors> errors = probe.Measure(exr);
    if (!errors.ok()) return errors.status();
    rows->push_back(SweepRow{grid[i], *bake, *errors});
    if (rows->size() == 1 || MoreAccurate(rows->back(), (*rows)[*best])) {
      if (!flags.keep_bakes && rows->size() > 1) {
        std::filesystem::remove(BakePath(flags, (*rows)[*best].knobs));
      }
      *best = rows->size() - 1;
    } else if (!flags.keep_bakes) {
      std::filesystem::remove(exr);
    }
  }
  progress.Update(static_cast<int64_t>(grid.size()), static_cast<int64_t>(grid.size()),
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  progress.Finish();
  return absl::OkStatus();
}

void PrintRows(const std::vector<SweepRow>& rows) {
  for (const SweepRow& r : rows) {
    std::printf(
        "%-40s %8.2fs %7.1f MiB  mean %.5f  surface p95 %.4f  free p95 "
        "%.4f%s\n",
        r.knobs.Label().c_str(), r.bake.seconds, r.bake.peak_rss_bytes / 1048576.0,
        r.errors.all.mean, r.errors.surface.p95, r.errors.free_space.p95,
        r.pareto ? "  *pareto" : "");
  }
}

// --target-error E: the chooser of `pdsm bake --target-error` on the same scene, its result
// measured on the sweep's (larger) point set. Exit 1 when that bake misses E.
int CheckTargetError(const SweepFlags& flags, const AccuracyProbe& probe,
                     const std::vector<SweepRow>& rows) {
  TargetErrorOptions options;
  options.scene_path = flags.scene_path;
  options.output_path =
      (std::filesystem::path(flags.out_dir) / "bakes" / "target_error.exr").string();
  options.target = *flags.target_error;
  options.threads = flags.threads;
  absl::StatusOr<TargetErrorResult> chosen = BakeToTargetError(options);
  if (!chosen.ok()) return ReportError(chosen.status());
  absl::StatusOr<BakeErrors> errors = probe.Measure(options.output_path);
  if (!errors.ok()) return ReportError(errors.status());
  const bool met = errors->all.mean <= *flags.target_error;
  std::printf(
      "target-error %g: chose %s (%.2fs); mean error on the sweep's "
      "points %.5f: %s\n",
      *flags.target_error, chosen->knobs.Label().c_str(), chosen->seconds, errors->all.mean,
      met ? "met" : "NOT met");
  // Against the sweep: the cheapest configuration it found that meets E.
  const SweepRow* cheapest = nullptr;
  for (const SweepRow& row : rows) {
    if (row.errors.all.mean <= *flags.target_error &&
        (cheapest == nullptr || row.bake.seconds < cheapest->bake.seconds)) {
      cheapest = &row;
    }
  }
  if (cheapest != nullptr) {
    std::printf(
        "target-error %g: the sweep's cheapest configuration meeting it: %s (%.2fs, %.5f)\n",
        *flags.target_error, cheapest->knobs.Label().c_str(), cheapest->bake.seconds,
        cheapest->errors.all.mean);
  } else {
    std::printf("target-error %g: no configuration of the sweep meets it\n", *flags.target_error);
  }
  if (!flags.keep_bakes) std::filesystem::remove(options.output_path);
  return met ? kExitOk : kExitFailure;
}

// DIR/error.png: where the most accurate configuration's error lives (error_map.h), on at
// most 256 x 256 of its rays so that the reference costs what the probe's points cost, give or
// take. The map is a convenience beside the CSV: its failure is a warning.
void DrawBestErrorMap(const SweepFlags& flags, const Scene& scene, ReferenceMethod method,
                      const SweepRow& best) {
  const std::string best_exr = BakePath(flags, best.knobs);
  const std::string png = (std::filesystem::path(flags.out_dir) / "error.png").string();
  const auto draw = [&]() -> absl::Status {
    absl::StatusOr<PdsmImage> pdsm = ReadPdsm(best_exr);
    if (!pdsm.ok()) return pdsm.status();
    const int longest = std::max(pdsm->header.geometry.width, pdsm->header.geometry.height);
    const int step = (longest + kSweepErrorMapRays - 1) / kSweepErrorMapRays;
    absl::StatusOr<ErrorMap> map = MeasureErrorMap(
        *pdsm, scene,
        ReferenceOptions{method, flags.reference_samples, 1, {pdsm->header.weighting}}, step);
    if (!map.ok()) return map.status();
    const ErrorMapSummary summary = SummarizeErrorMap(*map);
    const std::string title = absl::StrCat(best.knobs.Label(), ": ", ErrorMapTitle(*map));
    if (absl::Status s = WriteErrorMapPng(*map, summary, kDefaultErrorMapScale, title, png);
        !s.ok()) {
      return s;
    }
    std::printf(
        "error map of the most accurate configuration (%s): %s\n  all       %s\n  "
        "penumbra  %s\n",
        best.knobs.Label().c_str(), png.c_str(), FormatErrorStats(summary.all).c_str(),
        FormatErrorStats(summary.penumbra).c_str());
    return absl::OkStatus();
  };
  if (absl::Status s = draw(); !s.ok()) {
    std::fprintf(stderr, "pdsm: warning: no error map: %s\n", std::string(s.message()).c_str());
  }
  if (!flags.keep_bakes) std::filesystem::remove(best_exr);
}

// A missing gnuplot is a warning: the CSV is the result, the plot a convenience.
void Plot(const std::filesystem::path& dir, const std::string& scene_name) {
  const absl::Status plot =
      PlotSweep((dir / "sweep.csv").string(), (dir / "sweep.png").string(), scene_name);
  if (plot.ok()) {
    std::printf("plot: %s\n", (dir / "sweep.png").c_str());
  } else {
    std::fprintf(stderr, "pdsm: warning: no plot: %s\n", std::string(plot.message()).c_str());
  }
}

int RunSweep(const SweepFlags& flags) {
  absl::StatusOr<ReferenceMethod> method =
      ParseReferenceMethod(flags.reference_method, "--reference-method");
  if (!method.ok()) return ReportError(method.status());
  // Before any work: what the sweep writes is a regular file or a new path, not its scene.
  const std::filesystem::path out(flags.out_dir);
  OutputPaths outputs = {{"--out", (out / "sweep.png").string()}};
  if (!flags.replot) {
    outputs.insert(outputs.end(), {{"--out", (out / "sweep.csv").string()},
                                   {"--out", (out / "reference.csv").string()},
                                   {"--out", (out / "error.png").string()}});
  }
  if (absl::Status s = CheckOutputPaths(outputs, {flags.scene_path}); !s.ok()) {
    return ReportError(s);
  }
  absl::StatusOr<Scene> scene = LoadSceneFile(flags.scene_path);
  if (scene.ok()) scene = OneLight(*std::move(scene), "", "pdsm sweep");
  if (!scene.ok()) return ReportError(scene.status());
  if (flags.replot) {
    const std::filesystem::path csv = std::filesystem::path(flags.out_dir) / "sweep.csv";
    if (!std::filesystem::exists(csv)) {
      return ReportError(
          absl::InvalidArgumentError(absl::StrFormat("--replot: %s does not exist", csv.string())));
    }
    Plot(flags.out_dir, scene->name);
    return kExitOk;
  }
  absl::StatusOr<std::string> sampling = SceneSamplingName(flags.scene_path);
  if (!sampling.ok()) return ReportError(sampling.status());
  absl::StatusOr<std::vector<BakeKnobs>> grid = MakeGrid(flags, KnobsFromScene(*scene, *sampling));
  if (!grid.ok()) return ReportError(grid.status());

  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(flags.out_dir) / "bakes", ec);
  if (ec) {
    return ReportError(absl::InvalidArgumentError(
        absl::StrFormat("--out %s: cannot create the folder: %s", flags.out_dir, ec.message())));
  }
  const std::filesystem::path dir(flags.out_dir);
  absl::StatusOr<AccuracyProbe> probe = AccuracyProbe::Create(
      *scene, AccuracyPointCounts{flags.surface_points, flags.free_space_points}, flags.points_seed,
      // The definition the scene bakes (bake.weighting).
      ReferenceOptions{*method, flags.reference_samples, 1, {scene->bake.weighting}});
  if (!probe.ok()) return ReportError(probe.status());
  std::fprintf(stderr,
               "sweep: %zu configurations; reference (%s) on %zu + %zu points "
               "in %.1fs\n",
               grid->size(), ReferenceMethodName(probe->method()), probe->points().surface.size(),
               probe->points().free_space.size(), probe->reference_seconds());

  if (absl::Status s = probe->WriteReferenceCsv((dir / "reference.csv").string()); !s.ok()) {
    return ReportError(s);
  }
  std::vector<SweepRow> rows;
  size_t best = 0;
  if (absl::Status s = RunGrid(flags, *grid, *probe, &rows, &best); !s.ok()) {
    return ReportError(s);
  }
  MarkParetoFront(&rows);
  if (absl::Status s = WriteSweepCsv((dir / "sweep.csv").string(), rows); !s.ok()) {
    return ReportError(s);
  }
  PrintRows(rows);
  std::printf("sweep: %s\n", (dir / "sweep.csv").c_str());
  Plot(dir, scene->name);
  if (!rows.empty()) DrawBestErrorMap(flags, *scene, probe->method(), rows[best]);
  if (flags.target_error) return CheckTargetError(flags, *probe, rows);
  return kExitOk;
}

}  // namespace

void RegisterSweepCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<SweepFlags>();
  CLI::App* cmd = app.add_subcommand("sweep",
                                     "Bake every combination of knob values; "
                                     "error against time, CSV and plot");
  cmd->add_option("scene", flags->scene_path, "Scene file (JSON)")->required();
  cmd->add_option("--out", flags->out_dir,
                  "Output folder (sweep.csv, sweep.png, error.png, bakes/)")
      ->required();
  cmd->add_option("--samples", flags->samples, "Light sample counts, e.g. 4,16,64")
      ->delimiter(',')
      ->check(CLI::Range(1, kMaxSamples));
  cmd->add_option("--resolution", flags->resolution, "PDSM resolutions, e.g. 128x128,256x256")
      ->delimiter(',');
  cmd->add_option("--sm-resolution", flags->sm_resolution, "Shadow-map resolutions")
      ->delimiter(',')
      ->check(CLI::Range(1, kMaxShadowMapResolution));
  cmd->add_option("--epsilon", flags->epsilon, "Compression tolerances")->delimiter(',');
  cmd->add_option("--sampling", flags->sampling, "Sampling patterns (bake.sampling names)")
      ->delimiter(',');
  cmd->add_option("--depth-bias", flags->depth_bias, "Constant depth biases (world units)")
      ->delimiter(',');
  cmd->add_option("--surface-points", flags->surface_points, "Accuracy points on receivers")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  cmd->add_option("--free-points", flags->free_space_points, "Accuracy points in free space")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  cmd->add_option("--points-seed", flags->points_seed, "Seed of the accuracy points")
      ->capture_default_str();
  cmd->add_option("--reference-method", flags->reference_method, "exact, embree or auto")
      ->capture_default_str();
  cmd->add_option("--reference-samples", flags->reference_samples, "Embree reference samples")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  cmd->add_option("--threads", flags->threads, "Threads of each bake (default: one per core)")
      ->check(CLI::Range(1, 1024));
  cmd->add_flag("--replot", flags->replot, "Only redraw DIR/sweep.png from DIR/sweep.csv");
  cmd->add_flag("--keep-bakes", flags->keep_bakes, "Keep each configuration's PDSM in DIR/bakes");
  cmd->add_option("--target-error", flags->target_error,
                  "Also run `pdsm bake --target-error E` and check it on the "
                  "sweep's points")
      ->check(CLI::PositiveNumber);
  cmd->callback([flags, exit_code] { *exit_code = RunSweep(*flags); });
}

}  // namespace pdsm
