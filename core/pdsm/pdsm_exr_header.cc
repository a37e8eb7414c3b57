#include "core/pdsm/pdsm_exr_header.h"

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
#include <OpenEXR/ImfStdIO.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfTileDescription.h>
#include <OpenEXR/ImfVecAttribute.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
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
#include "core/assets/mesh_asset.h"
#include "core/pdsm/exr_output_stream.h"
#include "core/pdsm/pdsm_exr_tiles.h"
#include "core/pdsm/refined_pixel.h"
#include "core/util/atomic_file.h"
#include "core/util/file_system.h"
#include "core/util/little_endian.h"

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
constexpr char kAttrConeHalfAngle[] = "pdsmConeHalfAngleDeg";
constexpr char kAttrSphereFaceTangent[] = "pdsmSphereFaceTangent";
constexpr char kAttrWeighting[] = "pdsmWeighting";
constexpr char kAttrMaxRefinement[] = "pdsmMaxRefinement";

constexpr char kAttenuationNote[] =
    "channel 'attenuation' = A(z), the fraction of the light hidden from the point at depth "
    "Z on this pixel's ray (0 lit, 1 umbra); piecewise linear between samples, not "
    "monotonic, not alpha: do not composite";

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
constexpr EnumName<LightWeighting> kWeightingNames[] = {{LightWeighting::kUnweighted, "unweighted"},
                                                        {LightWeighting::kEmitter, "emitter"}};
constexpr EnumName<SamplingPattern> kSamplingNames[] = {
    {SamplingPattern::kStratified, "stratified"},
    {SamplingPattern::kUniform, "uniform"},
    {SamplingPattern::kSobol, "sobol"},
    {SamplingPattern::kHalton, "halton"},
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
  h->cone_half_angle_deg = in.GetOptional<double>(kAttrConeHalfAngle, 0.0);
  if (in.status().ok() && !(h->cone_half_angle_deg >= 0 && h->cone_half_angle_deg <= 90)) {
    in.Fail(absl::StrFormat("attribute %s = %g is not an angle in [0, 90] degrees",
                            kAttrConeHalfAngle, h->cone_half_angle_deg));
  }
  h->face_tangent = in.GetOptional<double>(kAttrSphereFaceTangent, 0.0);
  if (in.status().ok() && !(h->face_tangent >= 0 && h->face_tangent <= 1e6)) {
    in.Fail(absl::StrFormat("attribute %s = %g is not a tangent >= 0", kAttrSphereFaceTangent,
                            h->face_tangent));
  }
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
  if (!in.status().ok()) return;
  // What every lookup divides by or compares with: a corrupt value here would turn a query
  // into NaN pixel coordinates (found by fuzz_pdsm_reader) instead of an error.
  const auto finite = [](const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
  };
  const std::pair<const char*, glm::dvec3> vectors[] = {{kAttrLightCenter, g->frame.center},
                                                        {kAttrLightU, g->frame.u},
                                                        {kAttrLightV, g->frame.v},
                                                        {kAttrLightN, g->frame.n}};
  for (const auto& [name, v] : vectors) {
    if (!finite(v)) return in.Fail(absl::StrFormat("attribute %s is not finite", name));
  }
  const double s_extent = g->s_max - g->s_min;
  const double t_extent = g->t_max - g->t_min;
  if (!(std::isfinite(s_extent) && s_extent > 0 && std::isfinite(t_extent) && t_extent > 0)) {
    return in.Fail(absl::StrFormat("attributes %s/%s: (%g, %g) to (%g, %g) is no window",
                                   kAttrWindowMin, kAttrWindowMax, g->s_min, g->t_min, g->s_max,
                                   g->t_max));
  }
  if (!(std::isfinite(g->z_near) && std::isfinite(g->z_far) && g->z_near <= g->z_far)) {
    return in.Fail(absl::StrFormat("attributes %s/%s: %g to %g is no depth range", kAttrZNear,
                                   kAttrZFar, g->z_near, g->z_far));
  }
  if (!std::isfinite(g->z_valid_min)) {
    return in.Fail(absl::StrFormat("attribute %s is not finite", kAttrZValidMin));
  }
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
  h->max_refinement = in.GetOptional<int>(kAttrMaxRefinement, 1);
  if (in.status().ok() && !IsRefinementFactor(h->max_refinement)) {
    in.Fail(absl::StrFormat("attribute %s = %d is not 1, 2, 4 or 8", kAttrMaxRefinement,
                            h->max_refinement));
  }
  if (exr.find(kAttrWeighting) != exr.end()) {
    h->weighting = in.GetEnum(kAttrWeighting, kWeightingNames);
  }
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

}  // namespace

// ---------------------------------------------------------------------------------------

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

void SetPdsmPixelLayout(Imf::Header* exr, int tile_width, int tile_height) {
  exr->setType(Imf::DEEPTILE);
  exr->compression() = Imf::ZIPS_COMPRESSION;  // deep allows only NONE, RLE, ZIPS
  exr->lineOrder() = Imf::INCREASING_Y;
  exr->setTileDescription(Imf::TileDescription(tile_width, tile_height, Imf::ONE_LEVEL));
  exr->channels().insert(kDepthChannel, Imf::Channel(Imf::FLOAT));
  exr->channels().insert(kAttenuationChannel, Imf::Channel(Imf::FLOAT));
}

Imf::Header ExrHeaderFromPdsm(const PdsmHeader& h,
                              const std::optional<Imath::Box2i>& display_window) {
  const PdsmGeometry& g = h.geometry;
  Imf::Header exr(g.width, g.height);  // data and display windows [0, w-1] x [0, h-1]
  if (display_window) exr.displayWindow() = *display_window;
  if (!h.light_name.empty()) exr.setName(h.light_name);
  SetPdsmPixelLayout(&exr, h.tile_size, h.tile_size);

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
  if (h.max_refinement > 1) exr.insert(kAttrMaxRefinement, Imf::IntAttribute(h.max_refinement));
  if (h.weighting != LightWeighting::kUnweighted) {
    exr.insert(kAttrWeighting, Imf::StringAttribute(NameOf(kWeightingNames, h.weighting)));
  }
  if (h.cone_half_angle_deg > 0) {
    exr.insert(kAttrConeHalfAngle, Imf::DoubleAttribute(h.cone_half_angle_deg));
  }
  if (h.face_tangent > 0) {
    exr.insert(kAttrSphereFaceTangent, Imf::DoubleAttribute(h.face_tangent));
  }
  // What DeepTiledOutputFile would add itself, set first so that the checksum covers it.
  const TileGrid grid{g.width, g.height, h.tile_size};
  exr.setChunkCount(static_cast<int>(grid.Count()));
  SealExrHeader(&exr);
  return exr;
}

std::string HeaderChecksum(const ExrHeaderBytes& header) {
  Sha256 sha;
  for (const ExrAttributeBytes& a : header.attributes) {
    if (a.name == kHeaderChecksumAttribute) continue;
    char size[4];
    ByteWriter(size).I32(static_cast<int32_t>(a.value.size()));
    sha.Update(std::string_view(a.name.c_str(), a.name.size() + 1));
    sha.Update(std::string_view(a.type.c_str(), a.type.size() + 1));
    sha.Update(std::string_view(size, sizeof(size)));
    sha.Update(a.value);
  }
  return sha.FinalHex();
}

void SealExrHeader(Imf::Header* exr) {
  // The records exactly as OpenEXR will write them: its own serializer, read back by ours.
  Imf::StdOSStream out;
  exr->writeTo(out, /*isTiled=*/true);
  absl::StatusOr<ExrHeaderBytes> records = ParseExrHeaderBytes(out.str(), "header being written");
  if (!records.ok()) {  // a programmer error: our parser refuses what OpenEXR writes
    std::fprintf(stderr, "%s\n", std::string(records.status().message()).c_str());
    std::abort();
  }
  exr->insert(kHeaderChecksumAttribute, Imf::StringAttribute(HeaderChecksum(*records)));
}

absl::Status VerifyHeaderChecksum(const ExrHeaderBytes& header, absl::string_view path) {
  const ExrAttributeBytes* stored = header.Find(kHeaderChecksumAttribute);
  if (stored == nullptr) return absl::OkStatus();
  if (stored->type != "string" || !IsSha256Hex(stored->value)) {
    return absl::DataLossError(absl::StrCat(path, ": attribute ", kHeaderChecksumAttribute,
                                            " is not a string of 64 hex digits"));
  }
  if (const std::string actual = HeaderChecksum(header); actual != stored->value) {
    return absl::DataLossError(absl::StrCat(path, ": corrupt header: its checksum (",
                                            kHeaderChecksumAttribute,
                                            ") does not match its attributes"));
  }
  return absl::OkStatus();
}

// Reads typed attributes, remembering the first one missing or of the wrong type.

absl::StatusOr<PdsmHeader> PdsmHeaderFromExr(const Imf::Header& exr, absl::string_view path) {
  if (absl::Status s = CheckPdsmLayout(exr, path); !s.ok()) return s;
  AttributeReader in(exr, path);
  PdsmHeader h;
  h.format_version = in.Get<int>(kAttrFormatVersion);
  h.scene_name = in.Get<std::string>(kAttrSceneName);
  if (exr.hasName()) h.light_name = exr.name();
  ReadLight(in, &h);
  ReadGeometry(in, exr, &h.geometry);
  ReadBakeSettings(in, exr, &h);
  ReadAdaptive(in, exr, &h);
  if (!in.status().ok()) return in.status();
  if (h.format_version < MinimumFormatVersion(h)) {
    return absl::DataLossError(
        absl::StrFormat("%s: %s = %d, but its %s/%s/%s attributes need version %d", path,
                        kAttrFormatVersion, h.format_version, kAttrSurfacesOnly, kAttrZValidMin,
                        kAttrMaxRefinement, MinimumFormatVersion(h)));
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
  if (!IsRefinementFactor(h.max_refinement)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s: header.max_refinement = %d, must be 1, 2, 4 or 8", path, h.max_refinement));
  }
  if (h.tile_size <= 0 || h.tile_size > kMaxTileSize) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s: header.tile_size = %d, must be in [1, %d]", path, h.tile_size, kMaxTileSize));
  }
  return absl::OkStatus();
}

}  // namespace pdsm
