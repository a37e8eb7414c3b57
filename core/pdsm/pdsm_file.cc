#include "core/pdsm/pdsm_file.h"

#include <OpenEXR/IexBaseExc.h>
#include <OpenEXR/IexErrnoExc.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfCompression.h>
#include <OpenEXR/ImfDeepFrameBuffer.h>
#include <OpenEXR/ImfDeepTiledInputFile.h>
#include <OpenEXR/ImfDeepTiledInputPart.h>
#include <OpenEXR/ImfDeepTiledOutputFile.h>
#include <OpenEXR/ImfDoubleAttribute.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfTileDescription.h>
#include <OpenEXR/ImfVecAttribute.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <new>
#include <optional>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "absl/strings/escaping.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/string_view.h"
#include "core/pdsm/exr_output_stream.h"
#include "core/util/atomic_file.h"
#include "core/util/file_system.h"

namespace pdsm {
namespace {

// Header attribute names (docs/pdsm_format.md). OpenEXR limits names to 31 characters.
constexpr char kAttrFormatVersion[] = "pdsmFormatVersion";
constexpr char kAttrAttenuationChannel[] = "pdsmAttenuationChannel";
constexpr char kAttrSceneName[] = "pdsmSceneName";
constexpr char kAttrLightShape[] = "pdsmLightShape";
constexpr char kAttrLightHalfWidth[] = "pdsmLightHalfWidth";
constexpr char kAttrLightHalfHeight[] = "pdsmLightHalfHeight";
constexpr char kAttrLightRadius[] = "pdsmLightRadius";
constexpr char kAttrLightTanHalfAngle[] = "pdsmLightTanHalfAngle";
constexpr char kAttrLightCenter[] = "pdsmLightCenter";
constexpr char kAttrLightU[] = "pdsmLightU";
constexpr char kAttrLightV[] = "pdsmLightV";
constexpr char kAttrLightN[] = "pdsmLightN";
constexpr char kAttrProjection[] = "pdsmProjection";
constexpr char kAttrWindowMin[] = "pdsmWindowMin";
constexpr char kAttrWindowMax[] = "pdsmWindowMax";
constexpr char kAttrZNear[] = "pdsmZNear";
constexpr char kAttrZFar[] = "pdsmZFar";
constexpr char kAttrSamples[] = "pdsmSamples";
constexpr char kAttrShadowMapResolution[] = "pdsmShadowMapResolution";
constexpr char kAttrEpsilon[] = "pdsmEpsilon";
constexpr char kAttrCompressionMetric[] = "pdsmCompressionMetric";
constexpr char kAttrDepthBias[] = "pdsmDepthBias";
constexpr char kAttrSlopeBias[] = "pdsmSlopeBias";
constexpr char kAttrSampling[] = "pdsmSampling";
constexpr char kAttrSeed[] = "pdsmSeed";
constexpr char kAttrTileSize[] = "pdsmTileSize";
// Adaptive bakes only (absent otherwise, so fixed-count files are unchanged).
constexpr char kAttrAdaptiveTolerance[] = "pdsmAdaptiveTolerance";
constexpr char kAttrAdaptiveMinSamples[] = "pdsmAdaptiveMinSamples";
constexpr char kAttrTileSamples[] = "pdsmTileSamples";
// Optional attributes (written only when not at their default; absent reads as the default).
constexpr char kAttrZValidMin[] = "pdsmZValidMin";
constexpr char kAttrSurfacesOnly[] = "pdsmSurfacesOnly";

constexpr char kDepthChannel[] = "Z";
constexpr char kAttenuationChannel[] = "attenuation";
constexpr char kAttenuationNote[] =
    "channel 'attenuation' = A(z), the fraction of the light hidden from the point at depth "
    "Z on this pixel's ray (0 lit, 1 umbra); piecewise linear between samples, not "
    "monotonic, not alpha: do not composite";

// The sample count table of a deep tile holds cumulative int32 counts, and OpenEXR sizes a
// tile's unpacked data with an int: keep both within range.
constexpr uint64_t kMaxVerticesPerTile =
    static_cast<uint64_t>(std::numeric_limits<int32_t>::max()) / (2 * sizeof(float));

// ---------------------------------------------------------------------------------------
// Enum <-> attribute string.

template <typename E>
struct EnumName {
  E value;
  std::string_view name;
};

constexpr EnumName<Projection> kProjectionNames[] = {{Projection::kPerspective, "perspective"},
                                                     {Projection::kOrthographic, "orthographic"}};
constexpr EnumName<LightShape> kLightShapeNames[] = {
    {LightShape::kRect, "rect"}, {LightShape::kDisk, "disk"}, {LightShape::kSun, "sun"}};
constexpr EnumName<CompressionMetric> kMetricNames[] = {
    {CompressionMetric::kVertical, "vertical"},
    {CompressionMetric::kPerpendicular, "perpendicular"}};
constexpr EnumName<SamplingPattern> kSamplingNames[] = {
    {SamplingPattern::kStratified, "stratified"}, {SamplingPattern::kUniform, "uniform"},
    {SamplingPattern::kSobol, "sobol"},           {SamplingPattern::kHalton, "halton"},
    {SamplingPattern::kBlueNoise, "blue_noise"}};

template <typename E, size_t N>
std::string NameOf(const EnumName<E> (&table)[N], E value) {
  for (const auto& entry : table) {
    if (entry.value == value) return std::string(entry.name);
  }
  return "unknown";
}

template <typename E, size_t N>
std::optional<E> ValueOf(const EnumName<E> (&table)[N], std::string_view name) {
  for (const auto& entry : table) {
    if (entry.name == name) return entry.value;
  }
  return std::nullopt;
}

Imath::V3d ToImath(const glm::dvec3& v) { return {v.x, v.y, v.z}; }
glm::dvec3 ToGlm(const Imath::V3d& v) { return {v.x, v.y, v.z}; }

// ---------------------------------------------------------------------------------------
// Exceptions -> Status. OpenEXR reports everything by throwing; nothing escapes this file.

absl::Status StatusFromCurrentException(absl::string_view path, absl::string_view action) {
  try {
    throw;
  } catch (const Iex::EnoentExc& e) {
    return absl::NotFoundError(absl::StrCat(action, " ", path, ": ", e.what()));
  } catch (const Iex::EaccesExc& e) {
    return absl::PermissionDeniedError(absl::StrCat(action, " ", path, ": ", e.what()));
  } catch (const std::bad_alloc&) {
    return absl::ResourceExhaustedError(
        absl::StrCat(action, " ", path, ": out of memory (corrupt sample counts?)"));
  } catch (const std::exception& e) {
    return absl::DataLossError(absl::StrCat(action, " ", path, ": ", e.what()));
  } catch (...) {
    return absl::DataLossError(absl::StrCat(action, " ", path, ": unknown exception"));
  }
}

// ---------------------------------------------------------------------------------------
// Header <-> attributes.

Imf::Header ExrHeaderFromPdsm(const PdsmHeader& h) {
  const PdsmGeometry& g = h.geometry;
  Imf::Header exr(g.width, g.height);  // data and display windows [0, w-1] x [0, h-1]
  exr.setType(Imf::DEEPTILE);
  exr.compression() = Imf::ZIPS_COMPRESSION;  // deep allows only NONE, RLE, ZIPS
  exr.lineOrder() = Imf::INCREASING_Y;
  exr.setTileDescription(Imf::TileDescription(h.tile_size, h.tile_size, Imf::ONE_LEVEL));
  exr.channels().insert(kDepthChannel, Imf::Channel(Imf::FLOAT));
  exr.channels().insert(kAttenuationChannel, Imf::Channel(Imf::FLOAT));

  exr.insert(kAttrFormatVersion, Imf::IntAttribute(h.format_version));
  exr.insert(kAttrAttenuationChannel, Imf::StringAttribute(kAttenuationNote));
  exr.insert(kAttrSceneName, Imf::StringAttribute(h.scene_name));
  exr.insert(kAttrLightShape, Imf::StringAttribute(NameOf(kLightShapeNames, h.light_shape)));
  exr.insert(kAttrLightHalfWidth, Imf::DoubleAttribute(h.light_half_width));
  exr.insert(kAttrLightHalfHeight, Imf::DoubleAttribute(h.light_half_height));
  exr.insert(kAttrLightRadius, Imf::DoubleAttribute(h.light_radius));
  exr.insert(kAttrLightTanHalfAngle, Imf::DoubleAttribute(h.tan_half_angle));
  exr.insert(kAttrLightCenter, Imf::V3dAttribute(ToImath(g.frame.center)));
  exr.insert(kAttrLightU, Imf::V3dAttribute(ToImath(g.frame.u)));
  exr.insert(kAttrLightV, Imf::V3dAttribute(ToImath(g.frame.v)));
  exr.insert(kAttrLightN, Imf::V3dAttribute(ToImath(g.frame.n)));
  exr.insert(kAttrProjection, Imf::StringAttribute(NameOf(kProjectionNames, g.projection)));
  exr.insert(kAttrWindowMin, Imf::V2dAttribute(Imath::V2d(g.s_min, g.t_min)));
  exr.insert(kAttrWindowMax, Imf::V2dAttribute(Imath::V2d(g.s_max, g.t_max)));
  exr.insert(kAttrZNear, Imf::DoubleAttribute(g.z_near));
  exr.insert(kAttrZFar, Imf::DoubleAttribute(g.z_far));
  exr.insert(kAttrSamples, Imf::IntAttribute(h.samples));
  exr.insert(kAttrShadowMapResolution, Imf::IntAttribute(h.shadow_map_resolution));
  exr.insert(kAttrEpsilon, Imf::DoubleAttribute(h.epsilon));
  exr.insert(kAttrCompressionMetric,
             Imf::StringAttribute(NameOf(kMetricNames, h.compression_metric)));
  exr.insert(kAttrDepthBias, Imf::DoubleAttribute(h.depth_bias));
  exr.insert(kAttrSlopeBias, Imf::DoubleAttribute(h.slope_bias));
  exr.insert(kAttrSampling, Imf::StringAttribute(NameOf(kSamplingNames, h.sampling)));
  // EXR has no 64-bit integer attribute: decimal text keeps all 64 bits.
  exr.insert(kAttrSeed, Imf::StringAttribute(absl::StrCat(h.seed)));
  exr.insert(kAttrTileSize, Imf::IntAttribute(h.tile_size));
  if (h.adaptive()) {
    exr.insert(kAttrAdaptiveTolerance, Imf::DoubleAttribute(h.adaptive_tolerance));
    exr.insert(kAttrAdaptiveMinSamples, Imf::IntAttribute(h.adaptive_min_samples));
    // Decimal counts, comma-separated, row-major tile order (EXR has no int-vector type).
    exr.insert(kAttrTileSamples, Imf::StringAttribute(absl::StrJoin(h.tile_samples, ",")));
  }
  if (g.z_valid_min != 0) exr.insert(kAttrZValidMin, Imf::DoubleAttribute(g.z_valid_min));
  if (h.surfaces_only) exr.insert(kAttrSurfacesOnly, Imf::IntAttribute(1));
  return exr;
}

// Reads typed attributes, remembering the first one missing or of the wrong type.
class AttributeReader {
 public:
  AttributeReader(const Imf::Header& exr, absl::string_view path) : exr_(exr), path_(path) {}

  template <typename T>
  T Get(const char* name) {
    const auto* attr = exr_.findTypedAttribute<Imf::TypedAttribute<T>>(name);
    if (attr == nullptr) {
      Fail(absl::StrFormat("attribute %s is missing or not of type %s", name,
                           Imf::TypedAttribute<T>::staticTypeName()));
      return T();
    }
    return attr->value();
  }

  // An optional attribute: `fallback` when absent; of the wrong type is an error.
  template <typename T>
  T GetOptional(const char* name, T fallback) {
    if (exr_.find(name) == exr_.end()) return fallback;
    return Get<T>(name);
  }

  template <typename E, size_t N>
  E GetEnum(const char* name, const EnumName<E> (&table)[N]) {
    const std::string text = Get<std::string>(name);
    const std::optional<E> value = ValueOf(table, text);
    if (!value && status_.ok()) {
      Fail(absl::StrFormat("attribute %s: unknown value \"%s\"", name, absl::CEscape(text)));
    }
    return value.value_or(table[0].value);
  }

  void Fail(absl::string_view message) {
    if (status_.ok()) status_ = absl::DataLossError(absl::StrCat(path_, ": ", message));
  }
  const absl::Status& status() const { return status_; }

 private:
  const Imf::Header& exr_;
  std::string path_;
  absl::Status status_;
};

// Checks what makes the file a PDSM, in the order that gives the most useful message.
absl::Status CheckPdsmLayout(const Imf::Header& exr, absl::string_view path) {
  const auto* version = exr.findTypedAttribute<Imf::IntAttribute>(kAttrFormatVersion);
  if (version == nullptr) {
    return absl::DataLossError(
        absl::StrCat("not a PDSM file: ", path, " (no int attribute ", kAttrFormatVersion, ")"));
  }
  if (version->value() > kPdsmFormatVersion) {
    return absl::FailedPreconditionError(
        absl::StrFormat("%s: PDSM format version %d is newer than this build reads (%d)", path,
                        version->value(), kPdsmFormatVersion));
  }
  if (version->value() < 1) {
    return absl::DataLossError(
        absl::StrFormat("%s: invalid PDSM format version %d", path, version->value()));
  }
  if (!exr.hasType() || exr.type() != Imf::DEEPTILE) {
    return absl::DataLossError(absl::StrCat(path, ": not a deep tiled OpenEXR image"));
  }
  for (const char* name : {kDepthChannel, kAttenuationChannel}) {
    const Imf::Channel* channel = exr.channels().findChannel(name);
    if (channel == nullptr || channel->type != Imf::FLOAT) {
      return absl::DataLossError(absl::StrFormat("%s: no FLOAT channel \"%s\"", path, name));
    }
  }
  const Imath::Box2i& window = exr.dataWindow();
  constexpr int kIntMax = std::numeric_limits<int>::max();
  if (window.min.x != 0 || window.min.y != 0 || window.max.x < 0 || window.max.y < 0 ||
      window.max.x == kIntMax || window.max.y == kIntMax) {
    return absl::DataLossError(
        absl::StrCat(path, ": data window is not [0, width-1] x [0, height-1]"));
  }
  const Imf::TileDescription& tiles = exr.tileDescription();
  if (tiles.mode != Imf::ONE_LEVEL || tiles.xSize != tiles.ySize) {
    return absl::DataLossError(absl::StrCat(path, ": tiles are not square and single-level"));
  }
  return absl::OkStatus();
}

void ReadLight(AttributeReader& in, PdsmHeader* h) {
  h->light_shape = in.GetEnum(kAttrLightShape, kLightShapeNames);
  h->light_half_width = in.Get<double>(kAttrLightHalfWidth);
  h->light_half_height = in.Get<double>(kAttrLightHalfHeight);
  h->light_radius = in.Get<double>(kAttrLightRadius);
  h->tan_half_angle = in.Get<double>(kAttrLightTanHalfAngle);
}

void ReadGeometry(AttributeReader& in, const Imf::Header& exr, PdsmGeometry* g) {
  g->projection = in.GetEnum(kAttrProjection, kProjectionNames);
  g->frame.center = ToGlm(in.Get<Imath::V3d>(kAttrLightCenter));
  g->frame.u = ToGlm(in.Get<Imath::V3d>(kAttrLightU));
  g->frame.v = ToGlm(in.Get<Imath::V3d>(kAttrLightV));
  g->frame.n = ToGlm(in.Get<Imath::V3d>(kAttrLightN));
  g->width = exr.dataWindow().max.x + 1;
  g->height = exr.dataWindow().max.y + 1;
  const Imath::V2d window_min = in.Get<Imath::V2d>(kAttrWindowMin);
  const Imath::V2d window_max = in.Get<Imath::V2d>(kAttrWindowMax);
  g->s_min = window_min.x;
  g->t_min = window_min.y;
  g->s_max = window_max.x;
  g->t_max = window_max.y;
  g->z_near = in.Get<double>(kAttrZNear);
  g->z_far = in.Get<double>(kAttrZFar);
  g->z_valid_min = in.GetOptional<double>(kAttrZValidMin, 0.0);
}

void ReadBakeSettings(AttributeReader& in, const Imf::Header& exr, PdsmHeader* h) {
  h->samples = in.Get<int>(kAttrSamples);
  h->shadow_map_resolution = in.Get<int>(kAttrShadowMapResolution);
  h->epsilon = in.Get<double>(kAttrEpsilon);
  h->compression_metric = in.GetEnum(kAttrCompressionMetric, kMetricNames);
  h->depth_bias = in.Get<double>(kAttrDepthBias);
  h->slope_bias = in.Get<double>(kAttrSlopeBias);
  h->sampling = in.GetEnum(kAttrSampling, kSamplingNames);
  const std::string seed = in.Get<std::string>(kAttrSeed);
  if (in.status().ok() && !absl::SimpleAtoi(seed, &h->seed)) {
    in.Fail(
        absl::StrFormat("attribute %s: \"%s\" is not a uint64", kAttrSeed, absl::CEscape(seed)));
  }
  h->tile_size = in.Get<int>(kAttrTileSize);
  h->surfaces_only = in.GetOptional<int>(kAttrSurfacesOnly, 0) != 0;
  if (in.status().ok() && h->tile_size != static_cast<int>(exr.tileDescription().xSize)) {
    in.Fail(absl::StrFormat("attribute %s = %d disagrees with the EXR tile size %d", kAttrTileSize,
                            h->tile_size, exr.tileDescription().xSize));
  }
}

// The adaptive attributes, when present: one count in [1, samples] per tile.
void ReadAdaptive(AttributeReader& in, const Imf::Header& exr, PdsmHeader* h) {
  if (exr.find(kAttrAdaptiveTolerance) == exr.end()) return;  // a wrong type is Get's error
  h->adaptive_tolerance = in.Get<double>(kAttrAdaptiveTolerance);
  h->adaptive_min_samples = in.Get<int>(kAttrAdaptiveMinSamples);
  const std::string text = in.Get<std::string>(kAttrTileSamples);
  if (!in.status().ok() || h->tile_size <= 0) return;
  const int64_t tiles = ((h->geometry.width + h->tile_size - 1) / h->tile_size) *
                        int64_t{(h->geometry.height + h->tile_size - 1) / h->tile_size};
  const std::vector<absl::string_view> fields = absl::StrSplit(text, ',');
  h->tile_samples.resize(fields.size());
  bool ok = static_cast<int64_t>(fields.size()) == tiles;
  for (size_t t = 0; ok && t < fields.size(); ++t) {
    ok = absl::SimpleAtoi(fields[t], &h->tile_samples[t]) && h->tile_samples[t] >= 1 &&
         h->tile_samples[t] <= h->samples;
  }
  if (!ok) {
    in.Fail(absl::StrFormat("attribute %s: expected %d counts in [1, %d], comma-separated",
                            kAttrTileSamples, tiles, h->samples));
  }
}

absl::StatusOr<PdsmHeader> PdsmHeaderFromExr(const Imf::Header& exr, absl::string_view path) {
  if (absl::Status s = CheckPdsmLayout(exr, path); !s.ok()) return s;
  AttributeReader in(exr, path);
  PdsmHeader h;
  h.format_version = in.Get<int>(kAttrFormatVersion);
  h.scene_name = in.Get<std::string>(kAttrSceneName);
  ReadLight(in, &h);
  ReadGeometry(in, exr, &h.geometry);
  ReadBakeSettings(in, exr, &h);
  ReadAdaptive(in, exr, &h);
  if (!in.status().ok()) return in.status();
  if (h.format_version < MinimumFormatVersion(h)) {
    return absl::DataLossError(absl::StrFormat(
        "%s: %s = %d, but its %s/%s attributes need version %d", path, kAttrFormatVersion,
        h.format_version, kAttrSurfacesOnly, kAttrZValidMin, MinimumFormatVersion(h)));
  }
  return h;
}

absl::Status ValidateHeaderForWrite(const PdsmHeader& h, absl::string_view path) {
  if (h.format_version != MinimumFormatVersion(h)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s: header.format_version = %d, but its features need version %d", path,
                        h.format_version, MinimumFormatVersion(h)));
  }
  if (h.geometry.width <= 0 || h.geometry.height <= 0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s: header.geometry resolution %dx%d is empty", path, h.geometry.width,
                        h.geometry.height));
  }
  if (h.tile_size <= 0 || h.tile_size > kMaxTileSize) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s: header.tile_size = %d, must be in [1, %d]", path, h.tile_size, kMaxTileSize));
  }
  return absl::OkStatus();
}

// ---------------------------------------------------------------------------------------
// Tile grid.

struct TileGrid {
  int width, height, tile_size;

  int64_t TilesX() const { return (width + tile_size - 1) / tile_size; }
  int64_t TilesY() const { return (height + tile_size - 1) / tile_size; }
  int64_t Count() const { return TilesX() * TilesY(); }
  int TileWidth(int x0) const { return std::min(tile_size, width - x0); }
  int TileHeight(int y0) const { return std::min(tile_size, height - y0); }
};

// REQUIRES: tile.offsets has width * height + 1 entries.
absl::Status CheckTileFunctions(const PdsmTile& tile, absl::string_view path) {
  const size_t pixels = static_cast<size_t>(tile.width) * tile.height;
  if (tile.offsets[0] != 0 || tile.offsets[pixels] != tile.vertices.size()) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s: tile (%d, %d): offsets do not span the %d vertices", path, tile.x0,
                        tile.y0, tile.vertices.size()));
  }
  if (tile.vertices.size() > kMaxVerticesPerTile) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s: tile (%d, %d) has %d vertices, more than a deep EXR tile holds (%d)",
                        path, tile.x0, tile.y0, tile.vertices.size(), kMaxVerticesPerTile));
  }
  for (size_t p = 0; p < pixels; ++p) {
    const uint64_t begin = tile.offsets[p], end = tile.offsets[p + 1];
    if (end < begin) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: tile (%d, %d): offsets decrease at pixel %d", path, tile.x0, tile.y0, p));
    }
    for (uint64_t k = begin; k < end; ++k) {
      const float z = tile.vertices[k].z;
      if (std::isnan(z) || (k > begin && z < tile.vertices[k - 1].z)) {
        return absl::InvalidArgumentError(
            absl::StrFormat("%s: pixel (%d, %d): vertex depths are not nondecreasing", path,
                            tile.x0 + static_cast<int>(p % tile.width),
                            tile.y0 + static_cast<int>(p / tile.width)));
      }
    }
  }
  return absl::OkStatus();
}

// Per-pixel sample counts and channel pointers of one tile, as OpenEXR's deep frame
// buffers want them, addressed relative to the tile's corner.
struct DeepTileBuffers {
  std::vector<uint32_t> counts;
  std::vector<char*> z;
  std::vector<char*> a;

  void Resize(size_t pixels) {
    counts.resize(pixels);
    z.resize(pixels);
    a.resize(pixels);
  }

  // Points local pixel p at vertices[begin, end).
  void Set(size_t p, Vertex* vertices, uint64_t begin, uint64_t end) {
    counts[p] = static_cast<uint32_t>(end - begin);
    if (begin == end) {
      z[p] = a[p] = nullptr;  // never read; also keeps an empty vector's null data() out
      return;
    }
    char* vertex = reinterpret_cast<char*>(vertices + begin);
    z[p] = vertex + offsetof(Vertex, z);
    a[p] = vertex + offsetof(Vertex, a);
  }

  Imf::DeepFrameBuffer FrameBuffer(int tile_width) {
    constexpr bool kTileCoords = true;
    Imf::DeepFrameBuffer fb;
    fb.insertSampleCountSlice(Imf::Slice(Imf::UINT, reinterpret_cast<char*>(counts.data()),
                                         sizeof(uint32_t), sizeof(uint32_t) * tile_width, 1, 1, 0.0,
                                         kTileCoords, kTileCoords));
    fb.insert(kDepthChannel, ChannelSlice(z, tile_width));
    fb.insert(kAttenuationChannel, ChannelSlice(a, tile_width));
    return fb;
  }

 private:
  static Imf::DeepSlice ChannelSlice(std::vector<char*>& pointers, int tile_width) {
    return Imf::DeepSlice(Imf::FLOAT, reinterpret_cast<char*>(pointers.data()), sizeof(char*),
                          sizeof(char*) * tile_width, sizeof(Vertex), 1, 1, 0.0, true, true);
  }
};

// ---------------------------------------------------------------------------------------
// Writer.

class ExrPdsmWriter final : public PdsmWriter {
 public:
  ExrPdsmWriter(std::string path, FileSystem* fs, const PdsmHeader& header,
                std::unique_ptr<AtomicFile> file, std::unique_ptr<ExrOutputStream> stream,
                std::unique_ptr<Imf::DeepTiledOutputFile> exr)
      : path_(std::move(path)),
        fs_(fs),
        header_(header),
        grid_{header.geometry.width, header.geometry.height, header.tile_size},
        file_(std::move(file)),
        stream_(std::move(stream)),
        exr_(std::move(exr)) {
    if (header_.adaptive()) header_.tile_samples.assign(grid_.Count(), 0);
  }

  ~ExrPdsmWriter() override {
    // In this order: OpenEXR writes through the stream, the stream through the file; the
    // file removes its temporary unless committed.
    exr_.reset();
    stream_.reset();
    file_.reset();
  }

  absl::Status WriteTile(const PdsmTile& tile) override {
    if (!error_.ok()) return error_;
    if (finished_) return absl::FailedPreconditionError(path_ + ": already finished");
    absl::StatusOr<int64_t> index = CheckTile(tile);
    if (!index.ok()) return index.status();
    if (header_.adaptive()) header_.tile_samples[*index] = tile.samples;
    if (*index != next_tile_) {
      // Out of order: keep it until the tiles before it are written, so that the file's
      // bytes do not depend on the order of arrival.
      pending_.emplace(*index, tile);
      return absl::OkStatus();
    }
    if (absl::Status s = Emit(tile); !s.ok()) return s;
    for (auto it = pending_.find(next_tile_); it != pending_.end();
         it = pending_.find(next_tile_)) {
      if (absl::Status s = Emit(it->second); !s.ok()) return s;
      pending_.erase(it);
    }
    return absl::OkStatus();
  }

  absl::Status Finish() override {
    if (!error_.ok()) return error_;
    if (finished_) return absl::FailedPreconditionError(path_ + ": already finished");
    if (next_tile_ != grid_.Count()) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "%s: %d of %d tiles missing", path_, grid_.Count() - next_tile_, grid_.Count()));
    }
    exr_.reset();  // writes the tile offset table; a failure shows in the file's status
    if (!file_->status().ok()) return Fail(file_->status());
    if (header_.adaptive()) {
      if (absl::Status s = RewriteWithTileSamples(); !s.ok()) return Fail(s);
    }
    if (absl::Status s = file_->Commit(); !s.ok()) return Fail(s);
    finished_ = true;
    return absl::OkStatus();
  }

 private:
  // The tile's index in row-major tile order, or why it is not a tile of the grid.
  absl::StatusOr<int64_t> CheckTile(const PdsmTile& tile) const {
    const int ts = grid_.tile_size;
    if (tile.x0 < 0 || tile.y0 < 0 || tile.x0 >= grid_.width || tile.y0 >= grid_.height ||
        tile.x0 % ts != 0 || tile.y0 % ts != 0 || tile.width != grid_.TileWidth(tile.x0) ||
        tile.height != grid_.TileHeight(tile.y0)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: tile at (%d, %d) size %dx%d is not a cell of the %dx%d grid of %d-pixel tiles",
          path_, tile.x0, tile.y0, tile.width, tile.height, grid_.width, grid_.height, ts));
    }
    const int64_t index = (tile.y0 / ts) * grid_.TilesX() + tile.x0 / ts;
    if (index < next_tile_ || pending_.contains(index)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s: tile (%d, %d) written twice", path_, tile.x0, tile.y0));
    }
    if (tile.offsets.size() != static_cast<size_t>(tile.width) * tile.height + 1) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s: tile (%d, %d) has %d offsets, expected %d", path_, tile.x0, tile.y0,
                          tile.offsets.size(), static_cast<size_t>(tile.width) * tile.height + 1));
    }
    if (absl::Status s = CheckTileFunctions(tile, path_); !s.ok()) return s;
    if (header_.adaptive() && (tile.samples < 1 || tile.samples > header_.samples)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s: tile (%d, %d) of an adaptive bake has %d samples, expected [1, %d]",
                          path_, tile.x0, tile.y0, tile.samples, header_.samples));
    }
    return index;
  }

  // The header went out before any tile, but an adaptive bake knows its tiles' sample counts
  // only at the end: copy the finished tiles' compressed bytes (no decoding) into a second
  // file whose header carries them, and make that the one committed. The first one is
  // dropped (its temporary file removed) once the copy is whole.
  absl::Status RewriteWithTileSamples() {
    if (absl::Status s = file_->Flush(); !s.ok()) return s;
    absl::StatusOr<std::unique_ptr<AtomicFile>> copy_file = AtomicFile::Create(path_, fs_);
    if (!copy_file.ok()) return copy_file.status();
    {
      ExrOutputStream out(copy_file->get());
      try {
        Imf::DeepTiledInputFile in(file_->temp_path().c_str(), Imf::globalThreadCount());
        Imf::DeepTiledOutputFile copy(out, ExrHeaderFromPdsm(header_));
        copy.copyPixels(in);
      } catch (...) {
        if (!out.error().ok()) return out.error();
        return StatusFromCurrentException((*copy_file)->temp_path(), "rewriting");
      }
    }
    // The copy's destructor wrote its offset table: a failure there shows only here.
    if (!(*copy_file)->status().ok()) return (*copy_file)->status();
    stream_.reset();
    file_ = *std::move(copy_file);
    return absl::OkStatus();
  }

  // Hands one tile to OpenEXR. REQUIRES: it is tile next_tile_.
  absl::Status Emit(const PdsmTile& tile) {
    const size_t pixels = static_cast<size_t>(tile.width) * tile.height;
    // OpenEXR only reads through these pointers when writing.
    Vertex* vertices = const_cast<Vertex*>(tile.vertices.data());
    buffers_.Resize(pixels);
    for (size_t p = 0; p < pixels; ++p) {
      buffers_.Set(p, vertices, tile.offsets[p], tile.offsets[p + 1]);
    }
    try {
      exr_->setFrameBuffer(buffers_.FrameBuffer(tile.width));
      exr_->writeTile(tile.x0 / grid_.tile_size, tile.y0 / grid_.tile_size);
    } catch (...) {
      if (!stream_->error().ok()) return Fail(stream_->error());
      return Fail(absl::InternalError(absl::StrCat(
          StatusFromCurrentException(file_->temp_path(), "writing").message(), " (for ", path_,
          ")")));
    }
    ++next_tile_;
    return absl::OkStatus();
  }

  // Makes `status` sticky and drops the file at once: nothing of a failed writer stays on
  // disk while its owner still holds it.
  absl::Status Fail(absl::Status status) {
    error_ = status;
    exr_.reset();
    stream_.reset();
    file_.reset();
    return status;
  }

  const std::string path_;
  FileSystem* const fs_;
  PdsmHeader header_;  // tile_samples filled as tiles arrive (adaptive bakes)
  const TileGrid grid_;
  std::unique_ptr<AtomicFile> file_;  // the rewritten one once RewriteWithTileSamples() ran
  std::unique_ptr<ExrOutputStream> stream_;        // writes to *file_; null after a rewrite
  std::unique_ptr<Imf::DeepTiledOutputFile> exr_;  // writes to *stream_; null once finished
  std::map<int64_t, PdsmTile> pending_;            // out-of-order tiles by index
  int64_t next_tile_ = 0;                          // all tiles before it are written
  DeepTileBuffers buffers_;
  absl::Status error_;  // sticky: after a failure nothing more is written
  bool finished_ = false;
};

// ---------------------------------------------------------------------------------------
// Reader.

absl::Status OpenChecked(const std::string& path, std::unique_ptr<Imf::MultiPartInputFile>* file) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    return absl::NotFoundError(absl::StrCat("no such file: ", path));
  }
  try {
    *file = std::make_unique<Imf::MultiPartInputFile>(path.c_str(), Imf::globalThreadCount(),
                                                      /*reconstructChunkOffsetTable=*/false);
  } catch (...) {
    return StatusFromCurrentException(path, "cannot read");
  }
  return absl::OkStatus();
}

// Sample counts of all pixels, into image->offsets as a prefix sum.
void ReadOffsets(Imf::DeepTiledInputPart& part, PdsmImage* image) {
  const PdsmGeometry& g = image->header.geometry;
  const size_t pixels = static_cast<size_t>(g.width) * g.height;
  std::vector<uint32_t> counts(pixels);
  Imf::DeepFrameBuffer fb;
  fb.insertSampleCountSlice(Imf::Slice(Imf::UINT, reinterpret_cast<char*>(counts.data()),
                                       sizeof(uint32_t), sizeof(uint32_t) * g.width));
  part.setFrameBuffer(fb);
  part.readPixelSampleCounts(0, part.numXTiles(0) - 1, 0, part.numYTiles(0) - 1);
  image->offsets.assign(pixels + 1, 0);
  for (size_t p = 0; p < pixels; ++p) image->offsets[p + 1] = image->offsets[p] + counts[p];
}

// Vertices of all tiles, straight into image->vertices.
void ReadVertices(Imf::DeepTiledInputPart& part, PdsmImage* image) {
  const PdsmGeometry& g = image->header.geometry;
  const TileGrid grid{g.width, g.height, image->header.tile_size};
  image->vertices.resize(image->offsets.back());
  DeepTileBuffers buffers;
  for (int ty = 0; ty < grid.TilesY(); ++ty) {
    for (int tx = 0; tx < grid.TilesX(); ++tx) {
      const int x0 = tx * grid.tile_size, y0 = ty * grid.tile_size;
      const int w = grid.TileWidth(x0), h = grid.TileHeight(y0);
      buffers.Resize(static_cast<size_t>(w) * h);
      for (int y = 0; y < h; ++y) {
        const size_t row = static_cast<size_t>(y0 + y) * g.width + x0;
        for (int x = 0; x < w; ++x) {
          buffers.Set(static_cast<size_t>(y) * w + x, image->vertices.data(),
                      image->offsets[row + x], image->offsets[row + x + 1]);
        }
      }
      part.setFrameBuffer(buffers.FrameBuffer(w));
      part.readTile(tx, ty);
    }
  }
}

absl::Status CheckDepthOrder(const PdsmImage& image, absl::string_view path) {
  const int width = image.header.geometry.width;
  const size_t pixels = image.offsets.size() - 1;
  for (size_t p = 0; p < pixels; ++p) {
    for (uint64_t k = image.offsets[p]; k < image.offsets[p + 1]; ++k) {
      const float z = image.vertices[k].z;
      if (std::isnan(z) || (k > image.offsets[p] && z < image.vertices[k - 1].z)) {
        return absl::DataLossError(
            absl::StrFormat("%s: pixel (%d, %d): vertex depths are not nondecreasing (vertex %d)",
                            path, p % width, p / width, k - image.offsets[p]));
      }
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::unique_ptr<PdsmWriter>> PdsmWriter::Create(const std::string& path,
                                                               const PdsmHeader& header,
                                                               FileSystem* fs) {
  if (absl::Status s = ValidateHeaderForWrite(header, path); !s.ok()) return s;
  if (fs == nullptr) fs = FileSystem::Default();
  absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(path, fs);
  if (!file.ok()) return file.status();
  auto stream = std::make_unique<ExrOutputStream>(file->get());
  std::unique_ptr<Imf::DeepTiledOutputFile> exr;
  try {
    exr = std::make_unique<Imf::DeepTiledOutputFile>(*stream, ExrHeaderFromPdsm(header));
  } catch (...) {
    if (!stream->error().ok()) return stream->error();
    return absl::InternalError(
        StatusFromCurrentException((*file)->temp_path(), "cannot start").message());
  }
  return std::make_unique<ExrPdsmWriter>(path, fs, header, *std::move(file), std::move(stream),
                                         std::move(exr));
}

absl::StatusOr<PdsmHeader> ReadPdsmHeader(const std::string& path) {
  std::unique_ptr<Imf::MultiPartInputFile> file;
  if (absl::Status s = OpenChecked(path, &file); !s.ok()) return s;
  return PdsmHeaderFromExr(file->header(0), path);
}

absl::StatusOr<PdsmImage> ReadPdsm(const std::string& path) {
  std::unique_ptr<Imf::MultiPartInputFile> file;
  if (absl::Status s = OpenChecked(path, &file); !s.ok()) return s;
  PdsmImage image;
  absl::StatusOr<PdsmHeader> header = PdsmHeaderFromExr(file->header(0), path);
  if (!header.ok()) return header.status();
  image.header = *std::move(header);
  try {
    Imf::DeepTiledInputPart part(*file, 0);
    if (!part.isComplete()) {
      return absl::DataLossError(absl::StrCat(path, ": incomplete file (truncated?)"));
    }
    ReadOffsets(part, &image);
    ReadVertices(part, &image);
  } catch (...) {
    return StatusFromCurrentException(path, "cannot read");
  }
  if (absl::Status s = CheckDepthOrder(image, path); !s.ok()) return s;
  return image;
}

}  // namespace pdsm
