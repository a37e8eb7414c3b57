// The GPU PDSM (shaders/view/shade.frag) against the CPU code of `pdsm query`
// (QueryAttenuation, the viewer's `cpu` mode), on the same PDSM, camera and pixels, with a
// dynamic sphere that was not in the bake (thesis 4.3). docs/viewer.md states the tolerance.
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "client/view/frame_renderer.h"
#include "client/view/image_io.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_test_images.h"
#include "core/pdsm/refined_pixel.h"
#include "tests/view/view_test_support.h"

namespace pdsm::testing {
namespace {

using view::FloatImage;

// Tolerance (docs/viewer.md): |A_gpu - A_cpu| <= 1e-4 at every pixel but at most 0.1% of
// them. The GPU evaluates in float32 what the CPU does in double; only a fragment whose depth
// lies within float rounding of a jump of A(z) may land on the other side of it.
constexpr double kAttenuationTolerance = 1e-4;
constexpr double kMaxOutlierFraction = 1e-3;

// A sphere in the umbra of the pink plate of `plates` (above the ground, below the plate).
constexpr char kSphere[] = "--sphere -1.5,1.0,-1.0,0.6";
constexpr char kCamera[] = "--camera 4,7,6,0,1,0,40";

FloatImage RenderAttenuation(const std::string& mode, const std::string& extra, const TempDir& dir,
                             bool surfaces_only = false, const std::string& pdsm = "") {
  const std::string pfm = dir.File(mode + ".pfm");
  CommandResult r =
      RunView("plates",
              "--pdsm " + (pdsm.empty() ? SmallBake("plates", surfaces_only) : pdsm) +
                  " --headless --size 160x120 " + kCamera + " --mode " + mode + " --screenshot " +
                  dir.File(mode + ".png") + " --save-attenuation " + pfm + " " + extra,
              dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  absl::StatusOr<FloatImage> image = view::ReadPfm(pfm);
  EXPECT_TRUE(image.ok()) << image.status();
  return image.ok() ? *image : FloatImage{};
}

// Red where the two differ by more than the tolerance, grey elsewhere.
void WriteDiffImage(const FloatImage& a, const FloatImage& b, const std::string& path) {
  view::RgbImage diff{a.width, a.height, std::vector<uint8_t>(a.values.size() * 3)};
  for (size_t i = 0; i < a.values.size(); ++i) {
    const bool bad = !(std::abs(a.values[i] - b.values[i]) <= kAttenuationTolerance);
    const uint8_t grey = static_cast<uint8_t>(std::clamp(a.values[i], 0.0f, 1.0f) * 120 + 60);
    diff.rgb[3 * i] = bad ? 255 : grey;
    diff.rgb[3 * i + 1] = bad ? 0 : grey;
    diff.rgb[3 * i + 2] = bad ? 0 : grey;
  }
  ASSERT_TRUE(view::WritePng(path, diff).ok());
}

std::vector<bool> SphereMask(const std::string& mode, const TempDir& dir);

// GPU and CPU images of the same bake (`pdsm`, or the small bake of plates): same background
// and outside pixels, and attenuation within the tolerance; returns the count of pixels on the
// PDSM's surfaces.
size_t ExpectGpuMatchesCpu(bool surfaces_only, const std::string& diff_name,
                           const std::string& pdsm = "") {
  TempDir dir;
  const FloatImage gpu = RenderAttenuation("pdsm", kSphere, dir, surfaces_only, pdsm);
  const FloatImage cpu = RenderAttenuation("cpu", kSphere, dir, surfaces_only, pdsm);
  EXPECT_EQ(gpu.values.size(), cpu.values.size());
  if (gpu.values.empty() || gpu.values.size() != cpu.values.size()) {
    ADD_FAILURE() << "no image";
    return 0;
  }
  size_t surface = 0, outliers = 0, penumbra = 0, umbra = 0;
  double max_difference = 0;
  for (size_t i = 0; i < gpu.values.size(); ++i) {
    // The same pixels are background, outside the PDSM, or shaded in both.
    if ((gpu.values[i] == view::kBackground) != (cpu.values[i] == view::kBackground) ||
        (gpu.values[i] == view::kOutsidePdsm) != (cpu.values[i] == view::kOutsidePdsm)) {
      ADD_FAILURE() << "pixel " << i << ": GPU " << gpu.values[i] << ", CPU " << cpu.values[i];
      return 0;
    }
    if (gpu.values[i] < 0) continue;
    ++surface;
    const double d = std::abs(gpu.values[i] - cpu.values[i]);
    max_difference = std::max(max_difference, d);
    if (!(d <= kAttenuationTolerance)) ++outliers;
    if (cpu.values[i] > 0.05 && cpu.values[i] < 0.95) ++penumbra;
    if (cpu.values[i] >= 0.95) ++umbra;
  }
  std::printf("GPU vs CPU: %zu surface pixels, max |dA| %.3g, %zu above %.0e\n", surface,
              max_difference, outliers, kAttenuationTolerance);
  // Not vacuous: the image holds lit, penumbra and umbra pixels.
  EXPECT_GT(surface, gpu.values.size() / 4);
  EXPECT_GT(penumbra, surface / 100);
  EXPECT_GT(umbra, surface / 100);
  const bool ok = outliers <= kMaxOutlierFraction * surface;
  if (!ok) {
    const std::string diff = ViewTestOutputDir() + "/" + diff_name;
    WriteDiffImage(gpu, cpu, diff);
    ADD_FAILURE() << outliers << " of " << surface << " pixels differ by more than "
                  << kAttenuationTolerance << "; diff image: " << diff;
  }
  return surface;
}

TEST(ViewAgreement, GpuPdsmMatchesCpuQueryPerPixel) {
  ExpectGpuMatchesCpu(/*surfaces_only=*/false, "agreement_diff.png");
}

// A copy of the small bake of plates with refined pixels (format version 3,
// core/pdsm/refined_pixel.h): in blocks of 5 x 5 pixels, in turn unrefined, 2x, 4x and 8x.
// Sub-pixel (i, j) of a refined pixel holds the pixel's function with A scaled by
// 0.4 + 0.6 * (i + j) / (2f - 2): sharp steps between sub-pixels and across every kind of
// block edge, which the GPU's lookup must take exactly as the CPU's does. The 2x pixels' and
// every other 4x pixel's sub-functions are defined only from the pixel's first vertex on (a
// NaN-bracketed window), and some 8x sub-pixels have none, so that the lookup takes its
// fallbacks to the pixels' own functions too.
std::string RefinedPlates(const TempDir& dir) {
  absl::StatusOr<PdsmImage> plain = ReadPdsm(SmallBake("plates"));
  EXPECT_TRUE(plain.ok()) << plain.status();
  if (!plain.ok()) return "";
  PdsmImage refined;
  refined.header = plain->header;
  refined.header.max_refinement = 8;
  refined.header.format_version = MinimumFormatVersion(refined.header);
  refined.offsets.push_back(0);
  const PdsmGeometry& g = refined.header.geometry;
  const std::vector<RefinedBand> everywhere = {{-1e30f, 1e30f}};
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const std::span<const Vertex> own = plain->Function(x, y);
      const int f = (1 << ((x / 5 + y / 5) % 4));
      if (f == 1) {
        refined.vertices.insert(refined.vertices.end(), own.begin(), own.end());
      } else {
        std::vector<std::vector<Vertex>> subs;
        for (int j = 0; j < f; ++j) {
          for (int i = 0; i < f; ++i) {
            const float scale = 0.4f + 0.6f * static_cast<float>(i + j) / (2 * f - 2);
            std::vector<Vertex>& sub = subs.emplace_back();
            const bool windowed = !own.empty() && (f == 2 || (f == 4 && (x + y) % 2 == 0));
            if (f == 8 && (i + 3 * j) % 5 == 0) continue;  // undefined everywhere
            if (windowed) sub.push_back({kUndefinedFrom, kNaN});
            for (Vertex v : own) sub.push_back({v.z, v.a * scale});
            if (windowed) {
              sub.push_back({1e30f, sub.back().a});
              sub.push_back({1e30f, kNaN});
            }
          }
        }
        AppendRefinedPixel(f, everywhere, own, subs, &refined.vertices);
      }
      refined.offsets.push_back(refined.vertices.size());
    }
  }
  const std::string path = dir.File("plates_refined.exr");
  EXPECT_TRUE(WriteTiles(path, refined.header, CutTiles(refined)).ok());
  return path;
}

TEST(ViewAgreement, RefinedPixelsGpuMatchesCpu) {
  TempDir dir;
  const std::string refined = RefinedPlates(dir);
  ASSERT_FALSE(refined.empty());
  ExpectGpuMatchesCpu(/*surfaces_only=*/false, "agreement_refined_diff.png", refined);
  // Not vacuous: the refined copy reads differently from the plain bake.
  TempDir other;
  const FloatImage plain = RenderAttenuation("cpu", kSphere, other);
  const FloatImage with = RenderAttenuation("cpu", kSphere, other, false, refined);
  ASSERT_EQ(plain.values.size(), with.values.size());
  size_t differ = 0;
  for (size_t i = 0; i < plain.values.size(); ++i) {
    differ += plain.values[i] >= 0 && std::abs(plain.values[i] - with.values[i]) > 0.01;
  }
  EXPECT_GT(differ, plain.values.size() / 50);
}

// A surfaces-only PDSM holds A(z) only near the static receivers: there GPU and CPU agree as
// for a full file; on the dynamic sphere both say "unknown" (NaN on the CPU) -- the same
// pixels, checked by the outside-pixel comparison. (Without its own shadow, which would mark
// its far side as self-shadowed.)
TEST(ViewAgreement, SurfacesOnlyPdsmGpuMatchesCpu) {
  const size_t surface =
      ExpectGpuMatchesCpu(/*surfaces_only=*/true, "agreement_surfaces_only_diff.png");
  TempDir dir;
  const FloatImage gpu = RenderAttenuation("pdsm", std::string(kSphere) + " --no-dynamic-shadows",
                                           dir, /*surfaces_only=*/true);
  const std::vector<bool> sphere = SphereMask("pdsm", dir);
  ASSERT_EQ(sphere.size(), gpu.values.size());
  size_t sphere_pixels = 0, sphere_unknown = 0;
  for (size_t i = 0; i < sphere.size(); ++i) {
    if (!sphere[i]) continue;
    ++sphere_pixels;
    if (gpu.values[i] == view::kOutsidePdsm) ++sphere_unknown;
  }
  EXPECT_GT(surface, 1000u);
  EXPECT_GT(sphere_pixels, 50u);
  EXPECT_GT(sphere_unknown, sphere_pixels * 9 / 10);  // not a receiver: no function there
}

// Pixels showing the dynamic sphere, told by its colour (pink: red and blue above green,
// unlike every baked mesh of `plates`), in the PNG RenderAttenuation wrote for `mode`.
std::vector<bool> SphereMask(const std::string& mode, const TempDir& dir) {
  absl::StatusOr<view::RgbImage> image = view::ReadPng(dir.File(mode + ".png"));
  EXPECT_TRUE(image.ok()) << image.status();
  std::vector<bool> mask;
  if (!image.ok()) return mask;
  for (size_t i = 0; i < image->rgb.size(); i += 3) {
    const int r = image->rgb[i], g = image->rgb[i + 1], b = image->rgb[i + 2];
    mask.push_back(r > g + 20 && b > g + 8);
  }
  return mask;
}

// The sphere under the pink plate was not in the bake, yet its top is in the plate's umbra.
TEST(ViewAgreement, DynamicSphereReceivesPdsmShadow) {
  TempDir dir;
  const FloatImage with = RenderAttenuation("pdsm", kSphere, dir);
  const std::vector<bool> sphere = SphereMask("pdsm", dir);
  ASSERT_EQ(sphere.size(), with.values.size());
  size_t pixels = 0, umbra = 0;
  for (size_t i = 0; i < sphere.size(); ++i) {
    if (!sphere[i]) continue;
    ++pixels;
    if (with.values[i] >= 0.95) ++umbra;
  }
  EXPECT_GT(pixels, 50u);
  EXPECT_GT(umbra, pixels / 4);
}

// The same with a mesh file (--object, Assimp) placed by --object-transform: a box under the
// plate, its top in the umbra.
TEST(ViewAgreement, DynamicMeshReceivesPdsmShadow) {
  TempDir dir;
  WriteText(dir.File("box.obj"),
            "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\n"
            "v -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
            "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
            "f 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n");
  const FloatImage with =
      RenderAttenuation("pdsm",
                        "--object " + dir.File("box.obj") +
                            " --object-transform 0.5,0,0,-1.5,0,0.5,0,1.0,0,0,0.5,-1.0,0,0,0,1",
                        dir);
  const std::vector<bool> box = SphereMask("pdsm", dir);
  ASSERT_EQ(box.size(), with.values.size());
  size_t pixels = 0, umbra = 0;
  for (size_t i = 0; i < box.size(); ++i) {
    if (!box[i]) continue;
    ++pixels;
    if (with.values[i] >= 0.95) ++umbra;
  }
  EXPECT_GT(pixels, 50u);
  EXPECT_GT(umbra, pixels / 4);
}

// A sphere in the open casts in every mode: in the shadow-map modes it is drawn into their
// maps, in the PDSM modes into maps of its own (it was not in the bake), and with
// --no-dynamic-shadows it only receives.
TEST(ViewAgreement, DynamicSphereCastsInEveryMode) {
  TempDir dir;
  const std::string sphere = "--sphere -3,1.5,1.5,0.6";
  const std::vector<std::pair<std::string, std::string>> runs = {
      {"pdsm", ""}, {"cpu", ""}, {"hard", ""}, {"multi-sm", ""}, {"pdsm", "--no-dynamic-shadows"}};
  for (const auto& [mode, flag] : runs) {
    const FloatImage without = RenderAttenuation(mode, flag, dir);
    const FloatImage with = RenderAttenuation(mode, sphere + " " + flag, dir);
    const std::vector<bool> mask = SphereMask(mode, dir);
    ASSERT_EQ(mask.size(), with.values.size());
    size_t darker_ground = 0;
    for (size_t i = 0; i < with.values.size(); ++i) {
      if (!mask[i] && with.values[i] > std::max(without.values[i], 0.0f) + 0.2f) ++darker_ground;
    }
    if (flag.empty()) {
      EXPECT_GT(darker_ground, 20u) << mode << ": the sphere casts no shadow";
    } else {
      EXPECT_EQ(darker_ground, 0u) << mode << " " << flag;
    }
  }
}

}  // namespace
}  // namespace pdsm::testing
