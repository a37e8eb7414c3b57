// `pdsm export-image`: the PDSM as an ordinary image (client/export/attenuation_image.h). Each
// pixel must equal `pdsm query` at its point — on a plane, or on the receivers — the PNG must
// read back to within half a level with alpha marking what is undefined, the receivers must be
// the ones the bake's own light view shows, and bad requests fail naming what to fix.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <png.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "client/view/image_io.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"
#include "tests/test_support.h"

namespace pdsm::testing {
namespace {

const std::string kPdsm = PDSM_CLI;

struct ExrImage {
  int width = 0, height = 0;
  std::map<std::string, std::vector<float>> channels;  // row 0 at the top
  std::string what;                                    // the pdsmExport attribute
};

ExrImage ReadExr(const std::string& path) {
  ExrImage out;
  Imf::InputFile file(path.c_str());
  const Imath::Box2i window = file.header().dataWindow();
  out.width = window.max.x - window.min.x + 1;
  out.height = window.max.y - window.min.y + 1;
  if (const auto* what = file.header().findTypedAttribute<Imf::StringAttribute>("pdsmExport")) {
    out.what = what->value();
  }
  Imf::FrameBuffer frame;
  for (auto c = file.header().channels().begin(); c != file.header().channels().end(); ++c) {
    std::vector<float>& data = out.channels[c.name()];
    data.resize(static_cast<size_t>(out.width) * out.height);
    frame.insert(c.name(), Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(data.data()),
                                      sizeof(float), sizeof(float) * out.width));
  }
  file.setFrameBuffer(frame);
  file.readPixels(window.min.y, window.max.y);
  return out;
}

// 8-bit gray + alpha, as stored.
struct GrayAlpha {
  int width = 0, height = 0;
  std::vector<uint8_t> ga;
};

GrayAlpha ReadGrayAlphaPng(const std::string& path) {
  png_image image;
  std::memset(&image, 0, sizeof(image));
  image.version = PNG_IMAGE_VERSION;
  GrayAlpha out;
  if (!png_image_begin_read_from_file(&image, path.c_str())) return out;
  EXPECT_EQ(image.format, static_cast<png_uint_32>(PNG_FORMAT_GA)) << path;
  image.format = PNG_FORMAT_GA;
  out.width = static_cast<int>(image.width);
  out.height = static_cast<int>(image.height);
  out.ga.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, out.ga.data(), 0, nullptr)) out.ga.clear();
  return out;
}

class ExportImage : public ::testing::Test {
 protected:
  // A small bake of the example `name`, with its light view (--no-preview off: OUT.light.png).
  std::string Bake(const std::string& name) {
    const std::string out = dir_.File(name + ".exr");
    CommandResult r = RunCommand(kPdsm + " bake " + ExamplePath(name) + " -o " + out +
                                     " --resolution 64x64 --samples 16 --sm-resolution 256",
                                 dir_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return out;
  }
  CommandResult Export(const std::string& args) {
    return RunCommand(kPdsm + " export-image " + args, dir_);
  }

  TempDir dir_;
};

// The world point of image pixel (c, r) at light-space depth z: the PDSM pixel's ray.
glm::dvec3 PointOf(const PdsmGeometry& g, int c, int r, double z) {
  const int x = g.width - 1 - c, y = g.height - 1 - r;
  const double s = g.PixelCenterS(x), t = g.PixelCenterT(y);
  const glm::dvec3 p_light =
      g.projection == Projection::kOrthographic ? glm::dvec3(s, t, z) : glm::dvec3(s * z, t * z, z);
  return g.frame.WorldFromLight(p_light);
}

TEST_F(ExportImage, PlaneEqualsQueryAtEveryPixelCentre) {
  const std::string pdsm_path = Bake("plates");
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(pdsm_path);
  ASSERT_TRUE(pdsm.ok()) << pdsm.status();
  const PdsmGeometry& g = pdsm->header.geometry;
  // Between the lowest caster (the bar, light-space depth 8.7 to 9 below the light at 10) and
  // the ground (10).
  const double z = 9.5;
  CommandResult r = Export(pdsm_path + " --depth 9.5 -o " + dir_.File("plane.exr"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("4096 of 4096 pixels (100.0%) defined"), std::string::npos) << r.out;
  const ExrImage image = ReadExr(dir_.File("plane.exr"));
  ASSERT_EQ(image.width, g.width);
  ASSERT_EQ(image.height, g.height);
  EXPECT_NE(image.what.find("light-space depth 9.5"), std::string::npos) << image.what;
  for (const char* channel : {"Y", "A", "attenuation", "depth"}) {
    ASSERT_TRUE(image.channels.count(channel)) << channel;
  }
  int penumbra = 0;
  for (int row = 0; row < image.height; ++row) {
    for (int c = 0; c < image.width; ++c) {
      const size_t p = static_cast<size_t>(row) * image.width + c;
      const double expected = QueryAttenuation(*pdsm, PointOf(g, c, row, z));
      ASSERT_FALSE(std::isnan(expected));
      ASSERT_NEAR(image.channels.at("attenuation")[p], expected, 2e-6) << c << "," << row;
      ASSERT_NEAR(image.channels.at("Y")[p], 1.0 - expected, 2e-6);
      ASSERT_EQ(image.channels.at("A")[p], 1.0f);
      ASSERT_EQ(image.channels.at("depth")[p], static_cast<float>(z));
      penumbra += expected > 0.02 && expected < 0.98;
    }
  }
  EXPECT_GT(penumbra, 100);  // the plane crosses the plates' penumbrae, not only lit space
}

// On the receivers, for a perspective light (plates) and the sun's orthographic map.
TEST_F(ExportImage, SurfaceEqualsQueryOnTheReceiversTheLightViewShows) {
  for (const std::string name : {"plates", "sun_pillars"}) {
    SCOPED_TRACE(name);
    const std::string pdsm_path = Bake(name);
    absl::StatusOr<PdsmImage> pdsm = ReadPdsm(pdsm_path);
    ASSERT_TRUE(pdsm.ok()) << pdsm.status();
    const PdsmGeometry& g = pdsm->header.geometry;
    const std::string exr = dir_.File(name + "_surface.exr"), png = dir_.File(name + "_s.png");
    for (const std::string& out : {exr, png}) {
      CommandResult r = Export(pdsm_path + " --surface " + ExamplePath(name) + " -o " + out);
      ASSERT_EQ(r.exit_code, 0) << r.err;
    }
    const ExrImage image = ReadExr(exr);
    ASSERT_EQ(image.width, g.width);
    const std::vector<float>& a = image.channels.at("attenuation");
    const std::vector<float>& depth = image.channels.at("depth");
    // The bake's light view shades the same receivers (found by GL depth, not Embree):
    // gray = 36 + 219 (1 - A), dark blue where no receiver.
    absl::StatusOr<view::RgbImage> light = view::ReadPng(dir_.File(name + ".light.png"));
    ASSERT_TRUE(light.ok()) << light.status();
    const GrayAlpha exported = ReadGrayAlphaPng(png);
    ASSERT_EQ(exported.ga.size(), a.size() * 2);
    int defined = 0, penumbra = 0, agree = 0;
    for (size_t p = 0; p < a.size(); ++p) {
      const uint8_t* rgb = &light->rgb[3 * p];
      const bool light_view_has_receiver = !(rgb[0] == 24 && rgb[1] == 28 && rgb[2] == 52);
      if (std::isnan(a[p])) {
        EXPECT_EQ(image.channels.at("A")[p], 0.0f);
        EXPECT_EQ(exported.ga[2 * p + 1], 0);
        agree += !light_view_has_receiver;
        continue;
      }
      ++defined;
      penumbra += a[p] > 0.02 && a[p] < 0.98;
      const int c = static_cast<int>(p % image.width), row = static_cast<int>(p / image.width);
      ASSERT_NEAR(QueryAttenuation(*pdsm, PointOf(g, c, row, depth[p])), a[p], 1e-4)
          << c << "," << row;
      // The PNG reads back to within half a level (plus float rounding).
      EXPECT_NEAR(exported.ga[2 * p] / 255.0, 1.0 - a[p], 0.5 / 255 + 1e-6);
      EXPECT_EQ(exported.ga[2 * p + 1], 255);
      agree += light_view_has_receiver && std::abs((rgb[0] - 36) / 219.0 - (1.0 - a[p])) < 0.02;
    }
    std::printf("%s: %d of %zu pixels defined, %d in penumbra, %d agree with the light view\n",
                name.c_str(), defined, a.size(), penumbra, agree);
    EXPECT_GT(defined, static_cast<int>(a.size()) / 2);
    // From the light's centre the casters hide their umbrae; the penumbrae's rims show.
    EXPECT_GT(penumbra, 20);
    // Receiver depths from Embree and from GL differ only along silhouettes.
    EXPECT_GE(agree, 0.97 * static_cast<double>(a.size())) << agree << " of " << a.size();
  }
}

TEST_F(ExportImage, UndefinedPixelsAreTransparent) {
  const std::string pdsm_path = Bake("plates");
  // No point of a perspective ray lies behind the light.
  CommandResult r = Export(pdsm_path + " --depth -1 -o " + dir_.File("behind.png"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("0 of 4096 pixels (0.0%) defined"), std::string::npos) << r.out;
  const GrayAlpha png = ReadGrayAlphaPng(dir_.File("behind.png"));
  ASSERT_EQ(png.ga.size(), 2u * 4096);
  for (size_t p = 0; p < 4096; ++p) ASSERT_EQ(png.ga[2 * p + 1], 0);
}

TEST_F(ExportImage, BadRequestsFailNamingWhatToFix) {
  const std::string pdsm_path = Bake("plates");
  WriteText(dir_.File("keep.png"), "keep");
  const struct {
    std::string args, message;
  } cases[] = {
      {pdsm_path + " -o " + dir_.File("x.png"), "give either --depth Z"},
      {pdsm_path + " --depth 3 --surface " + ExamplePath("plates") + " -o " + dir_.File("x.png"),
       "give either --depth Z"},
      {pdsm_path + " --depth 3 -o " + dir_.File("x.jpg"), "unknown image type \".jpg\""},
      {pdsm_path + " --depth nan -o " + dir_.File("x.png"), "--depth"},
      {pdsm_path + " --depth 3 -o " + pdsm_path, "-o " + pdsm_path},
      {dir_.File("missing.exr") + " --depth 3 -o " + dir_.File("x.png"), "missing.exr"},
      {pdsm_path + " --surface " + ExamplePath("sun_pillars") + " -o " + dir_.File("keep.png"),
       "--allow-mismatch"},
  };
  for (const auto& c : cases) {
    CommandResult r = Export(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find("pdsm: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << "\n" << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir_.File("x.png")));
  EXPECT_FALSE(std::filesystem::exists(dir_.File("x.jpg")));
  EXPECT_EQ(ReadBytes(dir_.File("keep.png")), "keep");  // a refused export leaves it whole
  // --allow-mismatch turns the other scene into a warning.
  CommandResult r = Export(pdsm_path + " --surface " + ExamplePath("sun_pillars") +
                           " --allow-mismatch -o " + dir_.File("other.png"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("warning"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace pdsm::testing
