// The PDSM header as OpenEXR attributes (docs/pdsm_format.md): the conversion both ways, the
// checks a header must pass to be written or read, the channel names, and the one place
// OpenEXR's exceptions become statuses. Internal to core/pdsm (pdsm_file.cc is the public
// face).
#ifndef PDSM_CORE_PDSM_PDSM_EXR_HEADER_H_
#define PDSM_CORE_PDSM_PDSM_EXR_HEADER_H_

#include <OpenEXR/ImfHeader.h>

#include <cstdint>
#include <limits>
#include <optional>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "core/pdsm/exr_file_scan.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

inline constexpr char kDepthChannel[] = "Z";
inline constexpr char kAttenuationChannel[] = "attenuation";

// The sample count table of a deep tile holds cumulative int32 counts, and OpenEXR sizes a
// tile's unpacked data with an int: keep both within range.
inline constexpr uint64_t kMaxVerticesPerTile =
    static_cast<uint64_t>(std::numeric_limits<int32_t>::max()) / (2 * sizeof(float));

// The status of the exception being handled (call only inside a catch block): NOT_FOUND,
// PERMISSION_DENIED, RESOURCE_EXHAUSTED (out of memory), DATA_LOSS otherwise; the message is
// "<action> <path>: <what>". OpenEXR reports everything by throwing; nothing escapes core/pdsm.
absl::Status StatusFromCurrentException(absl::string_view path, absl::string_view action);

// What makes a deep tiled header a PDSM's pixels: DEEPTILE, ZIPS compression, INCREASING_Y,
// one level of tile_width x tile_height tiles, FLOAT channels Z and attenuation. Everything
// OpenEXR's compressed tile bytes depend on besides the pixels (tile_chunk.h).
void SetPdsmPixelLayout(Imf::Header* exr, int tile_width, int tile_height);

// The deep tiled header of a PDSM: channels, tiling, compression, chunkCount, every pdsm*
// attribute, and the header checksum over all of them (SealExrHeader).
// The part is named h.light_name when that is not empty. `display_window`: the parts of a
// multipart file share one (OpenEXR requires it); unset, the data window.
// REQUIRES: ValidateHeaderForWrite(h) is OK.
Imf::Header ExrHeaderFromPdsm(const PdsmHeader& h,
                              const std::optional<Imath::Box2i>& display_window = std::nullopt);

// INVALID_ARGUMENT naming `path` when `h` cannot be written (sizes, tile size, version).
absl::Status ValidateHeaderForWrite(const PdsmHeader& h, absl::string_view path);

// The header checksum (docs/pdsm_format.md, "Header checksum"): a string attribute holding
// the SHA-256, 64 lowercase hex digits, of every attribute record of the header (name\0
// type\0 int32 size, value) except its own, in file order. Every writer adds it; a reader
// verifies it when present, before it believes any attribute.
inline constexpr char kHeaderChecksumAttribute[] = "pdsmHeaderSha256";

// The checksum of `header`'s records (ExrHeaderBytes: exr_file_scan.h).
std::string HeaderChecksum(const ExrHeaderBytes& header);

// Sets `exr`'s checksum attribute for its other attributes as they are now (replacing one it
// has). REQUIRES: every attribute the file will carry is set, chunkCount included (OpenEXR
// adds it when writing otherwise, and the checksum would not cover it).
void SealExrHeader(Imf::Header* exr);

// OK when `header` has no checksum attribute (files from before it existed) or the checksum
// matches; DATA_LOSS naming `path` when it does not, or is not a string of 64 hex digits.
absl::Status VerifyHeaderChecksum(const ExrHeaderBytes& header, absl::string_view path);

// The PdsmHeader of a file's header. DATA_LOSS naming `path` and the attribute when it is not
// a PDSM or an attribute is missing, mistyped or out of range; FAILED_PRECONDITION for a
// format version newer than this build reads.
absl::StatusOr<PdsmHeader> PdsmHeaderFromExr(const Imf::Header& exr, absl::string_view path);

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_PDSM_EXR_HEADER_H_
