#include "core/pdsm/tile_chunk.h"

#include <OpenEXR/ImfDeepTiledInputFile.h>
#include <OpenEXR/ImfDeepTiledOutputFile.h>
#include <OpenEXR/ImfHeader.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/pdsm/exr_file_scan.h"
#include "core/pdsm/exr_memory_stream.h"
#include "core/pdsm/pdsm_exr_header.h"
#include "core/pdsm/pdsm_exr_tiles.h"
#include "core/pdsm/refined_pixel.h"
#include "core/util/little_endian.h"

namespace pdsm {
namespace {

// A chunk of a single-part deep tiled file starts with int32 dx, dy, lx, ly (OpenEXR's file
// layout), then the sizes and the data.
constexpr size_t kCoordinateBytes = 16;
// Then uint64 packed sample-count table, packed samples and unpacked samples sizes.
constexpr size_t kPrefixBytes = kCoordinateBytes + 3 * 8;

// Corner and size are ones an OpenEXR data window can hold, within one tile of the tile size
// (and a deep tile's counts).
bool HasAPlace(const EncodedTile& tile) {
  constexpr int kMax = std::numeric_limits<int>::max();
  return tile.x0 >= 0 && tile.y0 >= 0 && tile.width >= 0 && tile.height >= 0 &&
         tile.width <= kMax - tile.x0 && tile.height <= kMax - tile.y0 &&
         tile.width <= tile.tile_size && tile.height <= tile.tile_size &&
         static_cast<uint64_t>(tile.width) * static_cast<uint64_t>(tile.height) <=
             kMaxVerticesPerTile;
}

// The header of an image whose only tile is `tile`'s rectangle.
Imf::Header OneTileHeader(const EncodedTile& tile, Imf::LineOrder order) {
  const Imath::Box2i window(Imath::V2i(tile.x0, tile.y0),
                            Imath::V2i(tile.x0 + tile.width - 1, tile.y0 + tile.height - 1));
  Imf::Header exr(window, window);
  SetPdsmPixelLayout(&exr, tile.tile_size, tile.tile_size);
  exr.lineOrder() = order;
  return exr;
}

}  // namespace

absl::StatusOr<EncodedTile> EncodeTileChunk(const PdsmTile& tile, int tile_size) {
  EncodedTile encoded{tile.x0, tile.y0, tile.width, tile.height, tile.samples, tile_size, {}};
  if (!HasAPlace(encoded)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("tile at (%d, %d) of size %dx%d in tiles of %d", tile.x0, tile.y0,
                        tile.width, tile.height, tile_size));
  }
  const size_t pixels = static_cast<size_t>(tile.width) * tile.height;
  if (tile.offsets.size() != pixels + 1) {
    return absl::InvalidArgumentError(
        absl::StrFormat("tile at (%d, %d) has %d offsets, expected %d", tile.x0, tile.y0,
                        tile.offsets.size(), pixels + 1));
  }
  // A chunk does not know its file's header: it holds any well-formed pixel, and the file's
  // writer checks the header's largest refinement.
  if (absl::Status s = CheckTileFunctions(tile, "tile", kLargestRefinement); !s.ok()) return s;
  if (pixels == 0) return encoded;
  ExrStringOStream out("tile chunk");
  try {
    // RANDOM_Y: OpenEXR writes the tile as it is given instead of waiting for tiles before it.
    Imf::DeepTiledOutputFile file(out, OneTileHeader(encoded, Imf::RANDOM_Y), /*numThreads=*/0);
    const uint64_t start = out.tellp();  // after the header and the offset table
    DeepTileBuffers buffers;
    buffers.Resize(pixels);
    // OpenEXR only reads through these pointers when writing.
    Vertex* vertices = const_cast<Vertex*>(tile.vertices.data());
    for (size_t p = 0; p < pixels; ++p) {
      buffers.Set(p, vertices, tile.offsets[p], tile.offsets[p + 1]);
    }
    file.setFrameBuffer(buffers.FrameBuffer(tile.width));
    file.writeTile(0, 0);
    const uint64_t end = out.tellp();
    encoded.chunk =
        out.bytes().substr(static_cast<size_t>(start), static_cast<size_t>(end - start));
  } catch (...) {
    return absl::InternalError(StatusFromCurrentException("tile", "cannot encode").message());
  }
  return encoded;
}

absl::StatusOr<PdsmTile> DecodeTileChunk(const EncodedTile& encoded, absl::string_view label) {
  const auto corrupt = [&](absl::string_view what) {
    return absl::DataLossError(absl::StrCat(label, ": ", what));
  };
  PdsmTile tile;
  tile.x0 = encoded.x0;
  tile.y0 = encoded.y0;
  tile.width = encoded.width;
  tile.height = encoded.height;
  tile.samples = encoded.samples;
  if (!HasAPlace(encoded)) {
    return corrupt(absl::StrFormat("a tile at (%d, %d) of size %dx%d in tiles of %d", tile.x0,
                                   tile.y0, tile.width, tile.height, encoded.tile_size));
  }
  const size_t pixels = static_cast<size_t>(tile.width) * tile.height;
  if (pixels == 0) {
    if (!encoded.chunk.empty()) return corrupt("a tile of no pixel with a chunk");
    tile.offsets.assign(1, 0);
    return tile;
  }
  // Its sizes against its length and what zlib can inflate, before OpenEXR allocates for
  // them (as ScanPdsmFile checks a file's chunks).
  if (encoded.chunk.size() < kPrefixBytes) {
    return corrupt(absl::StrFormat("a chunk of %d bytes", encoded.chunk.size()));
  }
  ByteReader sizes(encoded.chunk.data() + kCoordinateBytes);
  const uint64_t packed_table = sizes.U64(), packed_data = sizes.U64();
  const uint64_t unpacked_data = sizes.U64();
  const uint64_t left = encoded.chunk.size() - kPrefixBytes;
  if (packed_table > left || packed_data != left - packed_table ||
      !ExrUnpackedSizeIsPossible(packed_table, uint64_t{4} * pixels) ||
      !ExrUnpackedSizeIsPossible(packed_data, unpacked_data) ||
      unpacked_data > static_cast<uint64_t>(std::numeric_limits<int32_t>::max())) {
    return corrupt(absl::StrFormat(
        "impossible sizes for %dx%d pixels in a chunk of %d bytes (sample counts %d packed, "
        "samples %d packed / %d bytes)",
        tile.width, tile.height, encoded.chunk.size(), packed_table, packed_data, unpacked_data));
  }
  try {
    // A file of this one tile: its header, its offset table (one entry: the chunk right after
    // it), the chunk.
    ExrStringOStream made("tile chunk");
    { Imf::DeepTiledOutputFile empty(made, OneTileHeader(encoded, Imf::INCREASING_Y), 0); }
    std::string& file = made.bytes();
    ByteWriter(file.data() + file.size() - sizeof(uint64_t)).U64(file.size());
    file += RelocateTileChunk(encoded.chunk, 0, 0);
    const std::string name(label);
    ExrStringIStream in(file, name.c_str());
    Imf::DeepTiledInputFile exr(in, /*numThreads=*/0);
    if (absl::Status s = ReadDeepTile(exr, 0, 0, label, &tile); !s.ok()) return s;
  } catch (...) {
    return corrupt(StatusFromCurrentException("chunk", "cannot decode").message());
  }
  if (absl::Status s = CheckTileFunctions(tile, label, kLargestRefinement); !s.ok()) {
    return corrupt(s.message());
  }
  return tile;
}

std::string RelocateTileChunk(std::string chunk, int dx, int dy) {
  ByteWriter out(chunk.data());
  out.I32(dx);
  out.I32(dy);
  out.I32(0);  // level 0 in x
  out.I32(0);  // and in y
  return chunk;
}

absl::StatusOr<std::string> EmptyTileChunks::Chunk(int width, int height) {
  {
    absl::MutexLock lock(&mu_);
    const auto known = by_size_.find({width, height});
    if (known != by_size_.end()) return known->second;
  }
  PdsmTile empty;
  empty.width = width;
  empty.height = height;
  if (width >= 0 && height >= 0) {
    empty.offsets.assign(static_cast<size_t>(width) * static_cast<size_t>(height) + 1, 0);
  }
  absl::StatusOr<EncodedTile> encoded = EncodeTileChunk(empty, tile_size_);
  if (!encoded.ok()) return encoded.status();
  absl::MutexLock lock(&mu_);
  by_size_.emplace(std::make_pair(width, height), encoded->chunk);
  return std::move(encoded->chunk);
}

absl::StatusOr<EncodedTile> EmptyTileChunks::Tile(int x0, int y0, int width, int height,
                                                  int samples) {
  absl::StatusOr<std::string> chunk = Chunk(width, height);
  if (!chunk.ok()) return chunk.status();
  return EncodedTile{x0, y0, width, height, samples, tile_size_, *std::move(chunk)};
}

}  // namespace pdsm
