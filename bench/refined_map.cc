// What a refined PDSM holds (issue #15 item 2; docs/performance.md "Adaptive resolution"):
// its refined pixels, and where their vertices go: the pixels' own functions, their
// sub-functions, and the sub-functions' windows (each costs a NaN bracket); with --depth Z, the
// sub-function vertices within --near of depth Z (a ground plane square to the light's axis,
// say) apart from the others.
//
// Usage: pdsm-bench-refinement PDSM.exr [--depth Z] [--near D]

#include <cmath>
#include <cstdio>
#include <string>

#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/refined_pixel.h"

namespace pdsm {
namespace {

int Main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: pdsm-bench-refinement PDSM.exr [--depth Z] [--near D]\n");
    return 2;
  }
  double depth = std::nan(""), near = 0.05;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--depth") {
      depth = std::stod(argv[i + 1]);
    } else if (flag == "--near") {
      near = std::stod(argv[i + 1]);
    } else {
      std::fprintf(stderr, "unknown flag %s\n", flag.c_str());
      return 2;
    }
  }
  absl::StatusOr<PdsmImage> image = ReadPdsm(argv[1]);
  if (!image.ok()) {
    std::fprintf(stderr, "%s\n", std::string(image.status().message()).c_str());
    return 1;
  }
  const PdsmGeometry& g = image->header.geometry;
  int64_t refined = 0, own = 0, subs = 0, sub_vertices = 0, windows = 0, near_depth = 0;
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const std::span<const Vertex> samples = image->Function(x, y);
      const int f = RefinementOf(samples);
      if (f == 1) continue;
      ++refined;
      own += static_cast<int64_t>(OwnFunction(samples).size());
      for (int j = 0; j < f; ++j) {
        for (int i = 0; i < f; ++i) {
          const std::span<const Vertex> sub = SubFunction(samples, f, i, j);
          ++subs;
          sub_vertices += static_cast<int64_t>(sub.size());
          for (size_t k = 0; k < sub.size(); ++k) {
            if (k > 0 && std::isnan(sub[k].a) && !std::isnan(sub[k - 1].a)) ++windows;
            if (!std::isnan(sub[k].a) && std::abs(sub[k].z - depth) <= near) ++near_depth;
          }
        }
      }
    }
  }
  const int64_t vertices = static_cast<int64_t>(image->vertices.size());
  std::printf(
      "%s: %dx%d, %lld vertices; %lld pixels refined (%.2f%%), their own functions %lld "
      "vertices, %lld sub-functions %lld (%.1f each, %.2f windows each), their index %lld\n",
      argv[1], g.width, g.height, static_cast<long long>(vertices), static_cast<long long>(refined),
      100.0 * refined / (double(g.width) * g.height), static_cast<long long>(own),
      static_cast<long long>(subs), static_cast<long long>(sub_vertices),
      subs ? double(sub_vertices) / subs : 0.0, subs ? double(windows) / subs : 0.0,
      static_cast<long long>(2 * refined + subs));
  if (!std::isnan(depth)) {
    std::printf("  sub-function vertices within %g of depth %g: %lld, elsewhere %lld\n", near,
                depth, static_cast<long long>(near_depth),
                static_cast<long long>(sub_vertices - near_depth));
  }
  return 0;
}

}  // namespace
}  // namespace pdsm

int main(int argc, char** argv) { return pdsm::Main(argc, argv); }
