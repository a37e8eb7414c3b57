#include "core/pdsm/encoded_tile_store.h"

#include <algorithm>
#include <limits>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/pdsm/pdsm_exr_tiles.h"
#include "core/util/file_system.h"

namespace pdsm {

EncodedTileStore::EncodedTileStore(const PdsmHeader& header, std::string output_path,
                                   FileSystem* fs)
    : width_(header.geometry.width),
      height_(header.geometry.height),
      tile_size_(header.tile_size),
      output_path_(std::move(output_path)),
      fs_(fs != nullptr ? fs : FileSystem::Default()),
      empty_(header.tile_size),
      places_(static_cast<size_t>(Grid().Count())) {
  static_assert(sizeof(Place) <= kHeldBytesPerTile, "kHeldBytesPerTile counts a Place");
}

TileGrid EncodedTileStore::Grid() const { return TileGrid{width_, height_, tile_size_}; }

absl::Status EncodedTileStore::ForOutput(const absl::Status& status) const {
  return absl::Status(status.code(), absl::StrCat(status.message(), " (for ", output_path_, ")"));
}

absl::StatusOr<size_t> EncodedTileStore::CellIndex(int x0, int y0, int width, int height) const {
  const TileGrid grid = Grid();
  const int ts = grid.tile_size;
  const bool is_cell = x0 >= 0 && y0 >= 0 && x0 < grid.width && y0 < grid.height && x0 % ts == 0 &&
                       y0 % ts == 0 && width == grid.TileWidth(x0) && height == grid.TileHeight(y0);
  if (!is_cell) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "tile at (%d, %d) size %dx%d is not a cell of the %dx%d grid of %d-pixel tiles", x0, y0,
        width, height, grid.width, grid.height, ts));
  }
  return static_cast<size_t>(y0 / ts * grid.TilesX() + x0 / ts);
}

absl::Status EncodedTileStore::Put(const PdsmTile& tile) {
  absl::StatusOr<size_t> index = CellIndex(tile.x0, tile.y0, tile.width, tile.height);
  if (!index.ok()) return index.status();
  const size_t pixels = static_cast<size_t>(tile.width) * tile.height;
  if (tile.vertices.empty() && tile.offsets.size() == pixels + 1 && tile.offsets.back() == 0) {
    return PutWithoutVertices(tile.x0, tile.y0, tile.samples);
  }
  return Encode(tile, *index, /*replace=*/false);
}

absl::Status EncodedTileStore::Replace(const PdsmTile& tile) {
  absl::StatusOr<size_t> index = CellIndex(tile.x0, tile.y0, tile.width, tile.height);
  if (!index.ok()) return index.status();
  return Encode(tile, *index, /*replace=*/true);
}

absl::Status EncodedTileStore::Encode(const PdsmTile& tile, size_t index, bool replace) {
  // Encoded before the lock: this is the bake's compression, on the thread that finished it.
  absl::StatusOr<EncodedTile> encoded = EncodeTileChunk(tile, tile_size_);
  if (!encoded.ok()) return encoded.status();
  if (encoded->chunk.size() > std::numeric_limits<uint32_t>::max()) {
    return absl::InvalidArgumentError(
        absl::StrFormat("tile at (%d, %d) compresses to %d bytes, more than a chunk holds", tile.x0,
                        tile.y0, encoded->chunk.size()));
  }
  // A tile without pixels encodes to nothing: kept as the empty chunk.
  return Keep(index, Place{0, static_cast<uint32_t>(encoded->chunk.size()), tile.samples, true},
              encoded->chunk, tile.x0, tile.y0, replace);
}

absl::StatusOr<PdsmTile> EncodedTileStore::Get(int x0, int y0) {
  const TileGrid grid = Grid();
  const int width = grid.TileWidth(x0), height = grid.TileHeight(y0);
  absl::StatusOr<size_t> index = CellIndex(x0, y0, width, height);
  if (!index.ok()) return index.status();
  EncodedTile tile{x0, y0, width, height, 0, grid.tile_size, ""};
  {
    absl::MutexLock lock(&mu_);
    if (!error_.ok()) return error_;
    const Place place = places_[*index];
    if (!place.present) {
      return absl::FailedPreconditionError(
          absl::StrFormat("tile at (%d, %d) was never stored", x0, y0));
    }
    tile.samples = place.samples;
    if (place.size == 0) {  // without a vertex: nothing to read or decode
      PdsmTile empty;
      empty.x0 = x0, empty.y0 = y0, empty.width = width, empty.height = height;
      empty.samples = place.samples;
      empty.offsets.assign(static_cast<size_t>(width) * height + 1, 0);
      return empty;
    }
    tile.chunk.assign(place.size, '\0');
    if (absl::Status s = scratch_->ReadAt(place.offset, place.size, tile.chunk.data()); !s.ok()) {
      return ForOutput(s);
    }
  }
  return DecodeTileChunk(tile, output_path_);
}

absl::Status EncodedTileStore::PutWithoutVertices(int x0, int y0, int samples) {
  const TileGrid grid = Grid();
  const int width = grid.TileWidth(x0), height = grid.TileHeight(y0);
  absl::StatusOr<size_t> index = CellIndex(x0, y0, width, height);
  if (!index.ok()) return index.status();
  // Encoded once per size, so that WriteTo finds it and a failure shows here.
  if (absl::StatusOr<std::string> empty = empty_.Chunk(width, height); !empty.ok()) {
    return empty.status();
  }
  return Keep(*index, Place{0, 0, samples, true}, "", x0, y0);
}

absl::Status EncodedTileStore::Keep(size_t index, Place place, const std::string& chunk, int x0,
                                    int y0, bool replace) {
  absl::MutexLock lock(&mu_);
  if (!error_.ok()) return error_;
  if (places_[index].present != replace) {
    return replace ? absl::FailedPreconditionError(
                         absl::StrFormat("tile at (%d, %d) was never stored", x0, y0))
                   : absl::InvalidArgumentError(
                         absl::StrFormat("tile at (%d, %d) stored twice", x0, y0));
  }
  if (!chunk.empty()) {
    if (!scratch_) {
      absl::StatusOr<std::unique_ptr<ScratchFile>> scratch =
          fs_->NewScratchFile(ParentDir(output_path_));
      if (!scratch.ok()) return error_ = ForOutput(scratch.status());
      scratch_ = *std::move(scratch);
    }
    if (absl::Status s = scratch_->WriteAt(scratch_end_, chunk); !s.ok()) {
      return error_ = ForOutput(s);
    }
    place.offset = scratch_end_;
    scratch_end_ += chunk.size();
  }
  places_[index] = place;
  return absl::OkStatus();
}

absl::Status EncodedTileStore::WriteTo(PdsmWriter* writer) {
  absl::MutexLock lock(&mu_);
  if (!error_.ok()) return error_;
  // Copied under the lock (16 bytes a tile), which stays held until the writer is done: the
  // analysis does not follow a lock into the lambda.
  const std::vector<Place> places = places_;
  ScratchFile* const scratch = scratch_.get();
  const TileGrid grid = Grid();
  return writer->WriteEncodedTiles([&](int64_t index) -> absl::StatusOr<EncodedTile> {
    const Place& place = places.at(static_cast<size_t>(index));
    const int x0 = static_cast<int>(index % grid.TilesX()) * grid.tile_size;
    const int y0 = static_cast<int>(index / grid.TilesX()) * grid.tile_size;
    if (!place.present) {
      return absl::FailedPreconditionError(
          absl::StrFormat("tile at (%d, %d) was never stored", x0, y0));
    }
    if (place.size == 0) {
      return empty_.Tile(x0, y0, grid.TileWidth(x0), grid.TileHeight(y0), place.samples);
    }
    EncodedTile tile{x0,
                     y0,
                     grid.TileWidth(x0),
                     grid.TileHeight(y0),
                     place.samples,
                     grid.tile_size,
                     std::string(place.size, '\0')};
    if (absl::Status s = scratch->ReadAt(place.offset, place.size, tile.chunk.data()); !s.ok()) {
      return ForOutput(s);
    }
    return tile;
  });
}

}  // namespace pdsm
