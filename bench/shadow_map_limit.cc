// The limit of the bake's design (issue #11, docs/performance.md "The limit"): rendering one
// full shadow map per light sample — every caster, the whole lattice window — with the bake's
// own renderer and threads, and nothing else. A bake that renders each sample's map once for
// all the tiles it serves, and only what each map sees, approaches it; one that re-renders
// per tile pays a multiple of it.
//
// Runs the limit and the real bake (`pdsm bake`'s RunLocalBake, no preview) alternately
// `--repeat` times in this one process and prints each run's CPU seconds (user + system of
// every thread, llvmpipe's included) and wall seconds, then the medians and the bake's CPU
// ratio to the limit: on a shared machine only CPU time and same-run ratios mean something.
//
// Usage: pdsm-bench-limit SCENE.json [--resolution N] [--samples N] [--sm-resolution N]
//        [--threads N] [--repeat N] [--out DIR]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "bench/bench_support.h"
#include "core/bake/bake_plan.h"
#include "core/scene/scene_loader.h"
#include "core/util/malloc_arenas.h"
#include "core/util/work_queue.h"
#include "gl/platform/osmesa_context.h"
#include "worker/bake_task.h"
#include "worker/local_bake.h"
#include "worker/shadow_map_renderer.h"

namespace pdsm {
namespace {

using bench::CpuSeconds;
using bench::FullWindow;
using bench::Median;

struct Options {
  std::string scene_path;
  pdsm::v1::BakeParams overrides;
  int threads = 0, repeat = 3;
  std::string out_dir = std::filesystem::temp_directory_path().string();
};

struct Cost {
  double cpu_s = 0, wall_s = 0;
  int64_t maps = 0, triangles = 0;
};

template <typename Work>
absl::StatusOr<Cost> Measure(const Work& work) {
  const double cpu = CpuSeconds();
  const auto start = std::chrono::steady_clock::now();
  absl::StatusOr<Cost> cost = work();
  if (!cost.ok()) return cost;
  cost->cpu_s = CpuSeconds() - cpu;
  cost->wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return cost;
}

// One full map per sample, samples dealt round-robin to `threads` renderers.
absl::StatusOr<Cost> RenderFullMaps(const BakePlan& plan, int threads) {
  WorkQueue queue(threads);
  absl::Mutex mu;
  absl::Status failure;
  for (int t = 0; t < threads; ++t) {
    queue.Post([&, t] {
      absl::Status s = [&]() -> absl::Status {
        absl::StatusOr<std::unique_ptr<ShadowMapRenderer>> renderer = ShadowMapRenderer::Create();
        if (!renderer.ok()) return renderer.status();
        if (absl::Status g = (*renderer)->SetGeometry(plan.casters.positions, plan.casters.indices);
            !g.ok()) {
          return g;
        }
        ShadowMapCamera camera = BakeCamera(plan);
        camera.window = FullWindow(plan);
        std::vector<float> depth;
        for (size_t k = t; k < plan.samples.size(); k += threads) {
          camera.sample = plan.samples[k];
          if (absl::Status r = (*renderer)->Render(camera, &depth); !r.ok()) return r;
        }
        return absl::OkStatus();
      }();
      absl::MutexLock lock(&mu);
      if (failure.ok()) failure = s;
    });
  }
  queue.Wait();
  if (!failure.ok()) return failure;
  Cost cost;
  cost.maps = static_cast<int64_t>(plan.samples.size());
  cost.triangles = cost.maps * static_cast<int64_t>(plan.casters.TriangleCount());
  return cost;
}

absl::StatusOr<Cost> Bake(const Scene& scene, const Options& o) {
  LocalBakeOptions options;
  options.output_path = o.out_dir + "/pdsm-bench-limit.exr";
  options.threads = o.threads;
  absl::StatusOr<BakeSummary> summary = RunLocalBake(scene, options);
  if (!summary.ok()) return summary.status();
  Cost cost;
  cost.maps = summary->tasks_stats.shadow_maps;
  cost.triangles = summary->tasks_stats.triangles_submitted;
  return cost;
}

bool ParseFlags(int argc, char** argv, Options* o) {
  if (argc < 2) return false;
  o->scene_path = argv[1];
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (bench::ApplySceneFlag(flag, argv[i + 1], &o->overrides)) continue;
    int v = 0;
    if (!absl::SimpleAtoi(argv[i + 1], &v) && flag != "--out") return false;
    if (flag == "--threads") {
      o->threads = v;
    } else if (flag == "--repeat") {
      o->repeat = std::max(1, v);
    } else if (flag == "--out") {
      o->out_dir = argv[i + 1];
    } else {
      return false;
    }
  }
  return true;
}

int Run(int argc, char** argv) {
  Options o;
  if (!ParseFlags(argc, argv, &o)) {
    std::fprintf(stderr,
                 "usage: pdsm-bench-limit SCENE.json [--resolution N] [--samples N] "
                 "[--sm-resolution N] [--threads N] [--repeat N] [--out DIR]\n");
    return 2;
  }
  absl::StatusOr<Scene> scene = LoadSceneFile(o.scene_path, o.overrides);
  if (!scene.ok()) return std::fprintf(stderr, "%s\n", scene.status().ToString().c_str()), 2;
  absl::StatusOr<BakePlan> plan = PlanBake(*scene);
  if (!plan.ok()) return std::fprintf(stderr, "%s\n", plan.status().ToString().c_str()), 1;
  const int threads = o.threads > 0 ? o.threads : CoreCount();
  // As the bake sets them, before the limit makes the process's first context and arenas:
  // both runs then see the same llvmpipe threads and malloc arenas as `pdsm bake`.
  gl::ShareCoresBetweenContexts(threads);
  LimitMallocArenas(threads);
  const ShadowMapWindow full = FullWindow(*plan);
  std::printf("%s: PDSM %dx%d, %d samples, shadow maps %dx%d, %zu casters, %d threads\n",
              scene->name.c_str(), scene->bake.width, scene->bake.height, scene->bake.samples,
              full.width, full.height, plan->casters.TriangleCount(), threads);
  std::vector<double> limit_cpu, bake_cpu, limit_wall, bake_wall;
  Cost limit, bake;
  for (int r = 0; r < o.repeat; ++r) {
    absl::StatusOr<Cost> l = Measure([&] { return RenderFullMaps(*plan, threads); });
    if (!l.ok()) return std::fprintf(stderr, "%s\n", l.status().ToString().c_str()), 1;
    absl::StatusOr<Cost> b = Measure([&] { return Bake(*scene, o); });
    if (!b.ok()) return std::fprintf(stderr, "%s\n", b.status().ToString().c_str()), 1;
    std::printf("run %d: limit %.2f CPU-s (%.2f s wall), bake %.2f CPU-s (%.2f s wall)\n", r + 1,
                l->cpu_s, l->wall_s, b->cpu_s, b->wall_s);
    std::fflush(stdout);
    limit_cpu.push_back(l->cpu_s), limit_wall.push_back(l->wall_s);
    bake_cpu.push_back(b->cpu_s), bake_wall.push_back(b->wall_s);
    limit = *l, bake = *b;
  }
  const double lc = Median(limit_cpu), bc = Median(bake_cpu);
  std::printf(
      "median: limit %.2f CPU-s (%.2f s wall, %lld maps, %lld triangles), bake %.2f CPU-s "
      "(%.2f s wall, %lld maps, %lld triangles submitted): bake / limit = %.2f\n",
      lc, Median(limit_wall), static_cast<long long>(limit.maps),
      static_cast<long long>(limit.triangles), bc, Median(bake_wall),
      static_cast<long long>(bake.maps), static_cast<long long>(bake.triangles), bc / lc);
  return 0;
}

}  // namespace
}  // namespace pdsm

int main(int argc, char** argv) { return pdsm::Run(argc, argv); }
