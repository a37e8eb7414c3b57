// What the C++ benchmarks share (bench/shadow_map_limit.cc, bench/layered_maps.cc): CPU time
// of the whole process, medians, the full shadow-map window of a plan and the scene flags.
// Benchmarks only; not part of the product.
#ifndef PDSM_BENCH_BENCH_SUPPORT_H_
#define PDSM_BENCH_BENCH_SUPPORT_H_

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "absl/strings/numbers.h"
#include "core/bake/bake_plan.h"
#include "pdsm/v1/scene.pb.h"

namespace pdsm::bench {

// User + system CPU seconds of every thread of the process so far (llvmpipe's included).
inline double CpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& t) { return t.tv_sec + t.tv_usec * 1e-6; };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

// The upper median (0 for none).
inline double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

// The whole lattice: every texel of the PDSM window at the plan's shadow-map pitch.
inline ShadowMapWindow FullWindow(const BakePlan& plan) {
  const PdsmGeometry& g = plan.geometry();
  const ShadowMapLattice& l = plan.lattice;
  return ShadowMapWindow{0, 0, static_cast<int>(std::ceil((g.s_max - g.s_min) / l.pitch_s)),
                         static_cast<int>(std::ceil((g.t_max - g.t_min) / l.pitch_t))};
}

// Applies `--resolution N` (square PDSM), `--samples N` or `--sm-resolution N` to `overrides`.
// False for another flag or a value that is not an integer.
inline bool ApplySceneFlag(const std::string& flag, const std::string& value,
                           pdsm::v1::BakeParams* overrides) {
  int v = 0;
  if (!absl::SimpleAtoi(value, &v)) return false;
  if (flag == "--resolution") {
    overrides->add_resolution(v);
    overrides->add_resolution(v);
  } else if (flag == "--samples") {
    overrides->set_samples(v);
  } else if (flag == "--sm-resolution") {
    overrides->set_shadow_map_resolution(v);
  } else {
    return false;
  }
  return true;
}

}  // namespace pdsm::bench

#endif  // PDSM_BENCH_BENCH_SUPPORT_H_
