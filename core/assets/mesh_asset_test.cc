#include "core/assets/mesh_asset.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "core/scene/alpha_mask.h"

namespace pdsm {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr size_t kHeaderBytes = 28;  // magic, version, vertex_count, index_count

// Awkward doubles on purpose: a text round trip through "%g" would change most of them.
MeshFileData Tetrahedron() {
  MeshFileData mesh;
  mesh.positions = {{0.1, -0.0, 1e-300},
                    {std::numbers::pi, 4.9e-324, -123456.789012345678},
                    {std::numeric_limits<double>::max(), 1.0 / 3.0, -2.5e-8},
                    {6.02214076e23, -1.0, 0x1.fffffffffffffp-1}};
  mesh.indices = {0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2};
  return mesh;
}

// The smallest valid mesh, one triangle, for byte-level tests.
MeshFileData Triangle() {
  MeshFileData mesh;
  mesh.positions = {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};
  mesh.indices = {0, 1, 2};
  return mesh;
}

// Two triangles sharing an edge, the second tested by a 3 x 2 mask.
MeshFileData MaskedQuad() {
  MeshFileData mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {-0.5f, 2.25f}};
  mesh.triangle_masks = {0, 1};
  auto mask = std::make_shared<AlphaMask>();
  mask->width = 3;
  mask->height = 2;
  mask->alpha = {0, 10, 20, 30, 40, 255};
  mask->wrap_u = TextureWrap::kMirroredRepeat;
  mask->wrap_v = TextureWrap::kClampToEdge;
  mask->cutoff = 0.3f;
  mesh.masks = {mask};
  return mesh;
}

void PutU32(std::string* bytes, size_t offset, uint32_t v) {
  for (int i = 0; i < 4; ++i) (*bytes)[offset + i] = static_cast<char>(v >> (8 * i));
}
void PutU64(std::string* bytes, size_t offset, uint64_t v) {
  for (int i = 0; i < 8; ++i) (*bytes)[offset + i] = static_cast<char>(v >> (8 * i));
}
void PutF64(std::string* bytes, size_t offset, double v) {
  PutU64(bytes, offset, std::bit_cast<uint64_t>(v));
}

void ExpectInvalid(const absl::StatusOr<MeshFileData>& mesh, const std::string& detail) {
  ASSERT_FALSE(mesh.ok()) << "expected an error containing " << detail;
  EXPECT_EQ(mesh.status().code(), absl::StatusCode::kInvalidArgument) << mesh.status();
  EXPECT_THAT(std::string(mesh.status().message()), StartsWith("ctx: "));
  EXPECT_THAT(mesh.status().message(), HasSubstr(detail));
}

void ExpectBitIdentical(const MeshFileData& a, const MeshFileData& b) {
  ASSERT_EQ(a.positions.size(), b.positions.size());
  for (size_t v = 0; v < a.positions.size(); ++v) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(std::bit_cast<uint64_t>(a.positions[v][c]),
                std::bit_cast<uint64_t>(b.positions[v][c]))
          << "vertex " << v << " component " << c;
    }
  }
  EXPECT_EQ(a.indices, b.indices);
}

// ---- Encoding --------------------------------------------------------------------------

TEST(MeshAssetTest, RoundTripIsBitExact) {
  const MeshFileData mesh = Tetrahedron();
  const std::string bytes = EncodeMeshAsset(mesh);
  absl::StatusOr<MeshFileData> decoded = DecodeMeshAsset(bytes, "ctx");
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  ExpectBitIdentical(*decoded, mesh);
  // -0.0 keeps its sign: equality of doubles would not notice.
  EXPECT_TRUE(std::signbit(decoded->positions[0].y));
  EXPECT_EQ(EncodeMeshAsset(*decoded), bytes);
}

TEST(MeshAssetTest, SameMeshSameBytesSameHash) {
  EXPECT_EQ(EncodeMeshAsset(Tetrahedron()), EncodeMeshAsset(Tetrahedron()));
  EXPECT_EQ(Sha256Hex(EncodeMeshAsset(Tetrahedron())), Sha256Hex(EncodeMeshAsset(Tetrahedron())));
  MeshFileData moved = Tetrahedron();
  moved.positions[2].z = std::nextafter(moved.positions[2].z, 0.0);  // one ulp
  EXPECT_NE(Sha256Hex(EncodeMeshAsset(moved)), Sha256Hex(EncodeMeshAsset(Tetrahedron())));
}

TEST(MeshAssetTest, LayoutIsLittleEndianAsDocumented) {
  const std::string bytes = EncodeMeshAsset(Triangle());
  ASSERT_EQ(bytes.size(), kHeaderBytes + 3 * 24 + 3 * 4);
  EXPECT_EQ(bytes.substr(0, 8), "PDSMMESH");
  EXPECT_EQ(bytes.substr(8, 4), std::string("\x01\x00\x00\x00", 4));                   // version
  EXPECT_EQ(bytes.substr(12, 8), std::string("\x03\x00\x00\x00\x00\x00\x00\x00", 8));  // vertices
  EXPECT_EQ(bytes.substr(20, 8), std::string("\x03\x00\x00\x00\x00\x00\x00\x00", 8));  // indices
  // Vertex 0 x = 1.0 = 0x3ff0000000000000.
  EXPECT_EQ(bytes.substr(28, 8), std::string("\x00\x00\x00\x00\x00\x00\xf0\x3f", 8));
  // The last index, 2.
  EXPECT_EQ(bytes.substr(bytes.size() - 4), std::string("\x02\x00\x00\x00", 4));
}

// ---- Decoding errors -------------------------------------------------------------------

TEST(MeshAssetTest, EveryTruncationIsInvalidArgument) {
  // An opaque mesh (version 1) and an alpha-tested one (version 2, its masks after the mesh).
  for (const MeshFileData& mesh : {Triangle(), MaskedQuad()}) {
    const std::string bytes = EncodeMeshAsset(mesh);
    for (size_t n = 0; n < bytes.size(); ++n) {
      SCOPED_TRACE(absl::StrCat(n, " of ", bytes.size(), " bytes"));
      absl::StatusOr<MeshFileData> decoded =
          DecodeMeshAsset(std::string_view(bytes).substr(0, n), "ctx");
      ASSERT_FALSE(decoded.ok());
      EXPECT_EQ(decoded.status().code(), absl::StatusCode::kInvalidArgument) << decoded.status();
      EXPECT_THAT(std::string(decoded.status().message()), StartsWith("ctx: "));
    }
    ExpectInvalid(DecodeMeshAsset(bytes + '\0', "ctx"), "size mismatch");
  }
  const std::string bytes = EncodeMeshAsset(Triangle());
  ExpectInvalid(DecodeMeshAsset(bytes.substr(0, 20), "ctx"), "truncated");
  ExpectInvalid(DecodeMeshAsset(bytes.substr(0, bytes.size() - 1), "ctx"), "size mismatch");
}

TEST(MeshAssetTest, BadMagic) {
  std::string bytes = EncodeMeshAsset(Triangle());
  bytes[4] = 'T';
  ExpectInvalid(DecodeMeshAsset(bytes, "ctx"), "not a mesh asset (bad magic)");
  ExpectInvalid(DecodeMeshAsset("ply\nformat ascii 1.0\n", "ctx"), "bad magic");
}

TEST(MeshAssetTest, UnknownVersion) {
  std::string bytes = EncodeMeshAsset(Triangle());
  PutU32(&bytes, 8, 3);
  ExpectInvalid(DecodeMeshAsset(bytes, "ctx"), "unsupported mesh asset version 3");
  // Version 2 says masks follow: an opaque mesh's bytes end before them.
  PutU32(&bytes, 8, 2);
  ExpectInvalid(DecodeMeshAsset(bytes, "ctx"), "size mismatch");
}

// ---- Alpha-tested meshes (version 2) ---------------------------------------------------

TEST(MeshAssetTest, MaskedMeshRoundTripsAsVersionTwo) {
  const MeshFileData mesh = MaskedQuad();
  const std::string bytes = EncodeMeshAsset(mesh);
  EXPECT_EQ(bytes.substr(8, 4), std::string("\x02\x00\x00\x00", 4));
  ASSERT_EQ(bytes.size(), kHeaderBytes + 4 * 24 + 6 * 4 + 4 + (14 + 6) + 4 * 8 + 2 * 2);
  absl::StatusOr<MeshFileData> decoded = DecodeMeshAsset(bytes, "ctx");
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  ExpectBitIdentical(*decoded, mesh);
  EXPECT_EQ(decoded->uvs, mesh.uvs);
  EXPECT_EQ(decoded->triangle_masks, mesh.triangle_masks);
  ASSERT_EQ(decoded->masks.size(), 1u);
  EXPECT_TRUE(SameMask(*decoded->masks[0], *mesh.masks[0]));
  EXPECT_EQ(decoded->masks[0]->label, "mask 1");
  EXPECT_EQ(EncodeMeshAsset(*decoded), bytes);
  // Opaque meshes stay version 1: their hashes are what they were before masks.
  EXPECT_EQ(EncodeMeshAsset(Triangle()).substr(8, 4), std::string("\x01\x00\x00\x00", 4));
}

TEST(MeshAssetTest, BadMasksAreInvalidArgument) {
  const std::string good = EncodeMeshAsset(MaskedQuad());
  const size_t masks_at = kHeaderBytes + 4 * 24 + 6 * 4;  // the mask count
  std::string bytes = good;
  PutU32(&bytes, masks_at, 0);
  ExpectInvalid(DecodeMeshAsset(bytes, "ctx"), "the mask count must be in [1, 65535] (got 0)");
  bytes = good;
  PutU32(&bytes, masks_at + 4, 0);  // width 0
  ExpectInvalid(DecodeMeshAsset(bytes, "ctx"), "mask 1: 0x2 texels");
  bytes = good;
  bytes[masks_at + 12] = 3;  // wrap_u
  ExpectInvalid(DecodeMeshAsset(bytes, "ctx"), "not a mask");
  bytes = good;
  PutU32(&bytes, masks_at + 14, std::bit_cast<uint32_t>(0.0f));  // cutoff
  ExpectInvalid(DecodeMeshAsset(bytes, "ctx"), "not a mask");
  bytes = good;
  PutU32(&bytes, masks_at + 18 + 6, std::bit_cast<uint32_t>(std::nanf("")));  // vertex 0's u
  ExpectInvalid(DecodeMeshAsset(bytes, "ctx"), "the UV of vertex 0 must be finite");
  bytes = good;
  bytes[bytes.size() - 2] = 2;  // triangle 1's mask: 2 of 1
  ExpectInvalid(DecodeMeshAsset(bytes, "ctx"), "triangle 1's mask must be <= 1");
}

TEST(MeshAssetTest, IndexOutOfRange) {
  std::string bytes = EncodeMeshAsset(Triangle());
  PutU32(&bytes, bytes.size() - 4, 3);
  ExpectInvalid(DecodeMeshAsset(bytes, "ctx"), "index 2 must be < 3, the vertex count (got 3)");
}

TEST(MeshAssetTest, NonFiniteCoordinates) {
  for (const double bad :
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
        -std::numeric_limits<double>::infinity()}) {
    std::string bytes = EncodeMeshAsset(Triangle());
    PutF64(&bytes, kHeaderBytes + 24 + 8, bad);  // vertex 1, y
    ExpectInvalid(DecodeMeshAsset(bytes, "ctx"), "vertex 1 must be finite (got 0, ");
  }
  std::string bytes = EncodeMeshAsset(Triangle());
  PutF64(&bytes, kHeaderBytes, std::numeric_limits<double>::quiet_NaN());
  ExpectInvalid(DecodeMeshAsset(bytes, "ctx"), "vertex 0 must be finite (got NaN, 0, 0)");
}

TEST(MeshAssetTest, NoTrianglesOrIncompleteTriangle) {
  MeshFileData empty;
  ExpectInvalid(DecodeMeshAsset(EncodeMeshAsset(empty), "ctx"), "no triangles");
  MeshFileData vertices_only = Triangle();
  vertices_only.indices.clear();
  ExpectInvalid(DecodeMeshAsset(EncodeMeshAsset(vertices_only), "ctx"), "no triangles");
  MeshFileData two_indices = Triangle();
  two_indices.indices.pop_back();
  ExpectInvalid(DecodeMeshAsset(EncodeMeshAsset(two_indices), "ctx"),
                "the index count must be a multiple of 3 (got 2)");
}

// Counts whose byte sizes wrap around 2^64 to match the blob must be caught before anything is
// multiplied or allocated.
TEST(MeshAssetTest, HugeCountsAreRefusedWithoutAllocating) {
  const std::string header = EncodeMeshAsset(MeshFileData{}).substr(0, kHeaderBytes);
  for (const auto& [vertices, indices] :
       {std::pair<uint64_t, uint64_t>{uint64_t{1} << 61, 0},  // 24 * 2^61 = 0 mod 2^64
        std::pair<uint64_t, uint64_t>{0, uint64_t{1} << 62},  // 4 * 2^62 = 0 mod 2^64
        std::pair<uint64_t, uint64_t>{(uint64_t{1} << 61) + 1, uint64_t{1} << 62},  // 24 + 0
        std::pair<uint64_t, uint64_t>{1, uint64_t{1} << 62},
        std::pair<uint64_t, uint64_t>{~uint64_t{0}, ~uint64_t{0}}}) {
    SCOPED_TRACE(absl::StrCat(vertices, " vertices, ", indices, " indices"));
    std::string bytes = header + std::string(24, '\0');
    PutU64(&bytes, 12, vertices);
    PutU64(&bytes, 20, indices);
    ExpectInvalid(DecodeMeshAsset(bytes, "ctx"), "size mismatch");
  }
}

// ---- Hashes ----------------------------------------------------------------------------

TEST(Sha256Test, KnownVectors) {
  // FIPS 180-2 examples.
  EXPECT_EQ(Sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(Sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(Sha256Hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Sha256Test, IncrementalEqualsOneShot) {
  std::string data;
  for (int i = 0; i < 5000; ++i) data.push_back(static_cast<char>((i * 131 + 7) & 0xff));
  const std::string expected = Sha256Hex(data);
  for (const size_t piece :
       {size_t{1}, size_t{3}, size_t{63}, size_t{64}, size_t{65}, size_t{1000}, data.size()}) {
    SCOPED_TRACE(absl::StrCat("pieces of ", piece));
    Sha256 hash;
    for (size_t offset = 0; offset < data.size(); offset += piece) {
      hash.Update(std::string_view(data).substr(offset, piece));
    }
    EXPECT_EQ(hash.FinalHex(), expected);
  }
  Sha256 empty;
  EXPECT_EQ(empty.FinalHex(), Sha256Hex(""));
}

TEST(Sha256Test, FinalHexStartsOver) {
  Sha256 hash;
  hash.Update("ab");
  hash.Update("c");
  EXPECT_EQ(hash.FinalHex(), Sha256Hex("abc"));
  hash.Update("abc");
  EXPECT_EQ(hash.FinalHex(), Sha256Hex("abc"));
  EXPECT_EQ(hash.FinalHex(), Sha256Hex(""));
  Sha256 moved = std::move(hash);
  moved.Update("abc");
  EXPECT_EQ(moved.FinalHex(), Sha256Hex("abc"));
}

TEST(Sha256Test, IsSha256Hex) {
  const std::string good = Sha256Hex("abc");
  EXPECT_TRUE(IsSha256Hex(good));
  EXPECT_TRUE(IsSha256Hex(std::string(64, '0')));
  EXPECT_FALSE(IsSha256Hex(""));
  EXPECT_FALSE(IsSha256Hex(good.substr(0, 63)));
  EXPECT_FALSE(IsSha256Hex(good + "0"));
  std::string upper = good;
  upper[0] = 'B';
  EXPECT_FALSE(IsSha256Hex(upper));
  std::string g = good;
  g[10] = 'g';
  EXPECT_FALSE(IsSha256Hex(g));
  EXPECT_FALSE(IsSha256Hex(std::string("../") + good.substr(3)));
  EXPECT_FALSE(IsSha256Hex(std::string(good.substr(0, 63)) + '\0'));
}

}  // namespace
}  // namespace pdsm
