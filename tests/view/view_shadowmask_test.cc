// pdsm-view --mode shadowmask: the textures `pdsm shadowmask` wrote, on the receivers they were
// made for, show what the pdsm mode shows (the PDSM evaluated per pixel). docs/shadowmask.md.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "client/view/frame_renderer.h"
#include "client/view/image_io.h"
#include "tests/view/view_test_support.h"

namespace pdsm::testing {
namespace {

using view::FloatImage;

// The bundled glTF world: a ground with a lightmap UV set (TEXCOORD_1), a box, a bar without
// UVs, and a sun, a spot and a bulb.
std::string WorldPath() { return std::string(PDSM_SOURCE_DIR) + "/examples/world/world.gltf"; }

// The world baked small (64^2 PDSM pixels, 16 samples), once per test process.
const std::string& WorldBake() {
  static const std::string* path = [] {
    const std::string out = ViewBakeDir().File("world.exr");
    CommandResult r = RunCommand(std::string(PDSM_CLI) + " bake " + WorldPath() + " -o " + out +
                                     " --resolution 64x64 --samples 16 --sm-resolution 256",
                                 ViewBakeDir());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return new std::string(out);
  }();
  return *path;
}

std::string WriteTextures(const std::string& name, const std::string& flags, const TempDir& dir) {
  const std::string out = dir.File(name);
  CommandResult r = RunCommand(std::string(PDSM_CLI) + " shadowmask " + WorldPath() + " --pdsm " +
                                   WorldBake() + " -o " + out + " " + flags,
                               dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return out;
}

constexpr char kView[] = "--light sun --headless --size 200x150 --camera 9,8,11,0,0,0,45";

FloatImage Render(const std::string& mode, const std::string& extra, const TempDir& dir,
                  const std::string& name) {
  const std::string pfm = dir.File(name + ".pfm");
  CommandResult r =
      RunCommand(std::string(PDSM_VIEW) + " " + WorldPath() + " --pdsm " + WorldBake() + " " +
                     kView + " --mode " + mode + " --screenshot " + dir.File(name + ".png") +
                     " --save-attenuation " + pfm + " " + extra,
                 dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  absl::StatusOr<FloatImage> image = view::ReadPfm(pfm);
  EXPECT_TRUE(image.ok()) << image.status();
  return image.ok() ? *image : FloatImage{};
}

struct Difference {
  size_t surface = 0;  // pixels both modes shade
  size_t differ = 0;   // of those, differing by more than 1e-4
  size_t far_off = 0;  // differing by more than 0.1
  double mean = 0;     // mean |difference| over the surface
};

Difference Compare(const FloatImage& a, const FloatImage& b) {
  Difference d;
  EXPECT_EQ(a.values.size(), b.values.size());
  if (a.values.size() != b.values.size()) return d;
  double sum = 0;
  for (size_t i = 0; i < a.values.size(); ++i) {
    EXPECT_EQ(a.values[i] == view::kBackground, b.values[i] == view::kBackground) << i;
    if (a.values[i] < 0 || b.values[i] < 0) continue;
    const double diff = std::abs(double(a.values[i]) - double(b.values[i]));
    ++d.surface;
    d.differ += diff > 1e-4;
    d.far_off += diff > 0.1;
    sum += diff;
  }
  d.mean = d.surface > 0 ? sum / d.surface : 0;
  return d;
}

TEST(ViewShadowmask, TheGroundsTextureShowsWhatThePdsmModeShows) {
  TempDir dir;
  const std::string dense = WriteTextures("dense", "--texels-per-unit 16", dir);
  const std::string coarse = WriteTextures("coarse", "--texels-per-unit 1", dir);
  const std::string visibility =
      WriteTextures("visibility", "--texels-per-unit 16 --visibility", dir);
  const FloatImage pdsm = Render("pdsm", "", dir, "pdsm");
  const FloatImage textured = Render("shadowmask", "--shadowmask " + dense, dir, "dense");
  const FloatImage blurred = Render("shadowmask", "--shadowmask " + coarse, dir, "coarse");
  const FloatImage from_visibility =
      Render("shadowmask", "--shadowmask " + visibility, dir, "visibility");

  const Difference near = Compare(textured, pdsm);
  const Difference far = Compare(blurred, pdsm);
  // The ground fills much of the view, with the box's and the bar's sun shadows on it.
  ASSERT_GT(near.surface, 5000u);
  // 256^2 texels over the 16 x 16 ground against the PDSM's own bilinear lookup per pixel:
  // the same function, sampled at texel centres and blended again. Measured (200 x 150):
  // mean 1.4e-4 over 18215 pixels, 386 differing at all, 5 by more than 0.1 (on the
  // shadows' edges).
  EXPECT_LT(near.mean, 2e-3);
  EXPECT_LT(near.far_off, near.surface / 200);
  // The ground really is drawn from its texture: its shadows differ from the per-pixel PDSM
  // in the last digits, and a 16^2 texture (a texel a unit) blurs them (measured: mean 6.3e-3,
  // 365 pixels more than 0.1 off).
  EXPECT_GT(near.differ, 0u);
  EXPECT_GT(far.mean, 10 * near.mean);
  EXPECT_GT(far.far_off, 10 * near.far_off + 10);
  // A texture of 1 - A (--visibility) is turned back into A: the same picture.
  const Difference same = Compare(from_visibility, textured);
  EXPECT_EQ(same.differ, 0u);
}

TEST(ViewShadowmask, AMissingFolderFlagOrLightIsNamed) {
  TempDir dir;
  const auto view = [&](const std::string& extra) {
    return RunCommand(std::string(PDSM_VIEW) + " " + WorldPath() + " --pdsm " + WorldBake() + " " +
                          kView + " --mode shadowmask --screenshot " + dir.File("out.png") + " " +
                          extra,
                      dir);
  };
  CommandResult r = view("");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--shadowmask DIR"), std::string::npos) << r.err;

  std::filesystem::create_directories(dir.File("empty"));
  r = view("--shadowmask " + dir.File("empty"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(dir.File("empty")), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("ground-shadowmask0.exr"), std::string::npos) << r.err;

  // Textures of the spot only: the sun (the viewer's light) is in none of them.
  const std::string spot = WriteTextures("spot", "--light spot", dir);
  r = view("--shadowmask " + spot);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("hold the lights spot, not \"sun\""), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.File("out.png")));
}

}  // namespace
}  // namespace pdsm::testing
