// Test images for the PDSM file tests: a header whose every field is off its default, random
// functions, the image cut into the writer's tiles, a write of them, and a tile comparison.
#ifndef PDSM_CORE_PDSM_PDSM_TEST_IMAGES_H_
#define PDSM_CORE_PDSM_PDSM_TEST_IMAGES_H_

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "absl/status/status.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_image.h"
#include "core/pdsm/refined_pixel.h"
#include "core/util/file_system.h"

namespace pdsm::testing {

// Every field differs from its default, and doubles are ones a decimal round trip would
// break (1/3, pi, values near 1e6).
inline PdsmHeader FullHeader(int width, int height, int tile_size) {
  PdsmHeader h;
  h.scene_name = "plates \"quoted\" \xc3\xa9t\xc3\xa9";
  h.light_shape = LightShape::kDisk;
  h.light_half_width = 0.1 + 0.2;
  h.light_half_height = 1.0 / 3.0;
  h.light_radius = std::numbers::sqrt2;
  h.tan_half_angle = std::nextafter(0.00465, 1.0);
  PdsmGeometry& g = h.geometry;
  g.projection = Projection::kOrthographic;
  g.frame.center = {1e6 + 0.1, -2.5e5 - 1.0 / 7.0, std::numbers::pi};
  g.frame.u = {0.5 * std::numbers::sqrt2, 0.5 * std::numbers::sqrt2, 0.0};
  g.frame.v = {0.0, 0.0, -1.0};
  g.frame.n = {-0.5 * std::numbers::sqrt2, 0.5 * std::numbers::sqrt2, 0.0};
  g.width = width;
  g.height = height;
  g.s_min = -0.7;
  g.s_max = 0.9;
  g.t_min = -1.0 / 3.0;
  g.t_max = std::numbers::pi / 4;
  g.z_near = 0.01;
  g.z_far = 1e5 + 1.0 / 7.0;
  h.samples = 65536;
  h.shadow_map_resolution = 2048;
  h.epsilon = 0.02;
  h.compression_metric = CompressionMetric::kPerpendicular;
  h.depth_bias = 1e-4 / 3.0;
  h.slope_bias = 2.5;
  h.sampling = SamplingPattern::kUniform;
  h.seed = 0xFEDCBA9876543210ull;  // above INT64_MAX
  h.tile_size = tile_size;
  return h;
}

// Random functions: about a quarter of the pixels empty, repeated depths (jumps) included,
// and optionally one pixel with `big_count` vertices.
inline PdsmImage RandomImage(const PdsmHeader& header, uint32_t seed, int big_count = 0) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> count_dist(-3, 9);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  PdsmImage image;
  image.header = header;
  const size_t pixels = static_cast<size_t>(header.geometry.width) * header.geometry.height;
  const size_t big_pixel = pixels / 2;
  image.offsets.push_back(0);
  for (size_t p = 0; p < pixels; ++p) {
    const int count = p == big_pixel && big_count > 0 ? big_count : std::max(0, count_dist(rng));
    float z = 0.5f + unit(rng);
    for (int k = 0; k < count; ++k) {
      if (unit(rng) > 0.2f) z += unit(rng) * 3.0f;  // else a jump: same depth again
      image.vertices.push_back({z, unit(rng)});
    }
    image.offsets.push_back(image.vertices.size());
  }
  return image;
}

// Refines about one pixel in `every` of `image` (format version 3): each becomes a refined
// pixel (core/pdsm/refined_pixel.h) of a random factor up to header.max_refinement, keeping its
// function as its own, its sub-functions random like RandomImage's, some empty. REQUIRES:
// header.max_refinement > 1.
inline void RefineSomePixels(PdsmImage* image, uint32_t seed, int every = 5) {
  const std::vector<RefinedBand> kEverywhere = {{-1e30f, 1e30f}};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const PdsmGeometry& g = image->header.geometry;
  std::vector<int> factors;
  for (int f = 2; f <= image->header.max_refinement; f *= 2) factors.push_back(f);
  PdsmImage out;
  out.header = image->header;
  out.offsets.push_back(0);
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const std::span<const Vertex> own = image->Function(x, y);
      if (rng() % every != 0) {
        out.vertices.insert(out.vertices.end(), own.begin(), own.end());
      } else {
        const int f = factors[rng() % factors.size()];
        std::vector<std::vector<Vertex>> subs(static_cast<size_t>(f) * f);
        for (std::vector<Vertex>& sub : subs) {
          float z = 0.5f + unit(rng);
          for (int k = static_cast<int>(rng() % 6) - 1; k > 0; --k) {
            if (unit(rng) > 0.2f) z += unit(rng) * 3.0f;
            sub.push_back({z, unit(rng)});
          }
        }
        AppendRefinedPixel(f, kEverywhere, own, subs, &out.vertices);
      }
      out.offsets.push_back(out.vertices.size());
    }
  }
  *image = std::move(out);
}

inline PdsmTile CutTile(const PdsmImage& image, int x0, int y0) {
  const int ts = image.header.tile_size;
  PdsmTile tile;
  tile.x0 = x0;
  tile.y0 = y0;
  tile.width = std::min(ts, image.header.geometry.width - x0);
  tile.height = std::min(ts, image.header.geometry.height - y0);
  tile.offsets.push_back(0);
  for (int y = y0; y < y0 + tile.height; ++y) {
    for (int x = x0; x < x0 + tile.width; ++x) {
      for (const Vertex& v : image.Function(x, y)) tile.vertices.push_back(v);
      tile.offsets.push_back(tile.vertices.size());
    }
  }
  return tile;
}

inline std::vector<PdsmTile> CutTiles(const PdsmImage& image) {
  std::vector<PdsmTile> tiles;
  const int ts = image.header.tile_size;
  for (int y0 = 0; y0 < image.header.geometry.height; y0 += ts) {
    for (int x0 = 0; x0 < image.header.geometry.width; x0 += ts) {
      tiles.push_back(CutTile(image, x0, y0));
    }
  }
  return tiles;
}

inline absl::Status WriteTiles(const std::string& path, const PdsmHeader& header,
                               const std::vector<PdsmTile>& tiles,
                               FileSystem* file_system = nullptr,
                               int64_t reorder_memory_bytes = kTileReorderMemoryBytes) {
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer =
      PdsmWriter::Create(path, header, file_system, reorder_memory_bytes);
  if (!writer.ok()) return writer.status();
  for (const PdsmTile& tile : tiles) {
    if (absl::Status s = (*writer)->WriteTile(tile); !s.ok()) return s;
  }
  return (*writer)->Finish();
}

// Expects `got` to be `want` exactly: rectangle, samples, offsets and every vertex's bit
// pattern (-0.0 must stay -0.0, a NaN its payload).
inline void ExpectSameTile(const PdsmTile& got, const PdsmTile& want) {
  EXPECT_EQ(got.x0, want.x0);
  EXPECT_EQ(got.y0, want.y0);
  EXPECT_EQ(got.width, want.width);
  EXPECT_EQ(got.height, want.height);
  EXPECT_EQ(got.samples, want.samples);
  EXPECT_EQ(got.offsets, want.offsets);
  ASSERT_EQ(got.vertices.size(), want.vertices.size());
  for (size_t i = 0; i < got.vertices.size(); ++i) {
    EXPECT_EQ(std::bit_cast<uint64_t>(got.vertices[i]), std::bit_cast<uint64_t>(want.vertices[i]))
        << "vertex " << i;
  }
}

}  // namespace pdsm::testing

#endif  // PDSM_CORE_PDSM_PDSM_TEST_IMAGES_H_
