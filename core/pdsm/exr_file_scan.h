// A bounded first read of a PDSM file, before OpenEXR reads it. OpenEXR allocates what the
// sizes in a file say — a string attribute's length, a preview's width × height, a tile's
// packed and unpacked sizes — before it can tell that the file does not hold that many bytes:
// a 37 KB corrupt file made `pdsm info` allocate 2 GB. This reads the header itself, checking
// every size against the bytes the file has before keeping anything, then the tile offset
// table and the 40-byte prefix of every tile (docs/pdsm_format.md, "File layout"), so that
// what OpenEXR then allocates is bounded by a constant times the file's size. It also gives
// the header's raw attribute bytes, over which the header checksum is computed.
// Internal to core/pdsm.
#ifndef PDSM_CORE_PDSM_EXR_FILE_SCAN_H_
#define PDSM_CORE_PDSM_EXR_FILE_SCAN_H_

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace pdsm {

// One header attribute as it is stored: name\0 type\0 int32 size, then `size` value bytes.
struct ExrAttributeBytes {
  std::string name;
  std::string type;
  std::string value;
};

// The attributes of a header, in file order (OpenEXR writes them sorted by name).
struct ExrHeaderBytes {
  std::vector<ExrAttributeBytes> attributes;
  uint64_t end = 0;  // offset of the byte after the header's terminating \0

  // The attribute named `name`, or null.
  const ExrAttributeBytes* Find(std::string_view name) const;
};

// Parses a header's attribute list from `bytes` (what Imf::Header::writeTo writes: no magic
// number or version field), checking the framing as ScanPdsmFile does. DATA_LOSS naming
// `label` when it is malformed. `end` counts from the start of `bytes`.
absl::StatusOr<ExrHeaderBytes> ParseExrHeaderBytes(std::string_view bytes, absl::string_view label);

// Whether `packed` bytes of OpenEXR's ZIP or RLE compression can unpack to `unpacked` bytes:
// zlib inflates at most 1032 bytes per byte, and sizes that claim more are corrupt (refusing
// them keeps every buffer OpenEXR allocates for a tile within a constant times its bytes).
bool ExrUnpackedSizeIsPossible(uint64_t packed, uint64_t unpacked);

// Reads and checks `path` within its own length: a single-part file, or a multipart one (one
// part per light; docs/pdsm_format.md, "Several lights") whose every part is checked as below.
// DATA_LOSS naming the file (and the part) when:
// - the magic number is not OpenEXR's, or the version field is not a deep file of format 2
//   ("not a PDSM file");
// - a multipart file has no part, more than 65536, a part without a string `name` or two
//   parts of one name, or a chunk whose part number is not its part's;
// - an attribute's name or type is not NUL-terminated within 255 bytes, its size is negative
//   or larger than what is left of the file, a fixed-size type (int, double, v3d, box2i,
//   tiledesc, …) has another size, or a structured value (chlist, stringvector, preview) does
//   not fill its size exactly;
// - "type" is not "deeptile", dataWindow is not [0, w-1] × [0, h-1], tiles are not square,
//   single-level and at most 4096 pixels, chunkCount is not the number of tiles, or the
//   offset table does not fit in the file;
// - a tile's offset is not inside the file, its prefix names another tile or a level other
//   than 0, its packed sizes run past the end of the file, or an unpacked size (the sample
//   count table: the tile's pixels × 4 bytes) is more than zlib could inflate from its
//   packed bytes (at most 1032:1).
// `check_header`, when given, runs on each header's attributes before anything else of the
// header is judged, and its error is returned first (the checksum: a damaged header is named
// as such rather than by what it damaged). NOT_FOUND when there is no file. On success every
// part's header attributes, in file order (one for a single-part file).
absl::StatusOr<std::vector<ExrHeaderBytes>> ScanPdsmFile(
    const std::string& path,
    const std::function<absl::Status(const ExrHeaderBytes&)>& check_header = nullptr);

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_EXR_FILE_SCAN_H_
