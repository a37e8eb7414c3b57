// What the reader believes of a damaged file (issue #17, findings 6 and 7): sizes in the file
// are checked against the file before OpenEXR allocates from them, and the header checksum
// turns any change of the header into DATA_LOSS instead of a different answer.
#include <OpenEXR/ImfDeepTiledInputFile.h>
#include <OpenEXR/ImfDeepTiledOutputFile.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfVecAttribute.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <string>

#include "core/pdsm/exr_file_scan.h"
#include "core/pdsm/pdsm_exr_header.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_test_images.h"
#include "core/util/little_endian.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

using ::pdsm::testing::CutTiles;
using ::pdsm::testing::FullHeader;
using ::pdsm::testing::RandomImage;
using ::pdsm::testing::TempDir;
using ::pdsm::testing::WriteTiles;
using ::testing::HasSubstr;

std::string Bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void Put(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// A small PDSM (40x24, 16-pixel tiles: 6 tiles) and its bytes.
struct SmallFile {
  explicit SmallFile(const TempDir& dir) : path(dir.File("small.exr")) {
    const PdsmImage image = RandomImage(FullHeader(40, 24, 16), 7);
    EXPECT_TRUE(WriteTiles(path, image.header, CutTiles(image)).ok());
    bytes = Bytes(path);
    absl::StatusOr<std::vector<ExrHeaderBytes>> parts = ScanPdsmFile(path);
    EXPECT_TRUE(parts.ok()) << parts.status();
    EXPECT_EQ(parts->size(), 1u);
    header_end = parts->front().end;
    table_end = header_end + 6 * 8;
  }
  // Offset of attribute `name`'s int32 size field.
  size_t SizeFieldOf(const std::string& name) const {
    const size_t at = bytes.find(name + '\0');
    EXPECT_NE(at, std::string::npos) << name;
    return bytes.find('\0', at + name.size() + 1) + 1;
  }
  std::string path;
  std::string bytes;
  uint64_t header_end = 0, table_end = 0;
};

// The image written again: equal bytes mean an equal header and equal functions.
std::string Rewritten(const PdsmImage& image, const TempDir& dir) {
  const std::string path = dir.File("rewritten.exr");
  std::vector<PdsmTile> tiles = CutTiles(image);
  EXPECT_TRUE(WriteTiles(path, image.header, tiles).ok());
  return Bytes(path);
}

TEST(HeaderChecksum, EveryWriterAddsItAndTheReaderVerifiesIt) {
  TempDir dir;
  const SmallFile file(dir);
  absl::StatusOr<std::vector<ExrHeaderBytes>> parts = ScanPdsmFile(file.path);
  ASSERT_TRUE(parts.ok()) << parts.status();
  ASSERT_EQ(parts->size(), 1u);
  const ExrHeaderBytes* header = &parts->front();
  const ExrAttributeBytes* checksum = header->Find(kHeaderChecksumAttribute);
  ASSERT_NE(checksum, nullptr);
  EXPECT_EQ(checksum->type, "string");
  EXPECT_EQ(checksum->value, HeaderChecksum(*header));
  EXPECT_TRUE(VerifyHeaderChecksum(*header, file.path).ok());
  // It covers OpenEXR's own attributes too, chunkCount included: the writer set them first.
  for (const char* name : {"chunkCount", "dataWindow", "tiles", "channels", "version"}) {
    EXPECT_NE(header->Find(name), nullptr) << name;
  }
}

// A header edited by a tool that does not know the checksum: the light moved, the answers
// would differ, so the file is refused.
TEST(HeaderChecksum, AnEditedHeaderIsDataLoss) {
  TempDir dir;
  const SmallFile file(dir);
  Imf::Header header = Imf::MultiPartInputFile(file.path.c_str()).header(0);
  header.typedAttribute<Imf::V3dAttribute>("pdsmLightCenter").value().x += 1.0;
  const std::string edited = dir.File("edited.exr");
  {
    Imf::DeepTiledInputFile in(file.path.c_str());
    Imf::DeepTiledOutputFile out(edited.c_str(), header);
    out.copyPixels(in);
  }
  const absl::Status s = ReadPdsm(edited).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss) << s;
  EXPECT_THAT(s.message(), HasSubstr(edited));
  EXPECT_THAT(s.message(), HasSubstr(kHeaderChecksumAttribute));
  EXPECT_EQ(ReadPdsmHeader(edited).status().code(), absl::StatusCode::kDataLoss);
}

// Files from before the checksum read as their version says.
TEST(HeaderChecksum, AFileWithoutItReadsAsBefore) {
  TempDir dir;
  const PdsmImage image = RandomImage(FullHeader(40, 24, 16), 7);
  const SmallFile file(dir);
  const Imf::Header sealed = Imf::MultiPartInputFile(file.path.c_str()).header(0);
  Imf::Header header(40, 24);
  for (auto it = sealed.begin(); it != sealed.end(); ++it) {
    if (std::string(it.name()) != kHeaderChecksumAttribute)
      header.insert(it.name(), it.attribute());
  }
  const std::string old_path = dir.File("old.exr");
  {
    // The tiles as the writer stored them, copied unchanged under the unsealed header.
    Imf::DeepTiledInputFile in(file.path.c_str());
    Imf::DeepTiledOutputFile out(old_path.c_str(), header);
    out.copyPixels(in);
  }
  absl::StatusOr<PdsmImage> read = ReadPdsm(old_path);
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(Rewritten(*read, dir), file.bytes);
  EXPECT_EQ(read->header.format_version, 1);
}

// The property of the issue (300 single-bit flips in the first 1,400 bytes gave 5 silently
// different answers): every single-bit flip anywhere in the header and the tile offset table
// is DATA_LOSS, or reads as exactly the same PDSM (a flip in a name OpenEXR ignores, e.g. the
// checksum's own).
TEST(HeaderChecksum, EverySingleBitFlipOfTheHeaderIsDataLossOrChangesNothing) {
  TempDir dir;
  const SmallFile file(dir);
  const std::string flipped_path = dir.File("flipped.exr");
  int data_loss = 0, unchanged = 0;
  for (uint64_t bit = 0; bit < file.table_end * 8; ++bit) {
    std::string flipped = file.bytes;
    flipped[bit / 8] = static_cast<char>(flipped[bit / 8] ^ (1 << (bit % 8)));
    Put(flipped_path, flipped);
    absl::StatusOr<PdsmImage> read = ReadPdsm(flipped_path);
    if (!read.ok()) {
      ASSERT_EQ(read.status().code(), absl::StatusCode::kDataLoss)
          << "bit " << bit << ": " << read.status();
      ++data_loss;
      continue;
    }
    ASSERT_EQ(Rewritten(*read, dir), file.bytes) << "bit " << bit << " changed the answer";
    ++unchanged;
  }
  EXPECT_GT(data_loss, 0.99 * (data_loss + unchanged)) << unchanged << " flips read unchanged";
}

// Finding 6: a string attribute that claims 2 GB in a small file is refused from the file's
// own size, before anything is allocated for it (the end-to-end test measures the memory).
TEST(ExrFileScan, SizesLargerThanTheFileAreRefusedBeforeReading) {
  TempDir dir;
  const SmallFile file(dir);
  std::string bytes = file.bytes;
  ByteWriter(&bytes[file.SizeFieldOf("pdsmSceneName")]).I32(0x7fffffff);
  const std::string path = dir.File("claims.exr");
  Put(path, bytes);
  const absl::Status s = ReadPdsm(path).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss) << s;
  EXPECT_THAT(s.message(), HasSubstr(path));
  EXPECT_THAT(s.message(), HasSubstr("pdsmSceneName claims 2147483647 bytes"));
}

// A preview attribute (OpenEXR allocates width x height x 4 from its first 8 bytes) spliced
// into the header, and a tile claiming 2 GB of samples from a few packed bytes.
TEST(ExrFileScan, InnerSizesAreCheckedToo) {
  TempDir dir;
  const SmallFile file(dir);
  std::string preview("preview\0preview\0\x08\0\0\0", 20);
  preview += std::string("\xff\xff\0\0\xff\xff\0\0", 8);  // 65535 x 65535
  std::string bytes = file.bytes;
  bytes.insert(8, preview);
  const std::string with_preview = dir.File("preview.exr");
  Put(with_preview, bytes);
  const absl::Status p = ReadPdsm(with_preview).status();
  EXPECT_EQ(p.code(), absl::StatusCode::kDataLoss) << p;
  EXPECT_THAT(p.message(), HasSubstr("preview"));

  bytes = file.bytes;
  const uint64_t tile0 = ByteReader(&bytes[file.header_end]).U64();
  ByteWriter(&bytes[tile0 + 32]).U64(0x7fffffff);  // unpacked sample data size
  const std::string bomb = dir.File("bomb.exr");
  Put(bomb, bytes);
  const absl::Status b = ReadPdsm(bomb).status();
  EXPECT_EQ(b.code(), absl::StatusCode::kDataLoss) << b;
  EXPECT_THAT(b.message(), HasSubstr("tile 0: impossible sizes"));

  bytes = file.bytes;
  ByteWriter(&bytes[file.SizeFieldOf("chunkCount") + 4]).I32(1 << 30);
  const std::string chunks = dir.File("chunks.exr");
  Put(chunks, bytes);
  EXPECT_EQ(ReadPdsm(chunks).status().code(), absl::StatusCode::kDataLoss);
}

}  // namespace
}  // namespace pdsm
