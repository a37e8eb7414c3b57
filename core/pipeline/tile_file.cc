#include "core/pipeline/tile_file.h"

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string_view>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/string_view.h"
#include "core/pdsm/tile_chunk.h"
#include "core/util/fnv1a.h"
#include "core/util/little_endian.h"

namespace pdsm {
namespace {

constexpr char kMagic[8] = {'P', 'D', 'S', 'M', 'T', 'I', 'L', 'E'};
constexpr size_t kChecksumBytes = 8;
// Version 3: magic, version, x0, y0, width, height, samples, tile_size, chunk_bytes.
constexpr size_t kChunkHeaderBytes = sizeof(kMagic) + 4 + 4 * 4 + 4 + 4 + 8;
// Versions 1 and 2 (earlier builds): magic, version, x0, y0, width, height, offset_count,
// vertex_count.
constexpr size_t kHeaderBytes = sizeof(kMagic) + 4 + 4 * 4 + 8 + 8;
constexpr size_t kOffsetBytes = 8;
constexpr size_t kVertexBytes = 8;  // float z, float a
// Version 2 (tiles of adaptive bakes) appends int32 samples after the vertices.
constexpr uint32_t kFixedSamplesVersion = 1;
constexpr uint32_t kAdaptiveVersion = 2;
constexpr size_t kSamplesBytes = 4;

absl::Status CheckTileForWrite(const PdsmTile& tile, const std::string& path) {
  const auto bad = [&](absl::string_view what) {
    return absl::InvalidArgumentError(absl::StrFormat("%s: tile at (%d, %d) size %dx%d: %s", path,
                                                      tile.x0, tile.y0, tile.width, tile.height,
                                                      what));
  };
  if (tile.x0 < 0 || tile.y0 < 0 || tile.width < 0 || tile.height < 0) {
    return bad("negative corner or size");
  }
  const uint64_t pixels = static_cast<uint64_t>(tile.width) * static_cast<uint64_t>(tile.height);
  if (tile.offsets.size() != pixels + 1) {
    return bad(absl::StrFormat("%d offsets, expected %d", tile.offsets.size(), pixels + 1));
  }
  if (tile.offsets[0] != 0 || tile.offsets.back() != tile.vertices.size()) {
    return bad(absl::StrFormat("offsets do not span the %d vertices", tile.vertices.size()));
  }
  for (size_t p = 0; p < pixels; ++p) {
    if (tile.offsets[p + 1] < tile.offsets[p]) {
      return bad(absl::StrFormat("offsets decrease at pixel %d", p));
    }
  }
  return absl::OkStatus();
}

std::string EncodeFunctions(const PdsmTile& tile) {
  // Fixed-count tiles keep version 1, byte for byte.
  const bool adaptive = tile.samples > 0;
  const size_t size = kHeaderBytes + tile.offsets.size() * kOffsetBytes +
                      tile.vertices.size() * kVertexBytes + (adaptive ? kSamplesBytes : 0) +
                      kChecksumBytes;
  std::string bytes(size, '\0');
  ByteWriter out(bytes.data());
  out.Bytes(kMagic, sizeof(kMagic));
  out.U32(adaptive ? kAdaptiveVersion : kFixedSamplesVersion);
  out.I32(tile.x0);
  out.I32(tile.y0);
  out.I32(tile.width);
  out.I32(tile.height);
  out.U64(tile.offsets.size());
  out.U64(tile.vertices.size());
  for (const uint64_t offset : tile.offsets) out.U64(offset);
  for (const Vertex& v : tile.vertices) {
    out.F32(v.z);
    out.F32(v.a);
  }
  if (adaptive) out.I32(tile.samples);
  out.U64(Fnv1a64(std::string_view(bytes).substr(0, size - kChecksumBytes)));
  return bytes;
}

std::string EncodeChunk(const EncodedTile& tile) {
  const size_t size = kChunkHeaderBytes + tile.chunk.size() + kChecksumBytes;
  std::string bytes(size, '\0');
  ByteWriter out(bytes.data());
  out.Bytes(kMagic, sizeof(kMagic));
  out.U32(kTileFileVersion);
  out.I32(tile.x0);
  out.I32(tile.y0);
  out.I32(tile.width);
  out.I32(tile.height);
  out.I32(tile.samples);
  out.I32(tile.tile_size);
  out.U64(tile.chunk.size());
  out.Bytes(tile.chunk.data(), tile.chunk.size());
  out.U64(Fnv1a64(std::string_view(bytes).substr(0, size - kChecksumBytes)));
  return bytes;
}

// A tile file's contents: the encoded tile (version 3) or the functions (versions 1, 2).
struct Contents {
  EncodedTile encoded;
  std::optional<PdsmTile> functions;
};

absl::StatusOr<PdsmTile> DecodeFunctions(const std::string& bytes, const std::string& path);

absl::StatusOr<Contents> Parse(const std::string& bytes, const std::string& path) {
  const auto corrupt = [&](absl::string_view what) {
    return absl::DataLossError(absl::StrCat("tile file ", path, ": ", what));
  };
  const size_t size = bytes.size();
  if (size < sizeof(kMagic) + 4 || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    if (size < kChunkHeaderBytes + kChecksumBytes) {
      return corrupt(absl::StrFormat("truncated (%d bytes, a tile file has at least %d)", size,
                                     kChunkHeaderBytes + kChecksumBytes));
    }
    return corrupt("not a tile file (bad magic)");
  }
  const uint32_t version = ByteReader(bytes.data() + sizeof(kMagic)).U32();
  if (version > kTileFileVersion && size >= sizeof(kMagic) + 4 + kChecksumBytes &&
      ByteReader(bytes.data() + size - kChecksumBytes).U64() ==
          Fnv1a64(std::string_view(bytes).substr(0, size - kChecksumBytes))) {
    return absl::FailedPreconditionError(
        absl::StrFormat("tile file %s: version %d is newer than this build reads (%d)", path,
                        version, kTileFileVersion));
  }
  if (version != kTileFileVersion) {
    absl::StatusOr<PdsmTile> functions = DecodeFunctions(bytes, path);
    if (!functions.ok()) return functions.status();
    Contents contents;
    contents.encoded.x0 = functions->x0;
    contents.encoded.y0 = functions->y0;
    contents.encoded.width = functions->width;
    contents.encoded.height = functions->height;
    contents.encoded.samples = functions->samples;
    contents.functions = *std::move(functions);
    return contents;
  }
  if (size < kChunkHeaderBytes + kChecksumBytes) {
    return corrupt(absl::StrFormat("truncated (%d bytes, a tile file has at least %d)", size,
                                   kChunkHeaderBytes + kChecksumBytes));
  }
  ByteReader in(bytes.data() + sizeof(kMagic) + 4);
  Contents contents;
  EncodedTile& tile = contents.encoded;
  tile.x0 = in.I32();
  tile.y0 = in.I32();
  tile.width = in.I32();
  tile.height = in.I32();
  tile.samples = in.I32();
  tile.tile_size = in.I32();
  const uint64_t chunk_bytes = in.U64();
  // Sizes first, for a better message than a checksum mismatch on a truncated file.
  if (chunk_bytes != size - kChunkHeaderBytes - kChecksumBytes) {
    return corrupt(absl::StrFormat("%d bytes, but its header describes a chunk of %d (truncated?)",
                                   size, chunk_bytes));
  }
  const uint64_t stored_checksum = ByteReader(bytes.data() + size - kChecksumBytes).U64();
  if (stored_checksum != Fnv1a64(std::string_view(bytes).substr(0, size - kChecksumBytes))) {
    return corrupt("checksum mismatch");
  }
  if (tile.x0 < 0 || tile.y0 < 0 || tile.width < 0 || tile.height < 0 || tile.samples < 0) {
    return corrupt(absl::StrFormat("negative corner, size or samples (%d, %d) %dx%d, %d samples",
                                   tile.x0, tile.y0, tile.width, tile.height, tile.samples));
  }
  tile.chunk.assign(bytes, kChunkHeaderBytes, static_cast<size_t>(chunk_bytes));
  return contents;
}

absl::StatusOr<PdsmTile> DecodeFunctions(const std::string& bytes, const std::string& path) {
  const auto corrupt = [&](absl::string_view what) {
    return absl::DataLossError(absl::StrCat("tile file ", path, ": ", what));
  };
  const size_t size = bytes.size();
  if (size < kHeaderBytes + kOffsetBytes + kChecksumBytes) {
    return corrupt(absl::StrFormat("truncated (%d bytes, a tile file has at least %d)", size,
                                   kHeaderBytes + kOffsetBytes + kChecksumBytes));
  }
  if (std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    return corrupt("not a tile file (bad magic)");
  }
  ByteReader in(bytes.data() + sizeof(kMagic));
  const uint32_t version = in.U32();
  PdsmTile tile;
  tile.x0 = in.I32();
  tile.y0 = in.I32();
  tile.width = in.I32();
  tile.height = in.I32();
  const uint64_t offset_count = in.U64();
  const uint64_t vertex_count = in.U64();
  const size_t trailer = version == kAdaptiveVersion ? kSamplesBytes : 0;
  if (version == kAdaptiveVersion || version == kFixedSamplesVersion) {
    // Sizes first, for a better message than a checksum mismatch on a truncated file.
    if (tile.x0 < 0 || tile.y0 < 0 || tile.width < 0 || tile.height < 0) {
      return corrupt(absl::StrFormat("negative corner or size (%d, %d) %dx%d", tile.x0, tile.y0,
                                     tile.width, tile.height));
    }
    const uint64_t pixels = static_cast<uint64_t>(tile.width) * static_cast<uint64_t>(tile.height);
    if (offset_count != pixels + 1) {
      return corrupt(absl::StrFormat("%d offsets for %dx%d pixels, expected %d", offset_count,
                                     tile.width, tile.height, pixels + 1));
    }
    // Both counts are at most size / 8 before they are multiplied: no overflow.
    if (offset_count > size / kOffsetBytes || vertex_count > size / kVertexBytes ||
        kHeaderBytes + offset_count * kOffsetBytes + vertex_count * kVertexBytes + trailer +
                kChecksumBytes !=
            size) {
      return corrupt(absl::StrFormat(
          "%d bytes, but its header describes %d offsets and %d vertices (truncated?)", size,
          offset_count, vertex_count));
    }
  }
  const uint64_t stored_checksum = ByteReader(bytes.data() + size - kChecksumBytes).U64();
  if (stored_checksum != Fnv1a64(std::string_view(bytes).substr(0, size - kChecksumBytes))) {
    return corrupt("checksum mismatch");
  }
  if (version > kTileFileVersion) {
    return absl::FailedPreconditionError(
        absl::StrFormat("tile file %s: version %d is newer than this build reads (%d)", path,
                        version, kTileFileVersion));
  }
  if (version != kAdaptiveVersion && version != kFixedSamplesVersion) {
    return corrupt(absl::StrCat("invalid version ", version));
  }

  tile.offsets.resize(offset_count);
  for (uint64_t& offset : tile.offsets) offset = in.U64();
  if (tile.offsets[0] != 0) return corrupt("the first offset is not 0");
  for (size_t p = 0; p + 1 < tile.offsets.size(); ++p) {
    if (tile.offsets[p + 1] < tile.offsets[p]) {
      return corrupt(absl::StrFormat("offsets decrease at pixel %d", p));
    }
  }
  if (tile.offsets.back() != vertex_count) {
    return corrupt(absl::StrFormat("the last offset %d is not the vertex count %d",
                                   tile.offsets.back(), vertex_count));
  }
  tile.vertices.resize(vertex_count);
  for (Vertex& v : tile.vertices) {
    v.z = in.F32();
    v.a = in.F32();
  }
  if (trailer > 0) {
    tile.samples = in.I32();
    if (tile.samples < 1) return corrupt(absl::StrFormat("%d samples", tile.samples));
  }
  return tile;
}

}  // namespace

absl::StatusOr<std::string> EncodeTileFile(const PdsmTile& tile, int tile_size,
                                           const std::string& label) {
  if (absl::Status s = CheckTileForWrite(tile, label); !s.ok()) return s;
  absl::StatusOr<EncodedTile> encoded = EncodeTileChunk(tile, tile_size);
  if (!encoded.ok()) {
    return absl::Status(encoded.status().code(),
                        absl::StrCat(label, ": ", encoded.status().message()));
  }
  return EncodeChunk(*encoded);
}

absl::StatusOr<PdsmTile> DecodeTileFile(const std::string& bytes, const std::string& label) {
  absl::StatusOr<Contents> contents = Parse(bytes, label);
  if (!contents.ok()) return contents.status();
  if (contents->functions) return *std::move(contents->functions);
  return DecodeTileChunk(contents->encoded, absl::StrCat("tile file ", label));
}

absl::Status CheckTileFileBytes(const std::string& bytes, const std::string& label) {
  return Parse(bytes, label).status();
}

absl::StatusOr<EncodedTile> DecodeTileChunkFile(const std::string& bytes, const std::string& label,
                                                int tile_size) {
  absl::StatusOr<Contents> contents = Parse(bytes, label);
  if (!contents.ok()) return contents.status();
  if (!contents->functions) return std::move(contents->encoded);
  // A file of an earlier build: encoded now, as the file will hold it.
  absl::StatusOr<EncodedTile> encoded = EncodeTileChunk(*contents->functions, tile_size);
  if (!encoded.ok()) {
    return absl::DataLossError(absl::StrCat("tile file ", label, ": ", encoded.status().message()));
  }
  return encoded;
}

std::string EncodeEarlierTileFile(const PdsmTile& tile) { return EncodeFunctions(tile); }

}  // namespace pdsm
