// `pdsm shadowmask` (client/export/shadowmask.h), run as a user runs it on a glTF world: each
// texel must hold `pdsm query`'s answer at the world point its centre maps to through the
// lightmap UVs (TEXCOORD_1, past a parent node's transform), one channel per light; the PNG
// must read back to within half a level; objects without UVs, another scene's PDSM and bad
// options are named.
#include <png.h>

#include <cmath>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "client/export/shadowmask.h"
#include "tests/test_support.h"

namespace pdsm::testing {
namespace {

using ::testing::HasSubstr;

const std::string kPdsm = PDSM_CLI;

// Where the ground's lightmap puts texel centres: TEXCOORD_1 maps the quad x, z in [-3, 3]
// onto [0, 1]^2 (v = 0 at z = -3), and the parent node "floor" moves it by +0.5 in z.
constexpr double kFloorShiftZ = 0.5;
glm::dvec3 GroundPoint(double u, double v) { return {6 * u - 3, 0, 6 * v - 3 + kFloorShiftZ}; }

// ground: quad at y = 0 with TEXCOORD_0 tiling (x, z) and TEXCOORD_1 its unwrap, under node
// "floor" (translation z + 0.5); card: a caster quad x, z in [-1, 1] at y = 1, no UVs;
// patch: a unit quad at x in [4, 5] with only TEXCOORD_0 over [0, 1]^2 (its lightmap set).
std::string LightmapWorldGltf() {
  std::string blob;
  const auto floats = [&](std::initializer_list<float> values) {
    for (float f : values) blob.append(reinterpret_cast<const char*>(&f), 4);
  };
  const auto uints = [&](std::initializer_list<uint32_t> values) {
    for (uint32_t u : values) blob.append(reinterpret_cast<const char*>(&u), 4);
  };
  floats({-3, 0, -3, 3, 0, -3, 3, 0, 3, -3, 0, 3});  // 0: ground positions, bytes 0..47
  uints({0, 2, 1, 0, 3, 2});                         // 1: indices (all quads), 48..71
  floats({-3, -3, 3, -3, 3, 3, -3, 3});              // 2: ground TEXCOORD_0 (tiles), 72..103
  floats({0, 0, 1, 0, 1, 1, 0, 1});                  // 3: unit UVs, 104..135
  floats({-1, 1, -1, 1, 1, -1, 1, 1, 1, -1, 1, 1});  // 4: card positions, 136..183
  floats({4, 0, 0, 5, 0, 0, 5, 0, 1, 4, 0, 1});      // 5: patch positions, 184..231
  const std::string views = absl::StrCat(
      R"({"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 24},)",
      R"( {"buffer": 0, "byteOffset": 72, "byteLength": 32}, {"buffer": 0, "byteOffset": 104, "byteLength": 32},)",
      R"( {"buffer": 0, "byteOffset": 136, "byteLength": 48}, {"buffer": 0, "byteOffset": 184, "byteLength": 48})");
  const std::string accessors = absl::StrCat(
      R"({"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-3, 0, -3], "max": [3, 0, 3]},)",
      R"( {"bufferView": 1, "componentType": 5125, "count": 6, "type": "SCALAR"},)",
      R"( {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},)",
      R"( {"bufferView": 3, "componentType": 5126, "count": 4, "type": "VEC2"},)",
      R"( {"bufferView": 4, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, 1, -1], "max": [1, 1, 1]},)",
      R"( {"bufferView": 5, "componentType": 5126, "count": 4, "type": "VEC3", "min": [4, 0, 0], "max": [5, 0, 1]})");
  return absl::StrCat(
      R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 2, 3]}],)",
      R"( "nodes": [{"name": "floor", "translation": [0, 0, )", kFloorShiftZ,
      R"(], "children": [1]}, {"name": "ground", "mesh": 0}, {"name": "card", "mesh": 1},)",
      R"( {"name": "patch", "mesh": 2}],)",
      R"( "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 2, "TEXCOORD_1": 3}, "indices": 1}]},)",
      R"( {"primitives": [{"attributes": {"POSITION": 4}, "indices": 1}]},)",
      R"( {"primitives": [{"attributes": {"POSITION": 5, "TEXCOORD_0": 3}, "indices": 1}]}],)",
      R"( "accessors": [)", accessors, R"(], "bufferViews": [)", views,
      R"(], "buffers": [{"byteLength": )", blob.size(),
      R"(, "uri": "data:application/octet-stream;base64,)", absl::Base64Escape(blob), R"("}]})");
}

// Two lights: a small lamp straight above the card (a soft square shadow under it) and a sun
// from the side.
constexpr char kSceneJson[] = R"({"name": "lightmapped", "meshes": [{"path": "world.gltf"}],
  "lights": [
    {"name": "lamp", "rect": {"center": [0, 4, 0.2], "normal": [0, -1, 0], "up": [0, 0, 1],
                              "size": [0.6, 0.6]}},
    {"name": "sun", "sun": {"direction": [0.5, -1, 0.2], "angularDiameterDeg": 3}}],
  "bake": {"resolution": [64, 64], "samples": 16, "tileSize": 16}})";

struct Rgb {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;
};

Rgb ReadRgbPng(const std::string& path) {
  png_image image;
  std::memset(&image, 0, sizeof(image));
  image.version = PNG_IMAGE_VERSION;
  Rgb out;
  if (!png_image_begin_read_from_file(&image, path.c_str())) return out;
  EXPECT_EQ(image.format, static_cast<png_uint_32>(PNG_FORMAT_RGB)) << path;
  image.format = PNG_FORMAT_RGB;
  out.width = static_cast<int>(image.width);
  out.height = static_cast<int>(image.height);
  out.rgb.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, out.rgb.data(), 0, nullptr)) out.rgb.clear();
  return out;
}

class Shadowmask : public ::testing::Test {
 protected:
  void SetUp() override {
    WriteText(dir_.File("world.gltf"), LightmapWorldGltf());
    WriteText(dir_.File("scene.json"), kSceneJson);
    const CommandResult bake = RunCommand(kPdsm + " bake " + dir_.File("scene.json") + " -o " +
                                              dir_.File("baked.exr") + " --no-preview",
                                          dir_);
    ASSERT_EQ(bake.exit_code, 0) << bake.err;
  }
  CommandResult Run(const std::string& args) {
    return RunCommand(kPdsm + " shadowmask " + dir_.File("scene.json") + " --pdsm " +
                          dir_.File("baked.exr") + " " + args,
                      dir_);
  }
  // `pdsm query` at `points`: one row of values (one per light) a point.
  std::vector<std::vector<double>> Query(const std::vector<glm::dvec3>& points) {
    std::ostringstream csv;
    csv.precision(17);
    for (const glm::dvec3& p : points) csv << p.x << "," << p.y << "," << p.z << "\n";
    WriteText(dir_.File("points.csv"), csv.str());
    const CommandResult r = RunCommand(
        kPdsm + " query " + dir_.File("baked.exr") + " --points " + dir_.File("points.csv"), dir_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::vector<std::vector<double>> rows;
    for (absl::string_view line : absl::StrSplit(r.out, '\n', absl::SkipEmpty())) {
      const std::vector<std::string> fields = absl::StrSplit(line, ',');
      if (fields.size() < 4 || fields[0] == "x") continue;
      std::vector<double> values;
      for (size_t k = 3; k < fields.size(); ++k) values.push_back(std::stod(fields[k]));
      rows.push_back(values);
    }
    return rows;
  }

  TempDir dir_;
};

TEST_F(Shadowmask, EveryTexelIsTheQueryAtItsCentresPointOneChannelPerLight) {
  const CommandResult r = Run("-o " + dir_.File("out") + " --texels-per-unit 8");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // 8 texels a unit over the 6-unit ground: 48 a side; the card has no UVs and is named.
  EXPECT_THAT(r.out, HasSubstr("ground: 48x48, UV set 1"));
  EXPECT_THAT(r.out, HasSubstr("patch: 8x8, UV set 0"));
  EXPECT_THAT(r.err, HasSubstr("node \"card\" has no UVs"));

  absl::StatusOr<ShadowmaskImage> image =
      ReadShadowmaskExr(dir_.File("out/ground-shadowmask0.exr"));
  ASSERT_TRUE(image.ok()) << image.status();
  ASSERT_EQ(image->width, 48);
  ASSERT_EQ(image->height, 48);
  EXPECT_EQ(image->lights, (std::vector<std::string>{"lamp", "sun"}));
  EXPECT_FALSE(image->visibility);

  std::vector<glm::dvec3> points;
  for (int row = 0; row < 48; ++row) {
    for (int column = 0; column < 48; ++column) {
      points.push_back(GroundPoint((column + 0.5) / 48, (row + 0.5) / 48));
    }
  }
  const std::vector<std::vector<double>> expected = Query(points);
  ASSERT_EQ(expected.size(), points.size());
  int umbra = 0, penumbra = 0, sun_shadow = 0;
  for (size_t t = 0; t < points.size(); ++t) {
    ASSERT_EQ(expected[t].size(), 2u);
    for (int light = 0; light < 2; ++light) {
      ASSERT_FALSE(std::isnan(expected[t][light])) << t;
      ASSERT_NEAR(image->values[t * 2 + light], expected[t][light], 1e-6)
          << "texel " << t % 48 << "," << t / 48 << " light " << light;
    }
    umbra += expected[t][0] > 0.99;
    penumbra += expected[t][0] > 0.05 && expected[t][0] < 0.95;
    sun_shadow += expected[t][1] > 0.5;
  }
  // The texture shows the card's shadows (so the comparison is not of empty images): an
  // umbra and a penumbra under the lamp, and the sun's shadow.
  EXPECT_GT(umbra, 20);
  EXPECT_GT(penumbra, 20);
  EXPECT_GT(sun_shadow, 20);

  // The PNG: R = lamp, G = sun, B unused, 8-bit linear.
  const Rgb png = ReadRgbPng(dir_.File("out/ground-shadowmask0.png"));
  ASSERT_EQ(png.width, 48);
  ASSERT_EQ(png.rgb.size(), 48u * 48u * 3u);
  for (size_t t = 0; t < points.size(); ++t) {
    for (int light = 0; light < 2; ++light) {
      ASSERT_NEAR(png.rgb[3 * t + light], 255.0 * expected[t][light], 0.5 + 1e-6) << t;
    }
    ASSERT_EQ(png.rgb[3 * t + 2], 0);
  }

  const std::string manifest = ReadBytes(dir_.File("out/shadowmask.json"));
  EXPECT_THAT(manifest, HasSubstr(R"("channels": {"R": "lamp", "G": "sun"})"));
  EXPECT_THAT(manifest, HasSubstr(R"("lights": ["lamp", "sun"])"));
  EXPECT_THAT(manifest, HasSubstr(R"(node \"card\": no UVs)"));
}

TEST_F(Shadowmask, VisibilityStoresOneMinusTheAttenuationAndOneLightIsGray) {
  ASSERT_EQ(Run("-o " + dir_.File("a") + " --texels-per-unit 4 --light lamp").exit_code, 0);
  const CommandResult r =
      Run("-o " + dir_.File("v") + " --texels-per-unit 4 --light lamp --visibility");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  absl::StatusOr<ShadowmaskImage> a = ReadShadowmaskExr(dir_.File("a/ground-shadowmask0.exr"));
  absl::StatusOr<ShadowmaskImage> v = ReadShadowmaskExr(dir_.File("v/ground-shadowmask0.exr"));
  ASSERT_TRUE(a.ok() && v.ok());
  EXPECT_EQ(a->lights, std::vector<std::string>{"lamp"});
  EXPECT_TRUE(v->visibility);
  ASSERT_EQ(a->values.size(), v->values.size());
  int shadowed = 0;
  for (size_t t = 0; t < a->values.size(); ++t) {
    ASSERT_NEAR(v->values[t], 1.0f - a->values[t], 1e-7);
    shadowed += a->values[t] > 0.5;
  }
  EXPECT_GT(shadowed, 0);
  // One light: a gray PNG.
  png_image image;
  std::memset(&image, 0, sizeof(image));
  image.version = PNG_IMAGE_VERSION;
  ASSERT_TRUE(
      png_image_begin_read_from_file(&image, dir_.File("a/ground-shadowmask0.png").c_str()));
  EXPECT_EQ(image.format, static_cast<png_uint_32>(PNG_FORMAT_GRAY));
  png_image_free(&image);
}

TEST_F(Shadowmask, PointsALightDoesNotReachAreNotHidden) {
  // The lamp alone, its PDSM's window narrowed to tangents of 0.3: at the ground (4 below) a
  // 2.4-unit square of the 6-unit ground; the rest is outside (NaN in a query).
  WriteText(dir_.File("narrow.json"),
            R"({"name": "narrow", "meshes": [{"path": "world.gltf"}],
  "lights": [{"name": "lamp", "rect": {"center": [0, 4, 0.2], "normal": [0, -1, 0],
                                       "up": [0, 0, 1], "size": [0.6, 0.6]}}],
  "bake": {"resolution": [32, 32], "samples": 8, "tileSize": 16,
           "frustum": {"window": [-0.3, 0.3, -0.3, 0.3], "depthRange": [1, 10]}}})");
  ASSERT_EQ(RunCommand(kPdsm + " bake " + dir_.File("narrow.json") + " -o " +
                           dir_.File("narrow.exr") + " --no-preview",
                       dir_)
                .exit_code,
            0);
  const auto shadowmask = [&](const std::string& out, const std::string& flags) {
    return RunCommand(kPdsm + " shadowmask " + dir_.File("narrow.json") + " --pdsm " +
                          dir_.File("narrow.exr") + " -o " + dir_.File(out) +
                          " --texels-per-unit 4 " + flags,
                      dir_);
  };
  const CommandResult r = shadowmask("a", "");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("texels lie outside a light's PDSM"));
  ASSERT_EQ(shadowmask("v", "--visibility").exit_code, 0);
  absl::StatusOr<ShadowmaskImage> a = ReadShadowmaskExr(dir_.File("a/ground-shadowmask0.exr"));
  absl::StatusOr<ShadowmaskImage> v = ReadShadowmaskExr(dir_.File("v/ground-shadowmask0.exr"));
  ASSERT_TRUE(a.ok() && v.ok());
  ASSERT_EQ(a->width, 24);
  std::vector<glm::dvec3> points;
  for (int row = 0; row < 24; ++row) {
    for (int column = 0; column < 24; ++column) {
      points.push_back(GroundPoint((column + 0.5) / 24, (row + 0.5) / 24));
    }
  }
  std::ostringstream csv;
  csv.precision(17);
  for (const glm::dvec3& p : points) csv << p.x << "," << p.y << "," << p.z << "\n";
  WriteText(dir_.File("points.csv"), csv.str());
  const CommandResult q = RunCommand(
      kPdsm + " query " + dir_.File("narrow.exr") + " --points " + dir_.File("points.csv"), dir_);
  ASSERT_EQ(q.exit_code, 0) << q.err;
  std::vector<double> expected;
  for (absl::string_view line : absl::StrSplit(q.out, '\n', absl::SkipEmpty())) {
    const std::vector<std::string> fields = absl::StrSplit(line, ',');
    if (fields.size() == 4 && fields[0] != "x") expected.push_back(std::stod(fields[3]));
  }
  ASSERT_EQ(expected.size(), points.size());
  int outside = 0, shadowed = 0;
  for (size_t t = 0; t < points.size(); ++t) {
    if (std::isnan(expected[t])) {
      ++outside;
      ASSERT_EQ(a->values[t], 0.0f) << t;  // not hidden
      ASSERT_EQ(v->values[t], 1.0f) << t;  // fully visible
    } else {
      ASSERT_NEAR(a->values[t], expected[t], 1e-6) << t;
      ASSERT_NEAR(v->values[t], 1.0 - expected[t], 1e-6) << t;
      shadowed += expected[t] > 0.5;
    }
  }
  // Both kinds of texel are there: most of the ground is outside, the card's umbra inside.
  EXPECT_GT(outside, 200);
  EXPECT_GT(shadowed, 10);
  EXPECT_THAT(r.err, HasSubstr(absl::StrCat(outside, " texels lie outside")));
}

TEST_F(Shadowmask, AnotherScenesPdsmAndBadOptionsAreNamed) {
  std::string other = kSceneJson;
  other.replace(other.find("lightmapped"), 11, "elsewhere");
  WriteText(dir_.File("other.json"), other);
  CommandResult r = RunCommand(kPdsm + " shadowmask " + dir_.File("other.json") + " --pdsm " +
                                   dir_.File("baked.exr") + " -o " + dir_.File("x"),
                               dir_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("baked from scene \"lightmapped\", not \"elsewhere\""));
  EXPECT_THAT(r.err, HasSubstr("--allow-mismatch"));

  r = Run("-o " + dir_.File("x") + " --texels-per-unit 0");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("--texels-per-unit: must be a finite number > 0"));
  r = Run("-o " + dir_.File("x") + " --light moon");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("moon"));

  // A scene whose receivers have no UVs at all.
  WriteText(dir_.File("plain.json"), kTinySceneJson);
  r = RunCommand(kPdsm + " shadowmask " + dir_.File("plain.json") + " --pdsm " +
                     dir_.File("baked.exr") + " -o " + dir_.File("x") + " --allow-mismatch",
                 dir_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("no receiving mesh has UVs"));
}

}  // namespace
}  // namespace pdsm::testing
