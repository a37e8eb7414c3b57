#include "server/tile_log.h"

#include <algorithm>
#include <cstring>
#include <string_view>
#include <utility>

#include <spdlog/spdlog.h>

#include "absl/strings/str_cat.h"
#include "core/pipeline/tile_file.h"
#include "core/util/fnv1a.h"
#include "core/util/little_endian.h"

namespace pdsm {
namespace {

constexpr char kMagic[8] = {'P', 'D', 'S', 'M', 'T', 'L', 'O', 'G'};
constexpr uint64_t kHeaderBytes = sizeof(kMagic) + 4 + 4;
constexpr char kRecordMagic[4] = {'T', 'R', 'E', 'C'};
constexpr uint64_t kFrameBytes = 4 + 4 + 8 + 8;  // magic, tile, payload bytes, checksum

std::string EncodeHeader() {
  std::string bytes(kHeaderBytes, '\0');
  ByteWriter out(bytes.data());
  out.Bytes(kMagic, sizeof(kMagic));
  out.U32(kTileLogVersion);
  out.U32(0);
  return bytes;
}

std::string EncodeFrame(int tile, uint64_t payload_bytes) {
  std::string bytes(kFrameBytes, '\0');
  ByteWriter out(bytes.data());
  out.Bytes(kRecordMagic, sizeof(kRecordMagic));
  out.I32(tile);
  out.U64(payload_bytes);
  out.U64(Fnv1a64(std::string_view(bytes).substr(0, kFrameBytes - 8)));
  return bytes;
}

}  // namespace

absl::StatusOr<std::unique_ptr<TileLog>> TileLog::Open(const std::string& path, FileSystem* fs) {
  if (fs == nullptr) fs = FileSystem::Default();
  absl::StatusOr<std::unique_ptr<RandomAccessFile>> file = fs->OpenFile(path);
  if (!file.ok()) return file.status();
  std::unique_ptr<TileLog> log(new TileLog(*std::move(file)));
  absl::StatusOr<uint64_t> size = log->file_->Size();
  if (!size.ok()) return size.status();
  if (*size < kHeaderBytes) {
    // New, or created by a process that died before its header was durable: nothing in it
    // can be a record (records follow a durable header), so it starts over.
    if (absl::Status s = log->file_->Truncate(0); !s.ok()) return s;
    if (absl::Status s = log->file_->WriteAt(0, EncodeHeader()); !s.ok()) return s;
    if (absl::Status s = log->file_->Sync(); !s.ok()) return s;
    absl::MutexLock lock(&log->mu_);
    log->end_ = kHeaderBytes;
    return log;
  }
  if (absl::Status s = log->Load(*size); !s.ok()) return s;
  return log;
}

absl::Status TileLog::Load(uint64_t size) {
  std::string header(kHeaderBytes, '\0');
  if (absl::Status s = file_->ReadAt(0, kHeaderBytes, header.data()); !s.ok()) return s;
  if (std::memcmp(header.data(), kMagic, sizeof(kMagic)) != 0) {
    return absl::DataLossError(absl::StrCat(path(), ": not a tile log (no PDSMTLOG magic)"));
  }
  const uint32_t version = ByteReader(header.data() + sizeof(kMagic)).U32();
  if (version > kTileLogVersion) {
    return absl::FailedPreconditionError(
        absl::StrCat(path(), ": tile log version ", version, " is newer than this build reads (",
                     kTileLogVersion, "); use a newer coordinator"));
  }
  absl::flat_hash_map<int, Record> records;
  uint64_t at = kHeaderBytes;
  std::string why;  // why reading stopped before the end
  std::string frame(kFrameBytes, '\0');
  std::string payload;
  while (at < size) {
    if (size - at < kFrameBytes) {
      why = "a record's frame is cut short";
      break;
    }
    if (absl::Status s = file_->ReadAt(at, kFrameBytes, frame.data()); !s.ok()) return s;
    ByteReader in(frame.data());
    char magic[sizeof(kRecordMagic)];
    in.Bytes(magic, sizeof(magic));
    const int tile = in.I32();
    const uint64_t bytes = in.U64();
    const uint64_t checksum = in.U64();
    if (std::memcmp(magic, kRecordMagic, sizeof(magic)) != 0 ||
        checksum != Fnv1a64(std::string_view(frame).substr(0, kFrameBytes - 8)) || tile < 0) {
      why = "a record's frame is damaged";
      break;
    }
    if (bytes > size - at - kFrameBytes) {
      why = absl::StrCat("tile ", tile, "'s record is cut short");
      break;
    }
    payload.resize(bytes);
    if (absl::Status s = file_->ReadAt(at + kFrameBytes, bytes, payload.data()); !s.ok()) {
      return s;
    }
    // The tile file's own checksum: bytes allocated but never written read as zeros.
    if (absl::Status checked = CheckTileFileBytes(payload, path()); !checked.ok()) {
      why = absl::StrCat("tile ", tile, "'s record is damaged (", checked.message(), ")");
      break;
    }
    records[tile] = Record{at + kFrameBytes, bytes};
    at += kFrameBytes + bytes;
  }
  if (at < size) {
    spdlog::warn("{}: {} at byte {}: cutting off the last {} bytes (a crash during an append)",
                 path(), why, at, size - at);
    if (absl::Status s = file_->Truncate(at); !s.ok()) return s;
    if (absl::Status s = file_->Sync(); !s.ok()) return s;
  }
  absl::MutexLock lock(&mu_);
  end_ = at;
  records_ = std::move(records);
  return absl::OkStatus();
}

absl::Status TileLog::Append(int tile, const std::string& tile_file) {
  std::string record = EncodeFrame(tile, tile_file.size());
  record += tile_file;
  absl::MutexLock lock(&mu_);
  if (!broken_.ok()) return broken_;
  if (absl::Status s = file_->WriteAt(end_, record); !s.ok()) {
    // What was written of it must go, or the records after it would be unreadable.
    if (absl::Status cut = file_->Truncate(end_); !cut.ok()) {
      broken_ = absl::Status(s.code(), absl::StrCat(s.message(), "; then ", cut.message(),
                                                    ": the tile log cannot take more tiles"));
    }
    return s;
  }
  records_[tile] = Record{end_ + kFrameBytes, tile_file.size()};
  end_ += record.size();
  return absl::OkStatus();
}

absl::Status TileLog::Sync() {
  {
    absl::MutexLock lock(&mu_);
    if (!broken_.ok()) return broken_;
  }
  return file_->Sync();
}

absl::StatusOr<std::string> TileLog::Read(int tile) const {
  Record record;
  {
    absl::MutexLock lock(&mu_);
    const auto it = records_.find(tile);
    if (it == records_.end()) {
      return absl::NotFoundError(absl::StrCat(path(), ": no record of tile ", tile));
    }
    record = it->second;
  }
  std::string bytes(record.bytes, '\0');
  if (absl::Status s = file_->ReadAt(record.offset, record.bytes, bytes.data()); !s.ok()) {
    return absl::DataLossError(absl::StrCat("tile ", tile, ": ", s.message()));
  }
  return bytes;
}

bool TileLog::Has(int tile) const {
  absl::MutexLock lock(&mu_);
  return records_.contains(tile);
}

void TileLog::Forget(int tile) {
  absl::MutexLock lock(&mu_);
  records_.erase(tile);
}

std::vector<int> TileLog::Tiles() const {
  std::vector<int> tiles;
  {
    absl::MutexLock lock(&mu_);
    tiles.reserve(records_.size());
    for (const auto& [tile, record] : records_) tiles.push_back(tile);
  }
  std::sort(tiles.begin(), tiles.end());
  return tiles;
}

}  // namespace pdsm
