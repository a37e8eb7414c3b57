// A PDSM's tiles as OpenEXR's deep tiled parts want them: the tile grid, the checks a tile's
// functions must pass before they are written, and the deep frame buffers that point OpenEXR
// at a tile's vertices. Internal to core/pdsm.
#ifndef PDSM_CORE_PDSM_PDSM_EXR_TILES_H_
#define PDSM_CORE_PDSM_PDSM_EXR_TILES_H_

#include <OpenEXR/ImfDeepFrameBuffer.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "absl/strings/string_view.h"
#include "core/pdsm/pdsm_exr_header.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

struct TileGrid {
  int width, height, tile_size;

  int64_t TilesX() const { return (width + tile_size - 1) / tile_size; }
  int64_t TilesY() const { return (height + tile_size - 1) / tile_size; }
  int64_t Count() const { return TilesX() * TilesY(); }
  int TileWidth(int x0) const { return std::min(tile_size, width - x0); }
  int TileHeight(int y0) const { return std::min(tile_size, height - y0); }
};

// INVALID_ARGUMENT naming `path` and the tile or pixel when the offsets do not span the
// vertices, decrease, or hold more vertices than a deep tile can, or a pixel's depths are NaN
// or decrease, or a refined pixel is malformed or refined beyond `max_refinement`
// (PixelFunctionFault, core/pdsm/refined_pixel.h). REQUIRES: tile.offsets has
// width * height + 1 entries.
absl::Status CheckTileFunctions(const PdsmTile& tile, absl::string_view path, int max_refinement);

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

// Reads tile (tile_x, tile_y) of `exr` (an Imf::DeepTiledInputFile or DeepTiledInputPart)
// into `tile`, whose rectangle is already set: its sample counts, then its vertices unless it
// has none (an all-lit tile: OpenEXR would still walk and copy every pixel of it). DATA_LOSS
// naming `label` and the tile when the counts sum past kMaxVerticesPerTile, checked before
// anything is allocated from them (a corrupt file's are any size). OpenEXR's exceptions
// propagate: the caller turns them into a status (StatusFromCurrentException).
template <typename DeepTiledInput>
absl::Status ReadDeepTile(DeepTiledInput& exr, int tile_x, int tile_y, absl::string_view label,
                          PdsmTile* tile) {
  const size_t pixels = static_cast<size_t>(tile->width) * tile->height;
  DeepTileBuffers buffers;
  buffers.Resize(pixels);
  exr.setFrameBuffer(buffers.FrameBuffer(tile->width));
  exr.readPixelSampleCount(tile_x, tile_y);
  tile->offsets.assign(pixels + 1, 0);
  for (size_t p = 0; p < pixels; ++p) tile->offsets[p + 1] = tile->offsets[p] + buffers.counts[p];
  if (tile->offsets.back() > kMaxVerticesPerTile) {
    return absl::DataLossError(
        absl::StrFormat("%s: tile (%d, %d) counts %d vertices, more than a tile holds (%d)", label,
                        tile_x, tile_y, tile->offsets.back(), kMaxVerticesPerTile));
  }
  if (tile->offsets.back() == 0) return absl::OkStatus();
  tile->vertices.resize(tile->offsets.back());
  for (size_t p = 0; p < pixels; ++p) {
    buffers.Set(p, tile->vertices.data(), tile->offsets[p], tile->offsets[p + 1]);
  }
  exr.setFrameBuffer(buffers.FrameBuffer(tile->width));
  exr.readTile(tile_x, tile_y);
  return absl::OkStatus();
}

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_PDSM_EXR_TILES_H_
