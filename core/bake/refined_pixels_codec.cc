#include "core/bake/refined_pixels_codec.h"

#include <cmath>
#include <cstring>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/util/little_endian.h"

namespace pdsm {
namespace {

constexpr char kMagic[8] = {'P', 'D', 'S', 'M', 'R', 'E', 'F', 'P'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeaderBytes = sizeof(kMagic) + 4 + 4 + 4;
constexpr size_t kPixelBytes = 4 + 4 + 4;
constexpr size_t kBandBytes = 8 + 8;

}  // namespace

std::string EncodeRefinedPixels(const RefinedPixels& refined) {
  size_t size = kHeaderBytes;
  for (int t = 0; t < refined.tiles(); ++t) {
    size += 4;
    for (const RefinedPixel& p : refined.Tile(t)) size += kPixelBytes + kBandBytes * p.bands.size();
  }
  std::string out(size, '\0');
  ByteWriter w(out.data());
  w.Bytes(kMagic, sizeof(kMagic));
  w.U32(kVersion);
  w.I32(refined.factor());
  w.U32(static_cast<uint32_t>(refined.tiles()));
  for (int t = 0; t < refined.tiles(); ++t) {
    w.U32(static_cast<uint32_t>(refined.Tile(t).size()));
    for (const RefinedPixel& p : refined.Tile(t)) {
      w.I32(p.x);
      w.I32(p.y);
      w.U32(static_cast<uint32_t>(p.bands.size()));
      for (const DepthWindow& band : p.bands) {
        w.F64(band.lo);
        w.F64(band.hi);
      }
    }
  }
  return out;
}

absl::StatusOr<std::shared_ptr<const RefinedPixels>> DecodeRefinedPixels(const std::string& bytes,
                                                                         const BakePlan& base,
                                                                         const std::string& label) {
  const auto corrupt = [&](const std::string& why) {
    return absl::DataLossError(absl::StrFormat("%s: refined pixels: %s", label, why));
  };
  size_t left = bytes.size();
  const auto take = [&](size_t n) {
    if (left < n) return false;
    left -= n;
    return true;
  };
  if (!take(kHeaderBytes) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    return corrupt("not a refined-pixel blob (no PDSMREFP header)");
  }
  ByteReader r(bytes.data() + sizeof(kMagic));
  if (const uint32_t version = r.U32(); version != kVersion) {
    return corrupt(absl::StrFormat("version %d; this build reads %d", version, kVersion));
  }
  const int factor = static_cast<int32_t>(r.U32());
  if (factor != 2 && factor != 4 && factor != 8) {
    return corrupt(absl::StrFormat("factor %d is not 2, 4 or 8", factor));
  }
  const uint32_t tiles = r.U32();
  if (tiles != static_cast<uint32_t>(base.tile_count())) {
    return corrupt(absl::StrFormat("%d tiles, but the base map has %d", tiles, base.tile_count()));
  }
  std::vector<std::vector<RefinedPixel>> by_tile(tiles);
  for (uint32_t t = 0; t < tiles; ++t) {
    if (!take(4)) return corrupt(absl::StrFormat("cut short in tile %d", t));
    const uint32_t pixels = r.U32();
    // Each pixel takes bytes: a count past what is left is corrupt, not an allocation.
    if (pixels > left / kPixelBytes) {
      return corrupt(absl::StrFormat("tile %d: %d pixels in %d bytes", t, pixels, left));
    }
    const TileRect rect = base.tile(static_cast<int>(t));
    std::vector<RefinedPixel>& out = by_tile[t];
    out.resize(pixels);
    for (uint32_t k = 0; k < pixels; ++k) {
      if (!take(kPixelBytes)) return corrupt(absl::StrFormat("cut short in tile %d", t));
      RefinedPixel& p = out[k];
      p.x = static_cast<int32_t>(r.U32());
      p.y = static_cast<int32_t>(r.U32());
      if (p.x < rect.x0 || p.x >= rect.x0 + rect.width || p.y < rect.y0 ||
          p.y >= rect.y0 + rect.height) {
        return corrupt(absl::StrFormat("tile %d: pixel (%d, %d) is outside it", t, p.x, p.y));
      }
      if (k > 0 && std::pair(p.y, p.x) <= std::pair(out[k - 1].y, out[k - 1].x)) {
        return corrupt(
            absl::StrFormat("tile %d: pixel (%d, %d) is out of row-major order", t, p.x, p.y));
      }
      const uint32_t bands = r.U32();
      if (bands == 0 || bands > left / kBandBytes) {
        return corrupt(
            absl::StrFormat("pixel (%d, %d): %d bands in %d bytes", p.x, p.y, bands, left));
      }
      take(kBandBytes * bands);
      p.bands.resize(bands);
      for (uint32_t b = 0; b < bands; ++b) {
        DepthWindow& band = p.bands[b];
        band.lo = r.F64();
        band.hi = r.F64();
        if (!std::isfinite(band.lo) || !std::isfinite(band.hi) || !(band.lo <= band.hi) ||
            (b > 0 && !(p.bands[b - 1].hi < band.lo))) {
          return corrupt(
              absl::StrFormat("pixel (%d, %d): band %d [%g, %g] is empty, not finite "
                              "or out of order",
                              p.x, p.y, b, band.lo, band.hi));
        }
      }
    }
  }
  if (left != 0) return corrupt(absl::StrFormat("%d bytes left over", left));
  return std::make_shared<const RefinedPixels>(base.header.geometry, base.header.tile_size, factor,
                                               std::move(by_tile));
}

}  // namespace pdsm
