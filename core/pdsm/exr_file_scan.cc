#include "core/pdsm/exr_file_scan.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <limits>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/pdsm/pdsm_image.h"
#include "core/util/file_system.h"
#include "core/util/little_endian.h"

namespace pdsm {
namespace {

// OpenEXR's limit on attribute and type names (Name::MAX_LENGTH), terminator excluded.
constexpr size_t kMaxNameLength = 255;
// Prefix of a deep tile chunk: dx, dy, lx, ly (int32), three uint64 sizes.
constexpr uint64_t kTilePrefixBytes = 4 * 4 + 3 * 8;
// Parts of a multipart PDSM: one per light (scene.h's kMaxLights), with room for the
// several faces a light may one day bake into.
constexpr size_t kMaxParts = 65536;
// zlib cannot inflate more than 1032 bytes per byte of deflate stream; OpenEXR's ZIP and RLE
// schemes stay below that. Sizes claiming more are corrupt, and refusing them keeps every
// buffer OpenEXR allocates for a tile within a constant times the tile's bytes in the file.
constexpr uint64_t kMaxInflateRatio = 1100;
constexpr uint64_t kInflateSlack = 4096;

// Where the bytes come from: the file (pread) or memory (a header being written).
class Source {
 public:
  virtual ~Source() = default;
  virtual uint64_t size() const = 0;
  // Appends bytes [offset, offset + n) to *out. REQUIRES: offset + n <= size().
  virtual bool Read(uint64_t offset, size_t n, std::string* out) const = 0;
};

class MemorySource final : public Source {
 public:
  explicit MemorySource(std::string_view bytes) : bytes_(bytes) {}
  uint64_t size() const override { return bytes_.size(); }
  bool Read(uint64_t offset, size_t n, std::string* out) const override {
    out->append(bytes_.data() + offset, n);
    return true;
  }

 private:
  std::string_view bytes_;
};

class FileSource final : public Source {
 public:
  FileSource(int fd, uint64_t size) : fd_(fd), size_(size) {}
  ~FileSource() override { ::close(fd_); }
  uint64_t size() const override { return size_; }
  bool Read(uint64_t offset, size_t n, std::string* out) const override {
    const size_t start = out->size();
    out->resize(start + n);
    size_t done = 0;
    while (done < n) {
      const ssize_t got =
          ::pread(fd_, out->data() + start + done, n - done, static_cast<off_t>(offset + done));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) return false;
      done += static_cast<size_t>(got);
    }
    return true;
  }

 private:
  const int fd_;
  const uint64_t size_;
};

size_t FixedSize(std::string_view type) {
  struct Entry {
    std::string_view type;
    size_t size;
  };
  static constexpr Entry kFixed[] = {
      {"int", 4},       {"float", 4},    {"double", 8},   {"v2i", 8},
      {"v2f", 8},       {"v2d", 16},     {"v3i", 12},     {"v3f", 12},
      {"v3d", 24},      {"box2i", 16},   {"box2f", 16},   {"compression", 1},
      {"lineOrder", 1}, {"tiledesc", 9}, {"envmap", 1},   {"deepImageState", 1},
      {"rational", 8},  {"timecode", 8}, {"keycode", 28}, {"m33f", 36},
      {"m33d", 72},     {"m44f", 64},    {"m44d", 128},   {"chromaticities", 32}};
  for (const Entry& e : kFixed) {
    if (e.type == type) return e.size;
  }
  return 0;
}

// A NUL-terminated name of at most kMaxNameLength characters at the start of `bytes`; its
// length without the terminator, or npos.
size_t NameLength(std::string_view bytes) {
  const size_t n = bytes.find('\0');
  return n == std::string_view::npos || n > kMaxNameLength ? std::string_view::npos : n;
}

// OpenEXR reads a chlist until an empty name: it must end exactly at the attribute's end.
bool ChannelListFills(std::string_view v) {
  size_t pos = 0;
  while (pos < v.size()) {
    const size_t n = NameLength(v.substr(pos));
    if (n == std::string_view::npos) return false;
    pos += n + 1;
    if (n == 0) return pos == v.size();
    pos += 16;  // pixel type, pLinear + 3 reserved, x and y sampling
  }
  return false;
}

bool StringVectorFills(std::string_view v) {
  size_t pos = 0;
  while (pos < v.size()) {
    if (v.size() - pos < 4) return false;
    const int32_t length = ByteReader(v.data() + pos).I32();
    pos += 4;
    if (length < 0 || static_cast<size_t>(length) > v.size() - pos) return false;
    pos += static_cast<size_t>(length);
  }
  return true;
}

// Why a value does not fit its type's layout, or "" when it does.
std::string ValueProblem(const ExrAttributeBytes& a) {
  if (const size_t fixed = FixedSize(a.type); fixed != 0) {
    return a.value.size() == fixed ? "" : absl::StrCat("a ", a.type, " has ", fixed, " bytes");
  }
  if (a.type == "chlist" && !ChannelListFills(a.value)) return "malformed channel list";
  if (a.type == "stringvector" && !StringVectorFills(a.value)) return "malformed string vector";
  if (a.type == "preview") {
    if (a.value.size() < 8) return "malformed preview";
    ByteReader in(a.value.data());
    const uint64_t w = in.U32(), h = in.U32();
    const uint64_t pixels = (a.value.size() - 8) / 4;
    if ((a.value.size() - 8) % 4 != 0 || (w != 0 && h > pixels / w) || w * h != pixels) {
      return "preview size disagrees with its width x height";
    }
  }
  return "";
}

// Reads the attributes from `start` to the terminating empty name, every size checked
// against what the source holds before anything is read.
class HeaderParser {
 public:
  HeaderParser(const Source& source, uint64_t start, absl::string_view label)
      : source_(source), pos_(start), label_(label) {}

  absl::StatusOr<ExrHeaderBytes> Parse() {
    ExrHeaderBytes header;
    for (;;) {
      ExrAttributeBytes a;
      if (!ReadName("attribute name", &a.name)) return error_;
      if (a.name.empty()) break;
      if (!ReadName(absl::StrCat("type of attribute ", a.name), &a.type)) return error_;
      std::string size_bytes;
      if (!ReadBytes(4, absl::StrCat("size of attribute ", a.name), &size_bytes)) return error_;
      const int32_t size = ByteReader(size_bytes.data()).I32();
      if (size < 0 || static_cast<uint64_t>(size) > source_.size() - pos_) {
        return Corrupt(absl::StrFormat("attribute %s claims %d bytes, %d are left in the file",
                                       a.name, size, source_.size() - pos_));
      }
      if (!ReadBytes(static_cast<size_t>(size), a.name, &a.value)) return error_;
      if (const std::string problem = ValueProblem(a); !problem.empty()) {
        return Corrupt(absl::StrFormat("attribute %s (%s, %d bytes): %s", a.name, a.type,
                                       a.value.size(), problem));
      }
      header.attributes.push_back(std::move(a));
    }
    header.end = pos_;
    return header;
  }

 private:
  bool ReadName(absl::string_view what, std::string* out) {
    const size_t n = static_cast<size_t>(std::min<uint64_t>(kMaxNameLength + 1, Left()));
    std::string bytes;
    if (n == 0 || !source_.Read(pos_, n, &bytes)) return Fail(absl::StrCat("truncated ", what));
    const size_t length = NameLength(bytes);
    if (length == std::string_view::npos) {
      return Fail(absl::StrCat(what, " is not NUL-terminated within ", kMaxNameLength, " bytes"));
    }
    out->assign(bytes, 0, length);
    pos_ += length + 1;
    return true;
  }

  bool ReadBytes(size_t n, absl::string_view what, std::string* out) {
    if (n > Left() || !source_.Read(pos_, n, out)) return Fail(absl::StrCat("truncated ", what));
    pos_ += n;
    return true;
  }

  uint64_t Left() const { return source_.size() - pos_; }

  bool Fail(absl::string_view message) {
    error_ = Corrupt(message);
    return false;
  }
  absl::Status Corrupt(absl::string_view message) const {
    return absl::DataLossError(absl::StrCat(label_, ": corrupt header: ", message));
  }

  const Source& source_;
  uint64_t pos_;
  const std::string label_;
  absl::Status error_;
};

absl::Status NotAPdsm(absl::string_view path, absl::string_view why) {
  return absl::DataLossError(absl::StrCat("not a PDSM file: ", path, " (", why, ")"));
}

// Magic number and version field: OpenEXR, format 2, deep ("non-image", 0x800), single-part
// or multipart (0x1000); long names (0x400) allowed, tiled (0x200: a single-part image) and
// unknown flags not. Sets `*multipart`.
absl::Status CheckMagicAndVersion(const Source& source, absl::string_view path, bool* multipart) {
  std::string bytes;
  if (source.size() < 8 || !source.Read(0, 8, &bytes) ||
      std::memcmp(bytes.data(), "\x76\x2f\x31\x01", 4) != 0) {
    return NotAPdsm(path, "not an OpenEXR file");
  }
  const uint32_t version = ByteReader(bytes.data() + 4).U32();
  if ((version & 0xff) != 2 || (version & 0x800) == 0 || (version & ~uint32_t{0x1cff}) != 0) {
    return NotAPdsm(
        path, absl::StrFormat("version field 0x%08x: not a deep tiled OpenEXR 2 file", version));
  }
  *multipart = (version & 0x1000) != 0;
  return absl::OkStatus();
}

// The tile grid the header describes, checked.
struct Grid {
  int64_t width = 0, height = 0, tile = 0, tiles_x = 0, tiles_y = 0;
  int64_t Count() const { return tiles_x * tiles_y; }
};

absl::StatusOr<Grid> CheckLayout(const ExrHeaderBytes& h, absl::string_view path) {
  const ExrAttributeBytes* type = h.Find("type");
  if (type == nullptr || type->type != "string" || type->value != "deeptile") {
    return NotAPdsm(path, "not a deep tiled OpenEXR image");
  }
  const ExrAttributeBytes* window = h.Find("dataWindow");
  const ExrAttributeBytes* tiles = h.Find("tiles");
  const ExrAttributeBytes* chunks = h.Find("chunkCount");
  if (window == nullptr || window->type != "box2i" || tiles == nullptr ||
      tiles->type != "tiledesc" || chunks == nullptr || chunks->type != "int") {
    return absl::DataLossError(
        absl::StrCat(path,
                     ": corrupt header: no box2i dataWindow, tiledesc tiles or int "
                     "chunkCount"));
  }
  ByteReader w(window->value.data());
  const int32_t x0 = w.I32(), y0 = w.I32(), x1 = w.I32(), y1 = w.I32();
  if (x0 != 0 || y0 != 0 || x1 < 0 || y1 < 0 || x1 == std::numeric_limits<int32_t>::max() ||
      y1 == std::numeric_limits<int32_t>::max()) {
    return absl::DataLossError(
        absl::StrCat(path, ": data window is not [0, width-1] x [0, height-1]"));
  }
  ByteReader t(tiles->value.data());
  const uint32_t tx = t.U32(), ty = t.U32();
  const uint8_t mode = static_cast<uint8_t>(tiles->value[8]);
  if ((mode & 0x0f) != 0 || tx != ty || tx < 1 || tx > static_cast<uint32_t>(kMaxTileSize)) {
    return absl::DataLossError(absl::StrCat(path,
                                            ": tiles are not square, single-level and at "
                                            "most ",
                                            kMaxTileSize, " pixels"));
  }
  Grid g;
  g.width = int64_t{x1} + 1;
  g.height = int64_t{y1} + 1;
  g.tile = tx;
  g.tiles_x = (g.width + g.tile - 1) / g.tile;
  g.tiles_y = (g.height + g.tile - 1) / g.tile;
  const int32_t chunk_count = ByteReader(chunks->value.data()).I32();
  if (chunk_count != g.Count()) {
    return absl::DataLossError(absl::StrFormat("%s: chunkCount %d, but the grid has %d tiles", path,
                                               chunk_count, g.Count()));
  }
  return g;
}

// Where a part's chunks are, and how they are framed: a multipart file's chunks start with
// the number of their part.
struct PartFraming {
  int part = -1;      // -1: a single-part file (no part number before a chunk)
  std::string label;  // "path" or "path: part 2"
  uint64_t prefix_bytes() const { return part < 0 ? kTilePrefixBytes : kTilePrefixBytes + 4; }
};

// One tile's prefix against the grid and the file.
absl::Status CheckTile(const Source& source, const Grid& g, int64_t index, uint64_t offset,
                       uint64_t first_chunk, const PartFraming& framing) {
  const auto corrupt = [&](absl::string_view why) {
    return absl::DataLossError(absl::StrFormat("%s: tile %d: %s", framing.label, index, why));
  };
  const uint64_t prefix = framing.prefix_bytes();
  if (offset < first_chunk || offset > source.size() || source.size() - offset < prefix) {
    return corrupt("its offset is outside the file (truncated?)");
  }
  std::string bytes;
  if (!source.Read(offset, prefix, &bytes)) return corrupt("cannot be read");
  ByteReader in(bytes.data());
  if (framing.part >= 0 && in.I32() != framing.part) {
    return corrupt("its chunk names another part");
  }
  const int32_t dx = in.I32(), dy = in.I32(), lx = in.I32(), ly = in.I32();
  const uint64_t packed_table = in.U64(), packed_data = in.U64(), unpacked_data = in.U64();
  if (dx != index % g.tiles_x || dy != index / g.tiles_x || lx != 0 || ly != 0) {
    return corrupt("its chunk names another tile");
  }
  const uint64_t left = source.size() - offset - prefix;
  if (packed_table > left || packed_data > left - packed_table) {
    return corrupt("its packed sizes run past the end of the file (truncated?)");
  }
  const int64_t w = std::min(g.tile, g.width - dx * g.tile);
  const int64_t h = std::min(g.tile, g.height - dy * g.tile);
  const uint64_t unpacked_table = static_cast<uint64_t>(w * h) * 4;
  // The packed bytes are in the file (checked above); what they unpack to must be possible.
  if (!ExrUnpackedSizeIsPossible(packed_table, unpacked_table) ||
      !ExrUnpackedSizeIsPossible(packed_data, unpacked_data) ||
      unpacked_data > static_cast<uint64_t>(std::numeric_limits<int32_t>::max())) {
    return corrupt(
        absl::StrFormat("impossible sizes (sample counts %d packed / %d bytes, "
                        "samples %d packed / %d bytes)",
                        packed_table, unpacked_table, packed_data, unpacked_data));
  }
  return absl::OkStatus();
}

// The offset table of one part, at `table_start`, and every tile it points to (at or after
// `first_chunk`, the end of the last part's table).
absl::Status CheckTiles(const Source& source, const Grid& g, uint64_t table_start,
                        uint64_t first_chunk, const PartFraming& framing) {
  const uint64_t count = static_cast<uint64_t>(g.Count());
  std::string table;
  if (!source.Read(table_start, count * 8, &table)) {
    return absl::DataLossError(absl::StrCat(framing.label, ": cannot read the tile offset table"));
  }
  for (uint64_t i = 0; i < count; ++i) {
    const uint64_t offset = ByteReader(table.data() + 8 * i).U64();
    if (absl::Status s =
            CheckTile(source, g, static_cast<int64_t>(i), offset, first_chunk, framing);
        !s.ok()) {
      return s;
    }
  }
  return absl::OkStatus();
}

// A multipart file's headers, each with a distinct string `name` (OpenEXR requires one),
// ended by an empty header; at most kMaxParts. `*tables_start`: the byte after the empty header.
absl::StatusOr<std::vector<ExrHeaderBytes>> ParseParts(const Source& source, absl::string_view path,
                                                       uint64_t* tables_start) {
  std::vector<ExrHeaderBytes> parts;
  std::set<std::string> names;
  uint64_t pos = 8;
  for (;;) {
    absl::StatusOr<ExrHeaderBytes> header = HeaderParser(source, pos, path).Parse();
    if (!header.ok()) return header.status();
    pos = header->end;
    if (header->attributes.empty()) break;  // the empty header after the last part
    if (parts.size() == kMaxParts) {
      return absl::DataLossError(
          absl::StrFormat("%s: more than %d parts (corrupt header?)", path, kMaxParts));
    }
    const ExrAttributeBytes* name = header->Find("name");
    if (name == nullptr || name->type != "string" || name->value.empty()) {
      return absl::DataLossError(
          absl::StrFormat("%s: part %d has no string attribute \"name\"", path, parts.size()));
    }
    if (!names.insert(name->value).second) {
      return absl::DataLossError(
          absl::StrFormat("%s: two parts are named \"%s\"", path, absl::CEscape(name->value)));
    }
    parts.push_back(*std::move(header));
  }
  if (parts.empty())
    return absl::DataLossError(absl::StrCat(path, ": a multipart file of no part"));
  *tables_start = pos;
  return parts;
}

}  // namespace

bool ExrUnpackedSizeIsPossible(uint64_t packed, uint64_t unpacked) {
  return unpacked <= kMaxInflateRatio * packed + kInflateSlack;
}

const ExrAttributeBytes* ExrHeaderBytes::Find(std::string_view name) const {
  for (const ExrAttributeBytes& a : attributes) {
    if (a.name == name) return &a;
  }
  return nullptr;
}

absl::StatusOr<ExrHeaderBytes> ParseExrHeaderBytes(std::string_view bytes,
                                                   absl::string_view label) {
  const MemorySource source(bytes);
  return HeaderParser(source, 0, label).Parse();
}

absl::StatusOr<std::vector<ExrHeaderBytes>> ScanPdsmFile(
    const std::string& path,
    const std::function<absl::Status(const ExrHeaderBytes&)>& check_header) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int error_number = errno;
    if (error_number == ENOENT) return absl::NotFoundError(absl::StrCat("no such file: ", path));
    return ErrnoStatus(error_number, absl::StrCat("cannot read ", path));
  }
  struct stat info;
  if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
    ::close(fd);
    return absl::DataLossError(absl::StrCat("not a PDSM file: ", path, " (not a regular file)"));
  }
  const FileSource source(fd, static_cast<uint64_t>(info.st_size));
  bool multipart = false;
  if (absl::Status s = CheckMagicAndVersion(source, path, &multipart); !s.ok()) return s;
  std::vector<ExrHeaderBytes> parts;
  uint64_t tables_start = 0;  // the offset tables, one per part in part order, then the chunks
  if (multipart) {
    absl::StatusOr<std::vector<ExrHeaderBytes>> headers = ParseParts(source, path, &tables_start);
    if (!headers.ok()) return headers.status();
    parts = *std::move(headers);
  } else {
    absl::StatusOr<ExrHeaderBytes> header = HeaderParser(source, 8, path).Parse();
    if (!header.ok()) return header.status();
    tables_start = header->end;
    parts.push_back(*std::move(header));
  }
  std::vector<PartFraming> framing(parts.size());
  std::vector<Grid> grids;
  for (size_t p = 0; p < parts.size(); ++p) {
    framing[p].part = multipart ? static_cast<int>(p) : -1;
    framing[p].label = multipart ? absl::StrFormat("%s: part %d", path, p) : path;
    if (check_header) {
      if (absl::Status s = check_header(parts[p]); !s.ok()) return s;
    }
    absl::StatusOr<Grid> grid = CheckLayout(parts[p], framing[p].label);
    if (!grid.ok()) return grid.status();
    grids.push_back(*grid);
  }
  uint64_t table_entries = 0;
  for (const Grid& g : grids) table_entries += static_cast<uint64_t>(g.Count());
  if (tables_start > source.size() || (source.size() - tables_start) / 8 < table_entries) {
    return absl::DataLossError(
        absl::StrFormat("%s: the offset table of %d tiles does not fit in the file (truncated?)",
                        path, table_entries));
  }
  const uint64_t first_chunk = tables_start + table_entries * 8;
  uint64_t table_start = tables_start;
  for (size_t p = 0; p < parts.size(); ++p) {
    if (absl::Status s = CheckTiles(source, grids[p], table_start, first_chunk, framing[p]);
        !s.ok()) {
      return s;
    }
    table_start += static_cast<uint64_t>(grids[p].Count()) * 8;
  }
  return parts;
}

}  // namespace pdsm
