// `pdsm bake SCENE -o OUT.exr` ends with two pictures: OUT.png, the camera view of the scene
// with its baked soft shadows (pdsm-view's headless renderer at its default camera, 1280x720),
// and OUT.light.png, the map seen from the light. --preview names the first, --no-preview
// skips both, and a picture that would land on another output is refused before the bake.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "client/view/image_io.h"
#include "core/pdsm/pdsm_file.h"
#include "tests/test_support.h"

namespace pdsm::testing {
namespace {

namespace fs = std::filesystem;

const std::string kPdsm = PDSM_CLI;
// plates, small enough for a test; the camera view keeps its full 1280x720.
const std::string kOverrides = " --resolution 64x64 --samples 16 --sm-resolution 256";

TEST(BakePreviews, CameraViewIsTheViewersPictureAndShowsSoftShadows) {
  TempDir dir;
  const std::string out = dir.File("plates.exr");
  CommandResult bake =
      RunCommand(kPdsm + " bake " + ExamplePath("plates") + " -o " + out + kOverrides, dir);
  ASSERT_EQ(bake.exit_code, 0) << bake.err;
  EXPECT_NE(bake.out.find("preview: " + dir.File("plates.png") + " (camera view"),
            std::string::npos)
      << bake.out;
  EXPECT_NE(bake.out.find("light view: " + dir.File("plates.light.png")), std::string::npos)
      << bake.out;

  absl::StatusOr<view::RgbImage> camera = view::ReadPng(dir.File("plates.png"));
  ASSERT_TRUE(camera.ok()) << camera.status();
  EXPECT_EQ(camera->width, 1280);
  EXPECT_EQ(camera->height, 720);
  absl::StatusOr<view::RgbImage> light = view::ReadPng(dir.File("plates.light.png"));
  ASSERT_TRUE(light.ok()) << light.status();
  EXPECT_EQ(light->width, 64);  // one pixel per PDSM pixel
  EXPECT_EQ(light->height, 64);

  // The same picture as the viewer's default camera, and the attenuation it was shaded with:
  // umbra and penumbra both well in view (the light's-eye map hid them behind the casters).
  CommandResult view =
      RunCommand(std::string(PDSM_VIEW) + " " + ExamplePath("plates") + " --pdsm " + out +
                     " --headless --size 1280x720" + " --screenshot " + dir.File("viewer.png") +
                     " --save-attenuation " + dir.File("viewer.pfm"),
                 dir);
  ASSERT_EQ(view.exit_code, 0) << view.err;
  absl::StatusOr<view::RgbImage> viewer = view::ReadPng(dir.File("viewer.png"));
  ASSERT_TRUE(viewer.ok()) << viewer.status();
  EXPECT_TRUE(viewer->rgb == camera->rgb) << "the camera view is not the viewer's picture";
  absl::StatusOr<view::FloatImage> a = view::ReadPfm(dir.File("viewer.pfm"));
  ASSERT_TRUE(a.ok()) << a.status();
  size_t umbra = 0, penumbra = 0;
  for (float v : a->values) {
    umbra += v > 0.98f;
    penumbra += v > 0.05f && v <= 0.98f;
  }
  // Measured: 1.4% umbra, 5.5% penumbra.
  const size_t pixels = a->values.size();
  std::printf("camera view: %zu umbra, %zu penumbra of %zu pixels\n", umbra, penumbra, pixels);
  EXPECT_GT(umbra, pixels / 200) << "umbra pixels";
  EXPECT_GT(penumbra, pixels / 50) << "penumbra pixels";
}

TEST(BakePreviews, PreviewFlagNamesBothAndNoPreviewSkipsThem) {
  TempDir dir;
  const std::string scene = ExamplePath("plates");
  CommandResult r = RunCommand(kPdsm + " bake " + scene + " -o " + dir.File("a.exr") +
                                   " --preview " + dir.File("pic.png") + kOverrides,
                               dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir.File("pic.png")));
  EXPECT_TRUE(fs::exists(dir.File("pic.light.png")));
  EXPECT_FALSE(fs::exists(dir.File("a.png")));

  r = RunCommand(
      kPdsm + " bake " + scene + " -o " + dir.File("b.exr") + " --no-preview" + kOverrides, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(dir.File("b.png")));
  EXPECT_FALSE(fs::exists(dir.File("b.light.png")));
  EXPECT_EQ(r.out.find("preview"), std::string::npos) << r.out;
}

// The light's map of a sun bake shows every receiver pixel: the ground nearest a low sun lies
// nearer than any caster, and the preview used to clip it there (a corner of the ground
// missing, though the PDSM holds it). Each pixel whose ray meets the ground is not background.
TEST(BakePreviews, SunLightMapShowsTheWholeGround) {
  TempDir dir;
  WriteText(dir.File("sun.json"), R"({
  "name": "sun",
  "meshes": [
    {"inline": {"positions": [-5,0,-5, 5,0,-5, 5,0,5, -5,0,5], "indices": [0,1,2, 0,2,3]},
     "role": "RECEIVER_ONLY"},
    {"inline": {"positions": [-0.5,1,-0.5, 0.5,1,-0.5, 0.5,1,0.5, -0.5,1,0.5],
                "indices": [0,1,2, 0,2,3]}, "role": "CASTER_ONLY"}
  ],
  "light": {"sun": {"direction": [-0.6,-0.5,-0.4], "angularDiameterDeg": 2}},
  "bake": {"resolution": [64,64], "samples": 4, "tileSize": 16}
})");
  const std::string out = dir.File("sun.exr");
  CommandResult r = RunCommand(kPdsm + " bake " + dir.File("sun.json") + " -o " + out, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  absl::StatusOr<PdsmHeader> header = ReadPdsmHeader(out);
  ASSERT_TRUE(header.ok()) << header.status();
  absl::StatusOr<view::RgbImage> light = view::ReadPng(dir.File("sun.light.png"));
  ASSERT_TRUE(light.ok()) << light.status();
  const PdsmGeometry& g = header->geometry;
  ASSERT_EQ(g.projection, Projection::kOrthographic);
  size_t ground = 0, missing = 0;
  for (int j = 0; j < g.height; ++j) {
    for (int i = 0; i < g.width; ++i) {
      // The pixel's ray (s, t, z), z along the sun's direction, meets y = 0 at one z.
      const glm::dvec3 origin = g.frame.WorldFromLight({g.PixelCenterS(i), g.PixelCenterT(j), 0});
      const double z = -origin.y / g.frame.n.y;
      const glm::dvec3 p = origin + z * g.frame.n;
      if (std::abs(p.x) > 4.9 || std::abs(p.z) > 4.9) continue;  // off the ground, or its rim
      ++ground;
      // As seen from the light (PreviewImage): t grows upwards, u runs right to left.
      const size_t at = (static_cast<size_t>(g.height - 1 - j) * g.width + (g.width - 1 - i)) * 3;
      missing += light->rgb[at] == 24 && light->rgb[at + 1] == 28 && light->rgb[at + 2] == 52;
    }
  }
  EXPECT_GT(ground, 1000u);
  EXPECT_EQ(missing, 0u) << "of " << ground << " ground pixels";
}

// A PDSM larger than the GL's storage buffer (plates at 1024^2 with epsilon 0: 17.2 M
// vertices, 137 MB; llvmpipe holds 128 MB) bakes and gets its camera view: the view streams
// the tiles it reads (client/view/pdsm_tile_pool.h), which fit. It used to fail the command
// after the PDSM was written, then to skip the picture with a warning.
TEST(BakePreviews, APdsmLargerThanTheGlsBuffersGetsItsCameraView) {
  TempDir dir;
  const std::string out = dir.File("big.exr");
  CommandResult r = RunCommand(kPdsm + " bake " + ExamplePath("plates") + " -o " + out +
                                   " --resolution 1024x1024 --epsilon 0 --threads 2",
                               dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(out));
  EXPECT_TRUE(fs::exists(dir.File("big.light.png")));
  EXPECT_TRUE(fs::exists(dir.File("big.png")));
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("preview: " + dir.File("big.png")), std::string::npos) << r.out;
}

// `-o x.png` would put the camera view on the PDSM, `--preview z.exr -o z.exr` the same, and
// `-o w.light.png --preview w.png` the light's map on it: each is refused before any work,
// naming both flags.
TEST(BakePreviews, PicturesOnAnotherOutputAreRefused) {
  TempDir dir;
  const std::string scene = ExamplePath("plates");
  struct Case {
    std::string args, flag;
  };
  const Case cases[] = {
      {" -o " + dir.File("x.png"), "--preview"},
      {" -o " + dir.File("z.exr") + " --preview " + dir.File("z.exr"), "--preview"},
      {" -o " + dir.File("w.light.png") + " --preview " + dir.File("w.png"), ".light.png"},
  };
  for (const Case& c : cases) {
    CommandResult r = RunCommand(kPdsm + " bake " + scene + c.args + kOverrides, dir);
    EXPECT_EQ(r.exit_code, 2) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find("pdsm: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("-o"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.flag), std::string::npos) << r.err;
  }
  for (const fs::directory_entry& e : fs::directory_iterator(dir.path())) {
    const std::string name = e.path().filename().string();
    EXPECT_TRUE(name == "cmd.out" || name == "cmd.err") << "left behind: " << name;
  }
}

}  // namespace
}  // namespace pdsm::testing
