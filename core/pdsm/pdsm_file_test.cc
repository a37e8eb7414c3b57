#include "core/pdsm/pdsm_file.h"
#include "absl/strings/str_cat.h"
#include "core/pdsm/pdsm_exr_header.h"
#include "core/pdsm/pdsm_test_images.h"
#include "core/util/fault_injecting_file_system.h"
#include "core/util/file_system.h"
#include "tests/test_support.h"
#include "tests/write_faults.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfDeepFrameBuffer.h>
#include <OpenEXR/ImfDeepTiledOutputFile.h>
#include <OpenEXR/ImfDoubleAttribute.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfTileDescription.h>
#include <OpenEXR/ImfVecAttribute.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <limits>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <ostream>
#include <random>
#include <string>
#include <tuple>
#include <vector>

namespace pdsm {

namespace {

namespace fs = std::filesystem;
using ::pdsm::testing::CutTile;
using ::pdsm::testing::CutTiles;
using ::pdsm::testing::ExpectSameTile;
using ::pdsm::testing::FullHeader;
using ::pdsm::testing::RandomImage;
using ::pdsm::testing::RefineSomePixels;
using ::pdsm::testing::WriteTiles;
using ::testing::HasSubstr;

void ExpectVec3Eq(const glm::dvec3& a, const glm::dvec3& b) {
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.y, b.y);
  EXPECT_EQ(a.z, b.z);
}

void ExpectHeadersEqual(const PdsmHeader& a, const PdsmHeader& b) {
  EXPECT_EQ(a.format_version, b.format_version);
  EXPECT_EQ(a.scene_name, b.scene_name);
  EXPECT_EQ(a.light_name, b.light_name);
  EXPECT_EQ(a.light_shape, b.light_shape);
  EXPECT_EQ(a.light_half_width, b.light_half_width);
  EXPECT_EQ(a.light_half_height, b.light_half_height);
  EXPECT_EQ(a.light_radius, b.light_radius);
  EXPECT_EQ(a.tan_half_angle, b.tan_half_angle);
  EXPECT_EQ(a.geometry.projection, b.geometry.projection);
  ExpectVec3Eq(a.geometry.frame.center, b.geometry.frame.center);
  ExpectVec3Eq(a.geometry.frame.u, b.geometry.frame.u);
  ExpectVec3Eq(a.geometry.frame.v, b.geometry.frame.v);
  ExpectVec3Eq(a.geometry.frame.n, b.geometry.frame.n);
  EXPECT_EQ(a.geometry.width, b.geometry.width);
  EXPECT_EQ(a.geometry.height, b.geometry.height);
  EXPECT_EQ(a.geometry.s_min, b.geometry.s_min);
  EXPECT_EQ(a.geometry.s_max, b.geometry.s_max);
  EXPECT_EQ(a.geometry.t_min, b.geometry.t_min);
  EXPECT_EQ(a.geometry.t_max, b.geometry.t_max);
  EXPECT_EQ(a.geometry.z_near, b.geometry.z_near);
  EXPECT_EQ(a.geometry.z_far, b.geometry.z_far);
  EXPECT_EQ(a.samples, b.samples);
  EXPECT_EQ(a.shadow_map_resolution, b.shadow_map_resolution);
  EXPECT_EQ(a.epsilon, b.epsilon);
  EXPECT_EQ(a.compression_metric, b.compression_metric);
  EXPECT_EQ(a.depth_bias, b.depth_bias);
  EXPECT_EQ(a.slope_bias, b.slope_bias);
  EXPECT_EQ(a.sampling, b.sampling);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.tile_size, b.tile_size);
  EXPECT_EQ(a.max_refinement, b.max_refinement);
}

void ExpectImagesEqual(const PdsmImage& expected, const PdsmImage& actual) {
  ExpectHeadersEqual(expected.header, actual.header);
  EXPECT_EQ(expected.offsets, actual.offsets);
  ASSERT_EQ(expected.vertices.size(), actual.vertices.size());
  EXPECT_TRUE(expected.vertices == actual.vertices);
}

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Writes a deep tiled EXR with OpenEXR directly: `header` as given, every pixel holding
// the same `samples` (Z, attenuation) pairs. For files the PdsmWriter refuses to make.
// Writes `header` as a writer would: a header that carries a checksum (a copy of a real
// PDSM's, edited) gets it recomputed, so that the reader's checks behind it are what a test
// exercises.
void WriteRawDeepTiled(const std::string& path, Imf::Header header,
                       const std::vector<Vertex>& samples) {
  if (header.find(kHeaderChecksumAttribute) != header.end()) SealExrHeader(&header);
  const Imath::Box2i window = header.dataWindow();
  const int width = window.max.x - window.min.x + 1;
  const int height = window.max.y - window.min.y + 1;
  const size_t pixels = static_cast<size_t>(width) * height;
  std::vector<uint32_t> counts(pixels, static_cast<uint32_t>(samples.size()));
  std::vector<Vertex> data(samples);
  char* base = samples.empty() ? nullptr : reinterpret_cast<char*>(data.data());
  std::vector<char*> z(pixels, base), a(pixels, base ? base + sizeof(float) : nullptr);
  Imf::DeepFrameBuffer fb;
  fb.insertSampleCountSlice(Imf::Slice(Imf::UINT, reinterpret_cast<char*>(counts.data()),
                                       sizeof(uint32_t), sizeof(uint32_t) * width));
  for (const auto& [name, pointers] : {std::pair{"Z", &z}, std::pair{"attenuation", &a}}) {
    if (header.channels().findChannel(name) == nullptr) continue;
    fb.insert(name, Imf::DeepSlice(Imf::FLOAT, reinterpret_cast<char*>(pointers->data()),
                                   sizeof(char*), sizeof(char*) * width, sizeof(Vertex)));
  }
  Imf::DeepTiledOutputFile out(path.c_str(), header);
  out.setFrameBuffer(fb);
  out.writeTiles(0, out.numXTiles(0) - 1, 0, out.numYTiles(0) - 1);
}

Imf::Header PlainDeepTiledHeader(int width, int height) {
  Imf::Header header(width, height);
  header.setType(Imf::DEEPTILE);
  header.compression() = Imf::ZIPS_COMPRESSION;
  header.setTileDescription(Imf::TileDescription(16, 16, Imf::ONE_LEVEL));
  header.channels().insert("Z", Imf::Channel(Imf::FLOAT));
  header.channels().insert("attenuation", Imf::Channel(Imf::FLOAT));
  return header;
}

Imf::Header HeaderOf(const std::string& path) {
  Imf::MultiPartInputFile file(path.c_str());
  return file.header(0);
}

class PdsmFileTest : public ::testing::Test {
 protected:
  std::string Path(const std::string& name) const { return (fs::path(dir_) / name).string(); }
  std::vector<std::string> Files() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      names.push_back(entry.path().filename().string());
    }
    return names;
  }
  // A small valid PDSM on disk.
  std::string WriteSample(const std::string& name, int width = 40, int height = 24) {
    const PdsmImage image = RandomImage(FullHeader(width, height, 16), 7);
    const std::string path = Path(name);
    EXPECT_TRUE(WriteTiles(path, image.header, CutTiles(image)).ok());
    return path;
  }

  ::pdsm::testing::TempDir temp_dir_;  // a fresh folder per test, removed after it
  const std::string dir_ = temp_dir_.path().string();
};

TEST_F(PdsmFileTest, RoundTripsHeaderAndFunctions) {
  const PdsmImage image = RandomImage(FullHeader(150, 90, 32), 1, /*big_count=*/4000);
  const std::string path = Path("round_trip.exr");
  ASSERT_TRUE(WriteTiles(path, image.header, CutTiles(image)).ok());

  absl::StatusOr<PdsmImage> read = ReadPdsm(path);
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectImagesEqual(image, *read);
  EXPECT_EQ(read->Function(0, 45).size(), 4000u);  // RandomImage's big pixel: the middle one

  absl::StatusOr<PdsmHeader> header = ReadPdsmHeader(path);
  ASSERT_TRUE(header.ok()) << header.status();
  ExpectHeadersEqual(image.header, *header);
}

TEST_F(PdsmFileTest, RoundTripsDefaultHeaderAndEmptyImage) {
  PdsmHeader header;  // every enum at its first value, zeros
  header.geometry.width = 20;
  header.geometry.height = 10;
  header.tile_size = 8;
  PdsmImage image;
  image.header = header;
  image.offsets.assign(201, 0);  // no vertex anywhere
  const std::string path = Path("empty.exr");
  ASSERT_TRUE(WriteTiles(path, header, CutTiles(image)).ok());
  absl::StatusOr<PdsmImage> read = ReadPdsm(path);
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectImagesEqual(image, *read);
}

TEST_F(PdsmFileTest, RoundTripsPixelWithManyVertices) {
  // One pixel holding what an unconsolidated million-event ray would leave.
  const PdsmImage image = RandomImage(FullHeader(1, 1, 64), 3, /*big_count=*/300000);
  const std::string path = Path("deep.exr");
  ASSERT_TRUE(WriteTiles(path, image.header, CutTiles(image)).ok());
  absl::StatusOr<PdsmImage> read = ReadPdsm(path);
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectImagesEqual(image, *read);
}

struct EdgeCase {
  int width, height, tile_size;
};

class PdsmFileEdgeTest : public PdsmFileTest, public ::testing::WithParamInterface<EdgeCase> {};

TEST_P(PdsmFileEdgeTest, RoundTripsPartialEdgeTiles) {
  const EdgeCase c = GetParam();
  const PdsmImage image = RandomImage(FullHeader(c.width, c.height, c.tile_size), 11);
  const std::string path = Path("edge.exr");
  ASSERT_TRUE(WriteTiles(path, image.header, CutTiles(image)).ok());
  absl::StatusOr<PdsmImage> read = ReadPdsm(path);
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectImagesEqual(image, *read);
}

INSTANTIATE_TEST_SUITE_P(PdsmFileSizes, PdsmFileEdgeTest,
                         ::testing::Values(EdgeCase{1, 1, 64}, EdgeCase{1000, 3, 64},
                                           EdgeCase{130, 70, 64}, EdgeCase{64, 64, 64},
                                           EdgeCase{7, 5, 1}, EdgeCase{3, 1000, 64}));

TEST_F(PdsmFileTest, BytesDoNotDependOnTileOrder) {
  const PdsmImage image = RandomImage(FullHeader(130, 70, 16), 5, 1000);
  std::vector<PdsmTile> tiles = CutTiles(image);
  ASSERT_TRUE(WriteTiles(Path("in_order.exr"), image.header, tiles).ok());

  std::vector<PdsmTile> reversed(tiles.rbegin(), tiles.rend());
  ASSERT_TRUE(WriteTiles(Path("reversed.exr"), image.header, reversed).ok());

  std::mt19937 rng(42);
  std::shuffle(tiles.begin(), tiles.end(), rng);
  ASSERT_TRUE(WriteTiles(Path("shuffled.exr"), image.header, tiles).ok());

  const std::string in_order = ReadBytes(Path("in_order.exr"));
  ASSERT_FALSE(in_order.empty());
  EXPECT_TRUE(in_order == ReadBytes(Path("reversed.exr")));
  EXPECT_TRUE(in_order == ReadBytes(Path("shuffled.exr")));
}

// Early tiles past the writer's memory budget wait in a scratch file (TileReorderBuffer):
// the bytes are those of a bake whose tiles came in order, and nothing is left beside the file.
TEST_F(PdsmFileTest, EarlyTilesSpilledToDiskGiveTheSameBytes) {
  const PdsmImage image = RandomImage(FullHeader(130, 70, 16), 5, 1000);
  const std::vector<PdsmTile> tiles = CutTiles(image);
  ASSERT_TRUE(WriteTiles(Path("in_order.exr"), image.header, tiles).ok());
  const std::vector<PdsmTile> reversed(tiles.rbegin(), tiles.rend());
  // Budget 0: every early tile with a vertex goes to disk; 20 KiB: some do.
  ASSERT_TRUE(WriteTiles(Path("spilled.exr"), image.header, reversed, nullptr, 0).ok());
  ASSERT_TRUE(WriteTiles(Path("some.exr"), image.header, reversed, nullptr, 20 << 10).ok());
  const std::string in_order = ReadBytes(Path("in_order.exr"));
  ASSERT_FALSE(in_order.empty());
  EXPECT_TRUE(in_order == ReadBytes(Path("spilled.exr")));
  EXPECT_TRUE(in_order == ReadBytes(Path("some.exr")));
  EXPECT_THAT(Files(), ::testing::UnorderedElementsAre("in_order.exr", "spilled.exr", "some.exr"));
}

// A spill that cannot be written fails the writer with the disk's error, and leaves nothing.
TEST_F(PdsmFileTest, AFullDiskWhileSpillingFailsTheWriterAndLeavesNothing) {
  const PdsmImage image = RandomImage(FullHeader(64, 64, 16), 3);
  const std::vector<PdsmTile> tiles = CutTiles(image);
  FaultInjectingFileSystem faults;
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer =
      PdsmWriter::Create(Path("out.exr"), image.header, &faults, /*reorder_memory_bytes=*/0);
  ASSERT_TRUE(writer.ok()) << writer.status();
  faults.FailNth(FileOp::kCreate, 1, ENOSPC);  // the scratch file
  const absl::Status early = (*writer)->WriteTile(tiles.back());
  EXPECT_EQ(early.code(), absl::StatusCode::kResourceExhausted) << early;
  EXPECT_EQ((*writer)->WriteTile(tiles.front()).code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(Files(), ::testing::IsEmpty());
}

TEST_F(PdsmFileTest, SameContentGivesSameBytesTwice) {
  // Nothing time- or address-dependent in the file.
  const PdsmImage image = RandomImage(FullHeader(33, 17, 8), 9);
  ASSERT_TRUE(WriteTiles(Path("a.exr"), image.header, CutTiles(image)).ok());
  ASSERT_TRUE(WriteTiles(Path("b.exr"), image.header, CutTiles(image)).ok());
  EXPECT_TRUE(ReadBytes(Path("a.exr")) == ReadBytes(Path("b.exr")));
}

TEST_F(PdsmFileTest, AbandonedWriterLeavesNothing) {
  const PdsmImage image = RandomImage(FullHeader(50, 50, 16), 2);
  const std::vector<PdsmTile> tiles = CutTiles(image);
  {
    absl::StatusOr<std::unique_ptr<PdsmWriter>> writer =
        PdsmWriter::Create(Path("out.exr"), image.header);
    ASSERT_TRUE(writer.ok()) << writer.status();
    ASSERT_TRUE((*writer)->WriteTile(tiles[0]).ok());
    ASSERT_TRUE((*writer)->WriteTile(tiles[5]).ok());  // buffered, out of order
    EXPECT_EQ(Files().size(), 1u);                     // the temporary file only
    const absl::Status finish = (*writer)->Finish();
    EXPECT_EQ(finish.code(), absl::StatusCode::kFailedPrecondition) << finish;
  }
  EXPECT_THAT(Files(), ::testing::IsEmpty());
}

TEST_F(PdsmFileTest, TemporaryFileIsBesideTheTarget) {
  const PdsmImage image = RandomImage(FullHeader(8, 8, 8), 2);
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer =
      PdsmWriter::Create(Path("out.exr"), image.header);
  ASSERT_TRUE(writer.ok()) << writer.status();
  ASSERT_EQ(Files().size(), 1u);
  EXPECT_THAT(Files()[0], ::testing::MatchesRegex("out\\.exr\\.tmp-[A-Za-z0-9]{6}"));
  ASSERT_TRUE((*writer)->WriteTile(CutTile(image, 0, 0)).ok());
  ASSERT_TRUE((*writer)->Finish().ok());
  EXPECT_THAT(Files(), ::testing::ElementsAre("out.exr"));
  writer->reset();
  EXPECT_THAT(Files(), ::testing::ElementsAre("out.exr"));
}

// The PDSM streams through the one atomic-write path: whichever write, sync or rename fails
// (OpenEXR's header, a tile, the offset table written by its destructor, a full disk at any
// point), the previous PDSM stays byte for byte and no temporary file is left.
TEST_F(PdsmFileTest, EveryFileSystemFailureLeavesThePreviousPdsm) {
  const PdsmImage previous = RandomImage(FullHeader(24, 20, 8), 3);
  const std::string path = Path("out.exr");
  ASSERT_TRUE(WriteTiles(path, previous.header, CutTiles(previous)).ok());
  const PdsmImage next = RandomImage(FullHeader(24, 20, 8), 4);
  testing::ExpectWriteFailuresLeaveTargetIntact(path, dir_, [&](FileSystem* file_system) {
    return WriteTiles(path, next.header, CutTiles(next), file_system);
  });
  absl::StatusOr<PdsmImage> read = ReadPdsm(path);
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectImagesEqual(previous, *read);
}

// A full disk mid-bake: the error is sticky, names the file, and the temporary file is gone
// at once, not only when the writer is destroyed.
TEST_F(PdsmFileTest, FullDiskFailsTheWriterAndLeavesNothing) {
  const PdsmImage image = RandomImage(FullHeader(64, 64, 16), 5);
  const std::vector<PdsmTile> tiles = CutTiles(image);
  FaultInjectingFileSystem faults;
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer =
      PdsmWriter::Create(Path("out.exr"), image.header, &faults);
  ASSERT_TRUE(writer.ok()) << writer.status();
  faults.SetDiskFullAfter(faults.bytes_written() + 100);
  absl::Status s;
  for (const PdsmTile& tile : tiles) {
    s = (*writer)->WriteTile(tile);
    if (!s.ok()) break;
  }
  if (s.ok()) s = (*writer)->Finish();  // the tiles may all fit in the write buffer
  EXPECT_EQ(s.code(), absl::StatusCode::kResourceExhausted) << s;
  EXPECT_THAT(std::string(s.message()), HasSubstr(Path("out.exr")));
  EXPECT_THAT(Files(), ::testing::IsEmpty());
  EXPECT_EQ((*writer)->Finish(), s);
  EXPECT_THAT(Files(), ::testing::IsEmpty());
}

TEST_F(PdsmFileTest, CreateInMissingFolderNamesThePath) {
  const std::string path = Path("no/such/folder/out.exr");
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer =
      PdsmWriter::Create(path, FullHeader(8, 8, 8));
  ASSERT_FALSE(writer.ok());
  EXPECT_EQ(writer.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(writer.status().message(), HasSubstr(path));
}

TEST_F(PdsmFileTest, CreateRejectsBadHeader) {
  PdsmHeader header = FullHeader(8, 8, 0);
  EXPECT_EQ(PdsmWriter::Create(Path("a.exr"), header).status().code(),
            absl::StatusCode::kInvalidArgument);
  header = FullHeader(0, 8, 8);
  EXPECT_EQ(PdsmWriter::Create(Path("a.exr"), header).status().code(),
            absl::StatusCode::kInvalidArgument);
  header = FullHeader(8, 8, 8);
  header.format_version = kPdsmFormatVersion + 1;
  EXPECT_EQ(PdsmWriter::Create(Path("a.exr"), header).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Files(), ::testing::IsEmpty());
}

TEST_F(PdsmFileTest, WriteTileRejectsTilesOffTheGrid) {
  const PdsmImage image = RandomImage(FullHeader(40, 40, 16), 4);
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer =
      PdsmWriter::Create(Path("out.exr"), image.header);
  ASSERT_TRUE(writer.ok()) << writer.status();
  PdsmWriter& w = **writer;

  PdsmTile misaligned = CutTile(image, 0, 0);
  misaligned.x0 = 3;
  EXPECT_EQ(w.WriteTile(misaligned).code(), absl::StatusCode::kInvalidArgument);

  PdsmTile wrong_size = CutTile(image, 32, 0);  // 8 wide at the edge
  wrong_size.width = 16;
  EXPECT_EQ(w.WriteTile(wrong_size).code(), absl::StatusCode::kInvalidArgument);

  PdsmTile bad_offsets = CutTile(image, 16, 0);
  bad_offsets.offsets.pop_back();
  EXPECT_EQ(w.WriteTile(bad_offsets).code(), absl::StatusCode::kInvalidArgument);

  PdsmTile unsorted;
  unsorted.x0 = 16;
  unsorted.y0 = 16;
  unsorted.width = unsorted.height = 16;
  unsorted.offsets.assign(257, 2);
  unsorted.offsets[0] = 0;
  unsorted.vertices = {{2.0f, 0.5f}, {1.0f, 0.5f}};
  const absl::Status s = w.WriteTile(unsorted);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("pixel (16, 16)"));

  ASSERT_TRUE(w.WriteTile(CutTile(image, 16, 16)).ok());
  EXPECT_EQ(w.WriteTile(CutTile(image, 16, 16)).code(), absl::StatusCode::kInvalidArgument);
  ASSERT_TRUE(w.WriteTile(CutTile(image, 0, 0)).ok());
  EXPECT_EQ(w.WriteTile(CutTile(image, 0, 0)).code(), absl::StatusCode::kInvalidArgument);
}

TEST_F(PdsmFileTest, MissingFileIsNotFound) {
  EXPECT_EQ(ReadPdsm(Path("missing.exr")).status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(ReadPdsmHeader(Path("missing.exr")).status().code(), absl::StatusCode::kNotFound);
}

TEST_F(PdsmFileTest, NonExrFileIsDataLoss) {
  WriteBytes(Path("text.exr"), "this is not an OpenEXR file, just some text\n");
  const absl::Status s = ReadPdsm(Path("text.exr")).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss) << s;
  EXPECT_THAT(s.message(), HasSubstr(Path("text.exr")));
  EXPECT_EQ(ReadPdsmHeader(Path("text.exr")).status().code(), absl::StatusCode::kDataLoss);
  WriteBytes(Path("empty.exr"), "");
  EXPECT_EQ(ReadPdsm(Path("empty.exr")).status().code(), absl::StatusCode::kDataLoss);
}

TEST_F(PdsmFileTest, TruncatedFileIsDataLoss) {
  const std::string bytes = ReadBytes(WriteSample("full.exr"));
  ASSERT_GT(bytes.size(), 200u);
  for (size_t keep : {size_t{8}, size_t{100}, bytes.size() / 2, bytes.size() - 1}) {
    SCOPED_TRACE(keep);
    const std::string path = Path("truncated.exr");
    WriteBytes(path, bytes.substr(0, keep));
    const absl::Status s = ReadPdsm(path).status();
    EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss) << s;
    EXPECT_THAT(s.message(), HasSubstr(path));
  }
}

TEST_F(PdsmFileTest, PlainDeepExrIsNotAPdsm) {
  const std::string path = Path("plain_deep.exr");
  WriteRawDeepTiled(path, PlainDeepTiledHeader(20, 20), {{1.0f, 0.5f}});
  const absl::Status s = ReadPdsm(path).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss) << s;
  EXPECT_THAT(s.message(), HasSubstr("not a PDSM file: " + path));
  EXPECT_EQ(ReadPdsmHeader(path).status().code(), absl::StatusCode::kDataLoss);
}

TEST_F(PdsmFileTest, ScanlineExrIsDataLoss) {
  const std::string path = Path("scanline.exr");
  {
    Imf::Header header(4, 4);
    header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
    std::vector<float> pixels(16, 0.25f);
    Imf::FrameBuffer fb;
    fb.insert("Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(pixels.data()), sizeof(float),
                              4 * sizeof(float)));
    Imf::OutputFile out(path.c_str(), header);
    out.setFrameBuffer(fb);
    out.writePixels(4);
  }
  const absl::Status s = ReadPdsm(path).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss) << s;
  EXPECT_THAT(s.message(), HasSubstr("not a PDSM file"));
}

TEST_F(PdsmFileTest, PdsmAttributesOnAScanlineImageAreDataLoss) {
  const std::string path = Path("flat.exr");
  {
    Imf::Header header = HeaderOf(WriteSample("sample.exr"));
    const Imath::Box2i window = header.dataWindow();
    Imf::Header flat(window.max.x + 1, window.max.y + 1);
    for (auto it = header.begin(); it != header.end(); ++it) {
      if (std::string(it.name()).rfind("pdsm", 0) == 0) flat.insert(it.name(), it.attribute());
    }
    flat.channels().insert("Z", Imf::Channel(Imf::FLOAT));
    flat.channels().insert("attenuation", Imf::Channel(Imf::FLOAT));
    Imf::OutputFile out(path.c_str(), flat);  // no pixels: zeros
    Imf::FrameBuffer fb;
    out.setFrameBuffer(fb);
    out.writePixels(flat.dataWindow().max.y + 1);
  }
  const absl::Status s = ReadPdsm(path).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss) << s;
  EXPECT_THAT(s.message(), HasSubstr("deep tiled"));
}

TEST_F(PdsmFileTest, NewerFormatVersionIsFailedPrecondition) {
  Imf::Header header = HeaderOf(WriteSample("sample.exr"));
  header.typedAttribute<Imf::IntAttribute>("pdsmFormatVersion").value() = kPdsmFormatVersion + 1;
  const std::string path = Path("future.exr");
  WriteRawDeepTiled(path, header, {});
  EXPECT_EQ(ReadPdsm(path).status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(ReadPdsmHeader(path).status().code(), absl::StatusCode::kFailedPrecondition);
}

TEST_F(PdsmFileTest, VersionTwoOnlyWhenTheEvaluationRuleChanged) {
  // Plain files stay version 1 (a version-1 reader opens them); surfaces-only and z_valid_min
  // files are version 2, and a version-1 file claiming those features is refused.
  EXPECT_EQ(HeaderOf(WriteSample("plain.exr"))
                .typedAttribute<Imf::IntAttribute>("pdsmFormatVersion")
                .value(),
            1);
  PdsmImage image = RandomImage(FullHeader(40, 24, 16), 7);
  image.header.surfaces_only = true;
  image.header.geometry.z_valid_min = image.header.geometry.z_near + 0.01;
  const std::string path = Path("v2.exr");
  EXPECT_EQ(WriteTiles(path, image.header, CutTiles(image)).code(),
            absl::StatusCode::kInvalidArgument);  // the header still says version 1
  image.header.format_version = MinimumFormatVersion(image.header);
  ASSERT_TRUE(WriteTiles(path, image.header, CutTiles(image)).ok());
  Imf::Header exr = HeaderOf(path);
  EXPECT_EQ(exr.typedAttribute<Imf::IntAttribute>("pdsmFormatVersion").value(), 2);
  absl::StatusOr<PdsmHeader> read = ReadPdsmHeader(path);
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->format_version, 2);

  exr.typedAttribute<Imf::IntAttribute>("pdsmFormatVersion").value() = 1;
  const std::string lying = Path("v1_claiming_v2.exr");
  WriteRawDeepTiled(lying, exr, {});
  const absl::Status s = ReadPdsmHeader(lying).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss) << s;
  EXPECT_THAT(s.message(), HasSubstr("pdsmSurfacesOnly"));
}

TEST_F(PdsmFileTest, RefinedPixelsRoundTripInVersionThree) {
  PdsmImage image = RandomImage(FullHeader(70, 40, 16), 11);
  image.header.max_refinement = 8;
  image.header.format_version = MinimumFormatVersion(image.header);
  RefineSomePixels(&image, 12);
  const std::string path = Path("refined.exr");
  ASSERT_TRUE(WriteTiles(path, image.header, CutTiles(image)).ok());
  EXPECT_EQ(HeaderOf(path).typedAttribute<Imf::IntAttribute>("pdsmFormatVersion").value(), 3);
  EXPECT_EQ(HeaderOf(path).typedAttribute<Imf::IntAttribute>("pdsmMaxRefinement").value(), 8);
  absl::StatusOr<PdsmImage> read = ReadPdsm(path);
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectImagesEqual(image, *read);
  // Tile by tile, as the viewer and the tile cache read it.
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(path);
  ASSERT_TRUE(reader.ok()) << reader.status();
  const std::vector<PdsmTile> tiles = CutTiles(image);
  for (const PdsmTile& want : tiles) {
    absl::StatusOr<PdsmTile> got = reader->ReadTile(0, want.x0 / 16, want.y0 / 16);
    ASSERT_TRUE(got.ok()) << got.status();
    ExpectSameTile(*got, want);
  }
  // Files without refinement keep their version and bytes: no attribute.
  const Imf::Header plain = HeaderOf(WriteSample("plain.exr"));
  EXPECT_EQ(plain.find("pdsmMaxRefinement"), plain.end());
}

TEST_F(PdsmFileTest, ARefinementBeyondTheHeadersIsRefused) {
  PdsmImage image = RandomImage(FullHeader(40, 24, 16), 13);
  image.header.max_refinement = 8;
  image.header.format_version = 3;
  RefineSomePixels(&image, 14, /*every=*/2);
  image.header.max_refinement = 2;  // the pixels hold up to 8x
  EXPECT_EQ(WriteTiles(Path("w.exr"), image.header, CutTiles(image)).code(),
            absl::StatusCode::kInvalidArgument);
  image.header.max_refinement = 1;  // and no refinement at all: version 1, a marker is no vertex
  image.header.format_version = 1;
  EXPECT_EQ(WriteTiles(Path("w.exr"), image.header, CutTiles(image)).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Files(), ::testing::IsEmpty());

  // Read: a pixel refined 4x in a file whose largest refinement is 2, and malformed pixels.
  image.header.max_refinement = 2;
  image.header.format_version = 3;
  const std::string valid = Path("valid.exr");
  PdsmImage two = RandomImage(image.header, 15);
  ASSERT_TRUE(WriteTiles(valid, two.header, CutTiles(two)).ok());
  const Imf::Header header = HeaderOf(valid);
  std::vector<Vertex> four;
  const std::vector<Vertex> own = {{1.0f, 0.25f}};
  const std::vector<RefinedBand> band = {{0.5f, 5.0f}};
  AppendRefinedPixel(4, band, own, std::vector<std::vector<Vertex>>(16, {{1.0f, 0.5f}}), &four);
  std::vector<Vertex> unordered;
  AppendRefinedPixel(2, band, own,
                     std::vector<std::vector<Vertex>>(4, {{2.0f, 0.5f}, {1.0f, 0.5f}}), &unordered);
  std::vector<Vertex> short_ends = {{4.0f, -2.0f}, {1.0f, -1.0f}, {1.0f, -1.0f}, {2.0f, -1.0f}};
  for (const auto& [name, samples, says] : {std::tuple{"four", four, "a refinement of 4"},
                                            std::tuple{"unordered", unordered, "sub-pixel (0, 0)"},
                                            std::tuple{"short", short_ends, "function ends"}}) {
    const std::string path = Path(std::string(name) + ".exr");
    WriteRawDeepTiled(path, header, samples);
    const absl::Status s = ReadPdsm(path).status();
    EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss) << name << ": " << s;
    EXPECT_THAT(s.message(), HasSubstr("pixel (0, 0)")) << name;
    EXPECT_THAT(s.message(), HasSubstr(says)) << name;
  }
}

TEST_F(PdsmFileTest, MissingAttributeIsDataLossNamingIt) {
  // A copy without the attribute (OpenEXR 3.1.5's Header::erase leaks it).
  const Imf::Header full = HeaderOf(WriteSample("sample.exr"));
  const Imath::Box2i window = full.dataWindow();
  Imf::Header header(window.max.x + 1, window.max.y + 1);
  for (auto it = full.begin(); it != full.end(); ++it) {
    if (std::string(it.name()) != "pdsmWindowMax") header.insert(it.name(), it.attribute());
  }
  const std::string path = Path("no_window.exr");
  WriteRawDeepTiled(path, header, {});
  const absl::Status s = ReadPdsmHeader(path).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss) << s;
  EXPECT_THAT(s.message(), HasSubstr("pdsmWindowMax"));
}

// Geometry a lookup divides by or compares with: a corrupt value is refused, naming the
// attribute, where it once made queries compute NaN pixel coordinates (fuzz_pdsm_reader).
TEST_F(PdsmFileTest, GeometryThatIsNoWindowOrNotFiniteIsDataLossNamingIt) {
  const Imf::Header good = HeaderOf(WriteSample("sample.exr"));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const auto refused = [&](const std::string& name, auto edit, const char* attribute) {
    Imf::Header header = good;
    edit(header);
    const std::string path = Path(name + ".exr");
    WriteRawDeepTiled(path, header, {});
    const absl::Status s = ReadPdsmHeader(path).status();
    EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss) << name << ": " << s;
    EXPECT_THAT(s.message(), HasSubstr(attribute)) << name;
  };
  const auto v2 = [](Imf::Header& h, const char* name) -> Imath::V2d& {
    return h.typedAttribute<Imf::V2dAttribute>(name).value();
  };
  refused(
      "empty_window", [&](Imf::Header& h) { v2(h, "pdsmWindowMax").x = v2(h, "pdsmWindowMin").x; },
      "pdsmWindowMin");
  refused(
      "inverted_window", [&](Imf::Header& h) { v2(h, "pdsmWindowMax").y = -1e9; }, "pdsmWindowMax");
  refused(
      "nan_window", [&](Imf::Header& h) { v2(h, "pdsmWindowMin").x = nan; }, "pdsmWindowMin");
  refused(
      "infinite_window", [&](Imf::Header& h) { v2(h, "pdsmWindowMax").x = inf; }, "pdsmWindowMax");
  refused(
      "nan_centre",
      [&](Imf::Header& h) {
        h.typedAttribute<Imf::V3dAttribute>("pdsmLightCenter").value().y = nan;
      },
      "pdsmLightCenter");
  refused(
      "infinite_normal",
      [&](Imf::Header& h) { h.typedAttribute<Imf::V3dAttribute>("pdsmLightN").value().z = inf; },
      "pdsmLightN");
  refused(
      "nan_far",
      [&](Imf::Header& h) { h.typedAttribute<Imf::DoubleAttribute>("pdsmZFar").value() = nan; },
      "pdsmZFar");
  refused(
      "far_before_near",
      [&](Imf::Header& h) {
        auto& near = h.typedAttribute<Imf::DoubleAttribute>("pdsmZNear").value();
        h.typedAttribute<Imf::DoubleAttribute>("pdsmZFar").value() = near - 1;
      },
      "pdsmZNear");
}

TEST_F(PdsmFileTest, DecreasingDepthsAreDataLossNamingThePixel) {
  const Imf::Header header = HeaderOf(WriteSample("sample.exr", 3, 2));
  const std::string path = Path("unsorted.exr");
  WriteRawDeepTiled(path, header, {{2.0f, 0.5f}, {1.0f, 1.0f}});
  const absl::Status s = ReadPdsm(path).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss) << s;
  EXPECT_THAT(s.message(), HasSubstr("pixel (0, 0)"));
}

// ---------------------------------------------------------------------------------------
// Several lights: one multipart file.

// Three lights of different sizes and bakes, written through a PdsmLightsWriter with each
// light's tiles in `order` (0: in order, 1: reversed).
struct ThreeLights {
  std::vector<PdsmImage> images;
  ThreeLights() {
    const int sizes[3][3] = {{40, 24, 16}, {130, 70, 32}, {7, 5, 1}};
    const char* names[] = {"sun", "lamp_1", "lamp.2-b"};
    for (int i = 0; i < 3; ++i) {
      PdsmImage image =
          RandomImage(FullHeader(sizes[i][0], sizes[i][1], sizes[i][2]), 20 + i, i == 1 ? 500 : 0);
      image.header.light_name = names[i];
      images.push_back(std::move(image));
    }
  }
  absl::Status Write(const std::string& path, int order) const {
    absl::StatusOr<std::unique_ptr<PdsmLightsWriter>> writer =
        PdsmLightsWriter::Create(path, 3, 130, 70);
    if (!writer.ok()) return writer.status();
    for (const PdsmImage& image : images) {
      absl::StatusOr<PdsmWriter*> part = (*writer)->BeginLight(image.header);
      if (!part.ok()) return part.status();
      std::vector<PdsmTile> tiles = CutTiles(image);
      if (order == 1) std::reverse(tiles.begin(), tiles.end());
      for (const PdsmTile& tile : tiles) {
        if (absl::Status s = (*part)->WriteTile(tile); !s.ok()) return s;
      }
      if (absl::Status s = (*part)->Finish(); !s.ok()) return s;
    }
    return (*writer)->Finish();
  }
};

TEST_F(PdsmFileTest, SeveralLightsRoundTripOnePartEach) {
  const ThreeLights lights;
  const std::string path = Path("lights.exr");
  ASSERT_TRUE(lights.Write(path, 0).ok());
  EXPECT_EQ(Files(), std::vector<std::string>{"lights.exr"});  // no staged part left

  absl::StatusOr<std::vector<PdsmHeader>> headers = ReadPdsmHeaders(path);
  ASSERT_TRUE(headers.ok()) << headers.status();
  ASSERT_EQ(headers->size(), 3u);
  absl::StatusOr<std::vector<PdsmImage>> all = ReadPdsmLights(path);
  ASSERT_TRUE(all.ok()) << all.status();
  ASSERT_EQ(all->size(), 3u);
  for (int i = 0; i < 3; ++i) {
    SCOPED_TRACE(lights.images[i].header.light_name);
    ExpectHeadersEqual(lights.images[i].header, (*headers)[i]);
    ExpectImagesEqual(lights.images[i], (*all)[i]);
    absl::StatusOr<PdsmImage> one = ReadPdsm(path, lights.images[i].header.light_name);
    ASSERT_TRUE(one.ok()) << one.status();
    ExpectImagesEqual(lights.images[i], *one);
  }
  // No name: the file holds several lights, and the error lists them.
  absl::StatusOr<PdsmImage> unnamed = ReadPdsm(path);
  EXPECT_EQ(unnamed.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(unnamed.status().message(), HasSubstr("\"sun\", \"lamp_1\", \"lamp.2-b\""));
  // One open file for every light: the same answers.
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(path);
  ASSERT_TRUE(reader.ok()) << reader.status();
  ASSERT_EQ(reader->light_count(), 3);
  absl::StatusOr<int> lamp = reader->FindLight("lamp_1");
  ASSERT_TRUE(lamp.ok()) << lamp.status();
  EXPECT_EQ(*lamp, 1);
  absl::StatusOr<PdsmImage> second = reader->ReadLight(1);
  ASSERT_TRUE(second.ok()) << second.status();
  ExpectImagesEqual(lights.images[1], *second);
  EXPECT_EQ(reader->ReadLight(3).status().code(), absl::StatusCode::kOutOfRange);
  absl::StatusOr<PdsmHeader> missing = ReadPdsmHeader(path, "moon");
  EXPECT_EQ(missing.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(missing.status().message(), HasSubstr("no light \"moon\""));
}

TEST_F(PdsmFileTest, SeveralLightsBytesDoNotDependOnTileOrder) {
  const ThreeLights lights;
  ASSERT_TRUE(lights.Write(Path("a.exr"), 0).ok());
  ASSERT_TRUE(lights.Write(Path("b.exr"), 1).ok());
  EXPECT_TRUE(ReadBytes(Path("a.exr")) == ReadBytes(Path("b.exr")));
}

TEST_F(PdsmFileTest, OneNamedLightIsASinglePartFileWithItsName) {
  PdsmImage image = RandomImage(FullHeader(40, 24, 16), 7);
  const std::string unnamed = Path("unnamed.exr");
  ASSERT_TRUE(WriteTiles(unnamed, image.header, CutTiles(image)).ok());
  image.header.light_name = "key";
  const std::string named = Path("named.exr");
  ASSERT_TRUE(WriteTiles(named, image.header, CutTiles(image)).ok());
  // An unnamed light's file carries no name attribute at all (the bytes of before).
  EXPECT_EQ(ReadBytes(unnamed).find("name\0string"), std::string::npos);
  absl::StatusOr<PdsmImage> by_name = ReadPdsm(named, "key");
  ASSERT_TRUE(by_name.ok()) << by_name.status();
  EXPECT_EQ(by_name->header.light_name, "key");
  absl::StatusOr<PdsmImage> only = ReadPdsm(named);  // its only light needs no name
  ASSERT_TRUE(only.ok()) << only.status();
  EXPECT_EQ(ReadPdsm(unnamed, "key").status().code(), absl::StatusCode::kNotFound);
}

TEST_F(PdsmFileTest, SeveralLightsWriterRefusesMisuseAndLeavesNothing) {
  const ThreeLights lights;
  const std::string path = Path("misuse.exr");
  {
    absl::StatusOr<std::unique_ptr<PdsmLightsWriter>> writer =
        PdsmLightsWriter::Create(path, 2, 130, 70);
    ASSERT_TRUE(writer.ok());
    PdsmHeader unnamed = lights.images[0].header;
    unnamed.light_name.clear();
    EXPECT_EQ((*writer)->BeginLight(unnamed).status().code(), absl::StatusCode::kInvalidArgument);
  }
  {
    absl::StatusOr<std::unique_ptr<PdsmLightsWriter>> writer =
        PdsmLightsWriter::Create(path, 2, 130, 70);
    ASSERT_TRUE(writer.ok());
    absl::StatusOr<PdsmWriter*> part = (*writer)->BeginLight(lights.images[0].header);
    ASSERT_TRUE(part.ok());
    // The first light is not finished: the second may not begin, nor the file end.
    EXPECT_EQ((*writer)->BeginLight(lights.images[1].header).status().code(),
              absl::StatusCode::kFailedPrecondition);
  }
  {
    absl::StatusOr<std::unique_ptr<PdsmLightsWriter>> writer =
        PdsmLightsWriter::Create(path, 2, 130, 70);
    ASSERT_TRUE(writer.ok());
    absl::StatusOr<PdsmWriter*> part = (*writer)->BeginLight(lights.images[0].header);
    ASSERT_TRUE(part.ok());
    for (const PdsmTile& tile : CutTiles(lights.images[0]))
      ASSERT_TRUE((*part)->WriteTile(tile).ok());
    ASSERT_TRUE((*part)->Finish().ok());
    EXPECT_FALSE(Files().empty());  // the staged part
    EXPECT_EQ((*writer)->BeginLight(lights.images[0].header).status().code(),
              absl::StatusCode::kInvalidArgument);  // "sun" again
    EXPECT_EQ((*writer)->Finish().code(), absl::StatusCode::kFailedPrecondition);
  }
  EXPECT_TRUE(Files().empty());  // abandoned: no file, no staged part
}

// A world of many lights: the writer holds a few descriptors, not one per light (10,000 lights
// ran out of them), and needs no higher limit on open files.
TEST_F(PdsmFileTest, SeveralLightsWriterHoldsAFewDescriptorsWhateverTheLights) {
  constexpr int kLights = 300;
  struct rlimit before;
  ASSERT_EQ(::getrlimit(RLIMIT_NOFILE, &before), 0);
  struct rlimit low = before;
  low.rlim_cur = 64;  // below kLights: one descriptor a light cannot fit
  ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &low), 0);
  std::vector<PdsmImage> images;
  absl::Status written = [&]() -> absl::Status {
    absl::StatusOr<std::unique_ptr<PdsmLightsWriter>> writer =
        PdsmLightsWriter::Create(Path("many.exr"), kLights, 3, 2);
    if (!writer.ok()) return writer.status();
    for (int i = 0; i < kLights; ++i) {
      PdsmImage image = RandomImage(FullHeader(3 - i % 2, 2, 2), 100 + i);
      image.header.light_name = absl::StrCat("l", i);
      absl::StatusOr<PdsmWriter*> part = (*writer)->BeginLight(image.header);
      if (!part.ok()) return part.status();
      for (const PdsmTile& tile : CutTiles(image)) {
        if (absl::Status s = (*part)->WriteTile(tile); !s.ok()) return s;
      }
      if (absl::Status s = (*part)->Finish(); !s.ok()) return s;
      images.push_back(std::move(image));
    }
    return (*writer)->Finish();
  }();
  struct rlimit after;
  ASSERT_EQ(::getrlimit(RLIMIT_NOFILE, &after), 0);
  ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &before), 0);
  ASSERT_TRUE(written.ok()) << written;
  EXPECT_EQ(after.rlim_cur, 64u);  // not raised
  EXPECT_EQ(Files(), std::vector<std::string>{"many.exr"});
  absl::StatusOr<std::vector<PdsmImage>> all = ReadPdsmLights(Path("many.exr"));
  ASSERT_TRUE(all.ok()) << all.status();
  ASSERT_EQ(all->size(), images.size());
  for (int i : {0, 1, 150, kLights - 1}) {
    SCOPED_TRACE(i);
    ExpectHeadersEqual(images[i].header, (*all)[i].header);
    ExpectImagesEqual(images[i], (*all)[i]);
  }
}

// The file must be readable by OpenEXR's own tools (DESIGN.md, "PDSM file").
class PdsmFileToolsTest : public PdsmFileTest, public ::testing::WithParamInterface<bool> {};

TEST_P(PdsmFileToolsTest, OpenExrToolsAcceptTheFile) {
  const bool several_lights = GetParam();
  std::string path = Path("tools.exr");
  if (several_lights) {
    ASSERT_TRUE(ThreeLights().Write(path, 0).ok());
  } else {
    path = WriteSample("tools.exr", 130, 70);
  }
  const std::string log = Path("tool.log");
  bool ran = false;
  for (const char* tool : {"exrheader", "exrinfo -s", "exrinfo -v -a"}) {
    const std::string name = std::string(tool).substr(0, std::string(tool).find(' '));
    if (!fs::exists("/usr/bin/" + name)) continue;
    ran = true;
    const std::string command =
        "/usr/bin/" + std::string(tool) + " '" + path + "' > '" + log + "' 2>&1";
    EXPECT_EQ(std::system(command.c_str()), 0) << command << "\n" << ReadBytes(log);
    if (name == "exrheader") {
      const std::string out = ReadBytes(log);
      EXPECT_THAT(out, HasSubstr("pdsmFormatVersion"));
      EXPECT_THAT(out, HasSubstr("deeptile"));
      if (several_lights) EXPECT_THAT(out, HasSubstr("lamp.2-b"));
    }
  }
  if (!ran) GTEST_SKIP() << "neither exrheader nor exrinfo in /usr/bin";
}

INSTANTIATE_TEST_SUITE_P(OneAndSeveralLights, PdsmFileToolsTest, ::testing::Bool());

}  // namespace
}  // namespace pdsm
