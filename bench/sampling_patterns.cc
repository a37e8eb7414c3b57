// Sampling patterns and adaptive sampling on the speed/accuracy curve (docs/accuracy.md,
// "Sampling patterns"). Bakes a scene (examples/plates by default) with every pattern at
// several sample counts and several seeds, then adaptive bakes at several tolerances, and
// prints a Markdown table: seconds and the error of `pdsm query` against the exact reference
// (core/reference) on the ground receiver (40x40 grid) and in free space (1500 random points),
// the point sets of tests/bake_accuracy_test.cc.
//
// Usage: pdsm-bench-sampling SCENE.json OUT_DIR [--seeds N] [--counts 4,16,64,256]
//        [--resolution 256] [--sm 1024] [--tile-size 16] [--tolerances 0.05,0.02,0.01]
// Every bake: epsilon 0.005, default bias, seeds 1..N (the table shows means over seeds).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_split.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"
#include "core/reference/exact_visibility.h"
#include "core/scene/scene_loader.h"
#include "worker/local_bake.h"

namespace pdsm {
namespace {

struct Options {
  std::string scene_path, out_dir;
  int seeds = 3, resolution = 256, sm = 1024, tile_size = 16;
  std::vector<int> counts = {4, 16, 64, 256};
  std::vector<double> tolerances = {0.05, 0.02, 0.01};
};

struct PointSet {
  std::vector<glm::dvec3> points;
  std::vector<double> exact;
};

struct Errors {
  double mean = 0, p95 = 0;
};

Errors Measure(const PdsmImage& pdsm, const PointSet& set) {
  std::vector<double> e;
  for (size_t k = 0; k < set.points.size(); ++k) {
    const double baked = QueryAttenuation(pdsm, set.points[k]);
    if (std::isnan(baked) || std::isnan(set.exact[k])) continue;
    e.push_back(std::abs(baked - set.exact[k]));
  }
  Errors out;
  if (e.empty()) return out;
  std::sort(e.begin(), e.end());
  for (double x : e) out.mean += x / e.size();
  out.p95 = e[e.size() * 95 / 100];
  return out;
}

struct Row {
  double seconds = 0, samples_per_tile = 0, shadow_maps = 0;
  Errors ground, volume;
};

absl::StatusOr<Row> BakeOnce(const Options& o, pdsm::v1::BakeParams params, const PointSet& ground,
                             const PointSet& volume) {
  params.add_resolution(o.resolution);
  params.add_resolution(o.resolution);
  params.set_shadow_map_resolution(o.sm);
  params.set_tile_size(o.tile_size);
  params.set_epsilon(0.005);
  absl::StatusOr<Scene> scene = LoadSceneFile(o.scene_path, params);
  if (!scene.ok()) return scene.status();
  LocalBakeOptions bake;
  bake.output_path = o.out_dir + "/bench.exr";
  absl::StatusOr<BakeSummary> summary = RunLocalBake(*scene, bake);
  if (!summary.ok()) return summary.status();
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(bake.output_path);
  if (!pdsm.ok()) return pdsm.status();
  Row row;
  row.seconds = summary->seconds;
  row.shadow_maps = static_cast<double>(summary->tasks_stats.shadow_maps);
  row.samples_per_tile = static_cast<double>(summary->tile_samples_total) / summary->tiles;
  row.ground = Measure(*pdsm, ground);
  row.volume = Measure(*pdsm, volume);
  return row;
}

// Mean over seeds.
absl::StatusOr<Row> BakeSeeds(const Options& o, const pdsm::v1::BakeParams& params,
                              const PointSet& ground, const PointSet& volume) {
  Row mean;
  for (int seed = 1; seed <= o.seeds; ++seed) {
    pdsm::v1::BakeParams p = params;
    p.set_seed(seed);
    absl::StatusOr<Row> row = BakeOnce(o, p, ground, volume);
    if (!row.ok()) return row.status();
    const double w = 1.0 / o.seeds;
    mean.seconds += w * row->seconds;
    mean.shadow_maps += w * row->shadow_maps;
    mean.samples_per_tile += w * row->samples_per_tile;
    mean.ground.mean += w * row->ground.mean;
    mean.ground.p95 += w * row->ground.p95;
    mean.volume.mean += w * row->volume.mean;
    mean.volume.p95 += w * row->volume.p95;
  }
  return mean;
}

void PrintRow(const char* pattern, const std::string& knob, const Row& r) {
  std::printf("| %s | %s | %.0f | %.0f | %.2f | %.4f | %.4f | %.4f | %.4f |\n", pattern,
              knob.c_str(), r.samples_per_tile, r.shadow_maps, r.seconds, r.ground.mean,
              r.ground.p95, r.volume.mean, r.volume.p95);
  std::fflush(stdout);
}

absl::StatusOr<PointSet> MakePoints(const Scene& scene, std::vector<glm::dvec3> points) {
  PointSet set;
  absl::StatusOr<std::vector<double>> exact = ExactAttenuation(scene, points);
  if (!exact.ok()) return exact.status();
  set.points = std::move(points);
  set.exact = *std::move(exact);
  return set;
}

int Run(const Options& o) {
  absl::StatusOr<Scene> scene = LoadSceneFile(o.scene_path, {});
  if (!scene.ok()) return std::fprintf(stderr, "%s\n", scene.status().ToString().c_str()), 2;
  // The point sets of tests/bake_accuracy_test.cc (plates: ground y = 0, casters 1..4).
  std::vector<glm::dvec3> grid, box;
  for (int i = 0; i < 40; ++i) {
    for (int j = 0; j < 40; ++j)
      grid.emplace_back(-6 + 12 * (i + 0.5) / 40, 0.0, -6 + 12 * (j + 0.5) / 40);
  }
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 1500; ++k)
    box.emplace_back(-5 + 10 * u(rng), 0.05 + 3.85 * u(rng), -5 + 10 * u(rng));
  absl::StatusOr<PointSet> ground = MakePoints(*scene, grid), volume = MakePoints(*scene, box);
  if (!ground.ok() || !volume.ok()) {
    std::fprintf(stderr, "reference failed\n");
    return 1;
  }
  std::printf(
      "| pattern | samples (max) / tolerance | samples per tile | shadow maps | seconds | "
      "ground mean | ground p95 | free-space mean | free-space p95 |\n"
      "|---|---|---|---|---|---|---|---|---|\n");
  const std::pair<const char*, pdsm::v1::Sampling> patterns[] = {
      {"stratified", pdsm::v1::STRATIFIED},
      {"uniform", pdsm::v1::UNIFORM},
      {"sobol", pdsm::v1::SOBOL},
      {"halton", pdsm::v1::HALTON},
      {"blue-noise", pdsm::v1::BLUE_NOISE}};
  for (int count : o.counts) {
    for (const auto& [name, sampling] : patterns) {
      pdsm::v1::BakeParams p;
      p.set_samples(count);
      p.set_sampling(sampling);
      absl::StatusOr<Row> row = BakeSeeds(o, p, *ground, *volume);
      if (!row.ok()) return std::fprintf(stderr, "%s\n", row.status().ToString().c_str()), 1;
      PrintRow(name, std::to_string(count), *row);
    }
  }
  for (double tolerance : o.tolerances) {
    pdsm::v1::BakeParams p;
    p.set_samples(o.counts.back());
    p.set_sampling(pdsm::v1::SOBOL);
    p.set_adaptive_tolerance(tolerance);
    p.set_adaptive_min_samples(16);
    absl::StatusOr<Row> row = BakeSeeds(o, p, *ground, *volume);
    if (!row.ok()) return std::fprintf(stderr, "%s\n", row.status().ToString().c_str()), 1;
    PrintRow("sobol adaptive",
             std::to_string(o.counts.back()) + " / " + std::to_string(tolerance).substr(0, 5),
             *row);
  }
  return 0;
}

bool ParseList(const std::string& text, std::vector<int>* out) {
  out->clear();
  for (absl::string_view f : absl::StrSplit(text, ',')) {
    int v;
    if (!absl::SimpleAtoi(f, &v)) return false;
    out->push_back(v);
  }
  return !out->empty();
}

}  // namespace
}  // namespace pdsm

int main(int argc, char** argv) {
  pdsm::Options o;
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--seeds" && has_value) {
      o.seeds = std::atoi(argv[++i]);
    } else if (a == "--resolution" && has_value) {
      o.resolution = std::atoi(argv[++i]);
    } else if (a == "--tile-size" && has_value) {
      o.tile_size = std::atoi(argv[++i]);
    } else if (a == "--sm" && has_value) {
      o.sm = std::atoi(argv[++i]);
    } else if (a == "--counts" && has_value) {
      if (!pdsm::ParseList(argv[++i], &o.counts)) return 2;
    } else if (a == "--tolerances" && has_value) {
      o.tolerances.clear();
      for (absl::string_view f : absl::StrSplit(argv[++i], ',')) {
        double v;
        if (!absl::SimpleAtod(f, &v)) return 2;
        o.tolerances.push_back(v);
      }
    } else {
      positional.push_back(a);
    }
  }
  if (positional.size() != 2 || o.seeds < 1) {
    std::fprintf(stderr,
                 "usage: pdsm-bench-sampling SCENE.json OUT_DIR [--seeds N] "
                 "[--counts 4,16,64,256] [--resolution R] [--sm R] [--tile-size T] "
                 "[--tolerances ...]\n");
    return 2;
  }
  o.scene_path = positional[0];
  o.out_dir = positional[1];
  return pdsm::Run(o);
}
