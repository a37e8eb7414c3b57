#include "client/export/shadowmask.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <system_error>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "client/export/receiver_objects.h"
#include "client/export/uv_raster.h"
#include "core/pdsm/exr_output_stream.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_lights.h"
#include "core/util/atomic_file.h"
#include "core/util/png_writer.h"
#include "core/util/process_log.h"

namespace pdsm {
namespace {

constexpr const char* kChannelNames[kLightsPerShadowmask] = {"R", "G", "B", "A"};
// Points per AttenuationAt call: bounds the answers held at once (8 bytes a value).
constexpr size_t kPointsPerQuery = size_t{1} << 20;

absl::Status CheckOptions(const ShadowmaskOptions& o) {
  if (!std::isfinite(o.texels_per_unit) || !(o.texels_per_unit > 0)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--texels-per-unit: must be a finite number > 0 (got ", o.texels_per_unit, ")"));
  }
  if (o.max_size < 1 || o.max_size > kMaxShadowmaskSize) {
    return absl::InvalidArgumentError(absl::StrCat("--max-size: must be in [1, ",
                                                   kMaxShadowmaskSize, "] (got ", o.max_size, ")"));
  }
  if (o.dilate < 0) {
    return absl::InvalidArgumentError(absl::StrCat("--dilate: must be >= 0 (got ", o.dilate, ")"));
  }
  return absl::OkStatus();
}

// "R=sun G=lamp": which light each channel of a texture holds.
std::string ChannelMap(const std::vector<std::string>& lights) {
  std::vector<std::string> entries;
  for (size_t c = 0; c < lights.size(); ++c)
    entries.push_back(absl::StrCat(kChannelNames[c], "=", lights[c]));
  return absl::StrJoin(entries, " ");
}

absl::Status WriteExr(const std::string& path, int size, const std::vector<std::string>& lights,
                      bool visibility, const std::vector<float>& values) {
  const int channels = static_cast<int>(lights.size());
  Imf::Header header(size, size);
  header.compression() = Imf::ZIP_COMPRESSION;
  for (int c = 0; c < channels; ++c)
    header.channels().insert(kChannelNames[c], Imf::Channel(Imf::FLOAT));
  header.insert("pdsmShadowmask", Imf::StringAttribute(ChannelMap(lights)));
  header.insert("pdsmStores", Imf::StringAttribute(visibility ? "visibility" : "attenuation"));
  absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(path);
  if (!file.ok()) return file.status();
  {
    ExrOutputStream stream(file->get());
    try {
      Imf::OutputFile out(stream, header);
      Imf::FrameBuffer frame;
      for (int c = 0; c < channels; ++c) {
        frame.insert(
            kChannelNames[c],
            Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(values.data() + c)),
                       sizeof(float) * channels, sizeof(float) * channels * size));
      }
      out.setFrameBuffer(frame);
      out.writePixels(size);
    } catch (const std::exception& e) {
      if (!stream.error().ok()) return stream.error();
      return absl::InternalError(absl::StrCat(path, ": OpenEXR: ", e.what()));
    }
    if (!stream.error().ok()) return stream.error();
  }
  return (*file)->Commit();
}

// Gray for one light, RGB for two or three (unused channels 0), RGBA for four.
absl::Status WritePngFile(const std::string& path, int size, int lights,
                          const std::vector<float>& values) {
  const int channels = lights == 1 ? 1 : (lights == 4 ? 4 : 3);
  const size_t texels = static_cast<size_t>(size) * size;
  std::vector<uint8_t> pixels(texels * channels, 0);
  for (size_t t = 0; t < texels; ++t) {
    for (int c = 0; c < lights; ++c) {
      const double v = std::clamp(static_cast<double>(values[t * lights + c]), 0.0, 1.0);
      pixels[t * channels + c] = static_cast<uint8_t>(std::lround(255.0 * v));
    }
  }
  return WritePng(path, size, size, channels, pixels);
}

std::string Quoted(const std::string& s) { return absl::StrCat("\"", JsonEscapedForLog(s), "\""); }

std::string ManifestJson(const std::string& scene_path, const std::string& pdsm_path,
                         const ShadowmaskOptions& options, const ShadowmaskReport& report) {
  std::vector<std::string> lights, textures, skipped;
  for (const std::string& l : report.lights) lights.push_back(Quoted(l));
  for (const ShadowmaskTexture& t : report.textures) {
    std::vector<std::string> files;
    for (const ShadowmaskFile& f : t.files) {
      std::vector<std::string> channels;
      for (size_t c = 0; c < f.lights.size(); ++c) {
        channels.push_back(absl::StrCat(Quoted(kChannelNames[c]), ": ", Quoted(f.lights[c])));
      }
      files.push_back(absl::StrCat("{\"exr\": ", Quoted(f.exr), ", \"png\": ", Quoted(f.png),
                                   ", \"channels\": {", absl::StrJoin(channels, ", "), "}}"));
    }
    textures.push_back(absl::StrCat(
        "    {\"object\": ", Quoted(t.object), ", \"source\": ", Quoted(t.source),
        ", \"uvSet\": ", t.uv_set, ", \"size\": ", t.size,
        ", \"clamped\": ", t.clamped ? "true" : "false", ", \"texelsCovered\": ", t.texels_covered,
        ", \"files\": [", absl::StrJoin(files, ", "), "]}"));
  }
  for (const std::string& s : report.without_uvs) skipped.push_back(Quoted(s + ": no UVs"));
  for (const std::string& s : report.without_area) skipped.push_back(Quoted(s + ": no UV area"));
  return absl::StrCat(
      "{\n  \"scene\": ", Quoted(scene_path), ",\n  \"pdsm\": ", Quoted(pdsm_path),
      ",\n  \"stores\": ", Quoted(options.visibility ? "visibility" : "attenuation"),
      ",\n  \"texelsPerUnit\": ", options.texels_per_unit, ",\n  \"dilate\": ", options.dilate,
      ",\n  \"lights\": [", absl::StrJoin(lights, ", "), "],\n  \"textures\": [\n",
      absl::StrJoin(textures, ",\n"), "\n  ],\n  \"skipped\": [", absl::StrJoin(skipped, ", "),
      "]\n}\n");
}

// One object's textures: rasterise its charts, query its covered texels' points for every
// light (a group of four at a time), dilate, write.
absl::Status WriteObject(const ReceiverObject& object, int size, const ShadowmaskOptions& options,
                         PdsmTileCache& cache, const std::vector<PdsmLightParts>& lights,
                         const std::string& out_dir, ShadowmaskTexture* texture) {
  const ChartRaster raster =
      RasterizeCharts(object.positions_world, object.indices, object.uvs, size, size);
  const size_t texels = static_cast<size_t>(size) * size;
  std::vector<size_t> covered_texels;
  for (size_t t = 0; t < texels; ++t) {
    if (raster.coverage[t] != TexelCoverage::kNone) covered_texels.push_back(t);
  }
  texture->texels_covered = static_cast<int64_t>(covered_texels.size());
  std::vector<uint8_t> outside(texels, 0);
  std::vector<glm::dvec3> points;
  for (size_t first = 0; first < lights.size(); first += kLightsPerShadowmask) {
    const size_t count = std::min<size_t>(kLightsPerShadowmask, lights.size() - first);
    const std::span<const PdsmLightParts> group(lights.data() + first, count);
    std::vector<float> values(texels * count, 0.0f);
    for (size_t begin = 0; begin < covered_texels.size(); begin += kPointsPerQuery) {
      const size_t end = std::min(covered_texels.size(), begin + kPointsPerQuery);
      points.clear();
      for (size_t k = begin; k < end; ++k) points.push_back(raster.points[covered_texels[k]]);
      absl::StatusOr<std::vector<double>> answers = AttenuationAt(cache, group, points);
      if (!answers.ok()) return answers.status();
      for (size_t k = begin; k < end; ++k) {
        const size_t t = covered_texels[k];
        for (size_t c = 0; c < count; ++c) {
          double a = (*answers)[(k - begin) * count + c];
          if (std::isnan(a)) {
            outside[t] = 1;
            a = 0;  // not hidden: the light does not reach there, the engine's falloff decides
          }
          values[t * count + c] = static_cast<float>(options.visibility ? 1.0 - a : a);
        }
      }
    }
    std::vector<uint8_t> covered(texels, 0);
    for (size_t t : covered_texels) covered[t] = 1;
    DilateCharts(size, size, static_cast<int>(count), options.dilate, &values, &covered);
    if (first == 0) {
      texture->texels_dilated =
          std::count(covered.begin(), covered.end(), uint8_t{1}) - texture->texels_covered;
    }
    ShadowmaskFile file;
    const std::string stem =
        ShadowmaskFileStem(object.name, static_cast<int>(first / kLightsPerShadowmask));
    file.exr = stem + ".exr";
    file.png = stem + ".png";
    for (const PdsmLightParts& l : group) file.lights.push_back(l.name);
    const std::string dir = out_dir.empty() ? std::string(".") : out_dir;
    if (absl::Status s = WriteExr((std::filesystem::path(dir) / file.exr).string(), size,
                                  file.lights, options.visibility, values);
        !s.ok()) {
      return s;
    }
    if (absl::Status s = WritePngFile((std::filesystem::path(dir) / file.png).string(), size,
                                      static_cast<int>(count), values);
        !s.ok()) {
      return s;
    }
    texture->files.push_back(std::move(file));
  }
  texture->texels_outside = std::count(outside.begin(), outside.end(), uint8_t{1});
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<ShadowmaskReport> WriteShadowmasks(const std::string& scene_path,
                                                  const std::string& pdsm_path,
                                                  const std::string& out_dir,
                                                  const ShadowmaskOptions& options,
                                                  std::vector<std::string>* warnings) {
  if (absl::Status s = CheckOptions(options); !s.ok()) return s;
  absl::StatusOr<ReceiverObjects> objects = LoadReceiverObjects(scene_path);
  if (!objects.ok()) return objects.status();
  ShadowmaskReport report;
  report.without_uvs = objects->without_uvs;
  if (objects->objects.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat(scene_path,
                     ": no receiving mesh has UVs (a shadowmask texture is laid out in a mesh's "
                     "second UV set, glTF TEXCOORD_1, or its first when it has one)"));
  }
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(pdsm_path);
  if (!reader.ok()) return reader.status();
  if (const std::string& baked = reader->headers().front().scene_name;
      baked != objects->scene_name) {
    const std::string message =
        absl::StrCat(pdsm_path, ": baked from scene \"", baked, "\", not \"", objects->scene_name,
                     "\" (", scene_path, ")");
    if (!options.allow_mismatch) {
      return absl::FailedPreconditionError(absl::StrCat(message, "; --allow-mismatch to go on"));
    }
    warnings->push_back(message);
  }
  absl::StatusOr<std::vector<PdsmLightParts>> lights =
      SelectLights(reader->headers(), reader->path(), options.light);
  if (!lights.ok()) return lights.status();
  for (const PdsmLightParts& l : *lights) report.lights.push_back(l.name);
  PdsmTileCache cache(*std::move(reader), options.cache_bytes);

  std::error_code ec;
  if (!out_dir.empty()) std::filesystem::create_directories(out_dir, ec);
  if (ec) {
    return absl::InvalidArgumentError(
        absl::StrCat(out_dir, ": cannot create the output folder: ", ec.message()));
  }
  for (const ReceiverObject& object : objects->objects) {
    ShadowmaskTexture texture;
    texture.object = object.name;
    texture.source = object.source;
    texture.uv_set = object.uv_set;
    const int side =
        TextureSideFor(object.positions_world, object.indices, object.uvs, options.texels_per_unit);
    if (side == 0) {
      report.without_area.push_back(object.source);
      continue;
    }
    texture.size = std::min(side, options.max_size);
    texture.clamped = side > options.max_size;
    if (absl::Status s =
            WriteObject(object, texture.size, options, cache, *lights, out_dir, &texture);
        !s.ok()) {
      return s;
    }
    report.textures.push_back(std::move(texture));
  }
  const std::string manifest =
      (std::filesystem::path(out_dir.empty() ? std::string(".") : out_dir) / "shadowmask.json")
          .string();
  if (absl::Status s =
          WriteFileAtomically(manifest, ManifestJson(scene_path, pdsm_path, options, report));
      !s.ok()) {
    return s;
  }
  return report;
}

std::string ShadowmaskFileStem(const std::string& object, int group) {
  return absl::StrCat(object, "-shadowmask", group);
}

absl::StatusOr<ShadowmaskImage> ReadShadowmaskExr(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return absl::NotFoundError(absl::StrCat(path, ": no such shadowmask file"));
  }
  ShadowmaskImage image;
  try {
    Imf::InputFile in(path.c_str());
    const auto* map = in.header().findTypedAttribute<Imf::StringAttribute>("pdsmShadowmask");
    if (map == nullptr) {
      return absl::InvalidArgumentError(
          absl::StrCat(path, ": not a pdsm shadowmask (no pdsmShadowmask attribute)"));
    }
    const auto* stores = in.header().findTypedAttribute<Imf::StringAttribute>("pdsmStores");
    image.visibility = stores != nullptr && stores->value() == "visibility";
    for (absl::string_view entry : absl::StrSplit(map->value(), ' ', absl::SkipEmpty())) {
      const size_t equals = entry.find('=');
      if (equals == absl::string_view::npos || image.lights.size() >= kLightsPerShadowmask ||
          entry.substr(0, equals) != kChannelNames[image.lights.size()]) {
        return absl::InvalidArgumentError(
            absl::StrCat(path, ": pdsmShadowmask: malformed channel map \"", map->value(), "\""));
      }
      image.lights.emplace_back(entry.substr(equals + 1));
    }
    const Imath::Box2i window = in.header().dataWindow();
    image.width = window.max.x - window.min.x + 1;
    image.height = window.max.y - window.min.y + 1;
    const size_t channels = image.lights.size();
    if (channels == 0 || image.width <= 0 || image.height <= 0) {
      return absl::InvalidArgumentError(absl::StrCat(path, ": an empty shadowmask"));
    }
    image.values.assign(static_cast<size_t>(image.width) * image.height * channels, 0.0f);
    Imf::FrameBuffer frame;
    char* base = reinterpret_cast<char*>(image.values.data()) -
                 (static_cast<ptrdiff_t>(window.min.x) +
                  static_cast<ptrdiff_t>(window.min.y) * image.width) *
                     static_cast<ptrdiff_t>(sizeof(float) * channels);
    for (size_t c = 0; c < channels; ++c) {
      frame.insert(kChannelNames[c],
                   Imf::Slice(Imf::FLOAT, base + c * sizeof(float), sizeof(float) * channels,
                              sizeof(float) * channels * image.width));
    }
    in.setFrameBuffer(frame);
    in.readPixels(window.min.y, window.max.y);
  } catch (const std::exception& e) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": OpenEXR: ", e.what()));
  }
  return image;
}

}  // namespace pdsm
