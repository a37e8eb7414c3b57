// The viewer's PDSM as a virtual texture (issue #12 item 6): the range allocator of its tile
// pool, the tiles a frame asks for, the pool's blocks after eviction and compaction read back
// from the GPU, and frames drawn under a budget smaller than the view needs.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <random>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "client/view/frame_renderer.h"
#include "client/view/pdsm_tile_pool.h"
#include "client/view/pdsm_tiles.h"
#include "client/view/range_allocator.h"
#include "client/view/tile_requests.h"
#include "client/view/view_scene.h"
#include "core/pdsm/pdsm_file.h"
#include "core/scene/scene_loader.h"
#include "gl/gl_functions.h"
#include "gl/platform/osmesa_context.h"
#include "tests/view/view_test_support.h"

namespace pdsm::testing {
namespace {

// Random allocations and frees against a map of what is held: ranges never overlap, stay
// inside the capacity, freed space merges (one free range once everything is freed), and
// Compact packs the held ranges from 0 in their order, with moves that only go down.
TEST(RangeAllocator, RangesNeverOverlapFreedSpaceMergesAndCompactionPacksInOrder) {
  std::mt19937 rng(7);
  view::RangeAllocator allocator(1000);
  std::map<uint64_t, uint64_t> held;  // offset -> size
  int failures = 0;
  for (int step = 0; step < 4000; ++step) {
    if (held.empty() || rng() % 3 != 0) {
      const uint64_t size = 1 + rng() % 60;
      std::optional<uint64_t> offset = allocator.Allocate(size);
      if (!offset) {
        ++failures;
        EXPECT_LT(allocator.largest_free(), size);
        continue;
      }
      ASSERT_LE(*offset + size, allocator.capacity());
      auto next = held.lower_bound(*offset);
      if (next != held.end()) {
        ASSERT_LE(*offset + size, next->first);
      }
      if (next != held.begin()) {
        auto previous = std::prev(next);
        ASSERT_LE(previous->first + previous->second, *offset);
      }
      held[*offset] = size;
    } else {
      auto it = std::next(held.begin(), rng() % held.size());
      allocator.Free(it->first, it->second);
      held.erase(it);
    }
    uint64_t used = 0;
    for (const auto& [offset, size] : held) used += size;
    ASSERT_EQ(allocator.used(), used);
    if (step % 500 == 499) {
      const std::vector<view::RangeAllocator::Move> moves = allocator.Compact();
      std::map<uint64_t, uint64_t> packed;
      uint64_t next = 0;
      size_t m = 0;
      for (const auto& [offset, size] : held) {
        if (offset != next) {
          ASSERT_LT(m, moves.size());
          EXPECT_EQ(moves[m].from, offset);
          EXPECT_EQ(moves[m].to, next);
          EXPECT_EQ(moves[m].size, size);
          EXPECT_LT(moves[m].to, moves[m].from);
          ++m;
        }
        packed[next] = size;
        next += size;
      }
      EXPECT_EQ(m, moves.size());
      held = packed;
      EXPECT_EQ(allocator.largest_free(), allocator.capacity() - used);
    }
  }
  EXPECT_GT(failures, 0);  // the pool did fill up
  for (const auto& [offset, size] : held) allocator.Free(offset, size);
  EXPECT_EQ(allocator.largest_free(), allocator.capacity());
  allocator.Grow(1500);
  EXPECT_EQ(allocator.largest_free(), 1500u);
}

// A pixel asks for the tiles of the PDSM pixels within 1.5 pixels of where it projects, and
// pixels outside the frustum or without a surface ask for none.
TEST(TilesSeen, APixelAsksForTheTilesItsLookupCanReadAndNothingOutside) {
  PdsmHeader h;
  h.geometry.projection = Projection::kOrthographic;
  h.geometry.width = 100;
  h.geometry.height = 60;
  h.geometry.s_min = 0, h.geometry.s_max = 100, h.geometry.t_min = 0, h.geometry.t_max = 60;
  h.tile_size = 20;  // 5 x 3 tiles
  const auto seen = [&h](std::vector<float> positions) {
    std::map<std::pair<int, int>, int64_t> tiles;
    for (const view::TileRequest& r : view::TilesSeen(h, positions)) {
      tiles[{r.tile_x, r.tile_y}] = r.pixels;
    }
    return tiles;
  };
  // Inside a tile, far from its edges: that tile alone, once per screen pixel.
  EXPECT_EQ(seen({50, 30, 1, 1, 50.2f, 30.1f, 1, 1}),
            (std::map<std::pair<int, int>, int64_t>{{{2, 1}, 2}}));
  // Within 1.5 pixels of a corner: the four tiles around it.
  EXPECT_EQ(seen({40.9f, 20.4f, 1, 1}).size(), 4u);
  // No surface, outside the window, NaN: nothing.
  EXPECT_TRUE(seen({50, 30, 1, 0, 120, 30, 1, 1, -1, 30, 1, 1, NAN, NAN, NAN, 1}).empty());
  // The border pixel of the map reads the border tiles only (clamped, as shade.frag does).
  EXPECT_EQ(seen({100, 60, 1, 1}), (std::map<std::pair<int, int>, int64_t>{{{4, 2}, 1}}));
}

// A PDSM of 1 x 5 one-pixel tiles whose functions hold `counts[i]` vertices each.
PdsmImage OnePixelTiles(const std::vector<int>& counts) {
  PdsmImage image;
  image.header.geometry.projection = Projection::kOrthographic;
  image.header.geometry.width = static_cast<int>(counts.size());
  image.header.geometry.height = 1;
  image.header.tile_size = 1;
  image.offsets.push_back(0);
  for (size_t p = 0; p < counts.size(); ++p) {
    for (int v = 0; v < counts[p]; ++v) {
      image.vertices.push_back(
          {static_cast<float>(v) + 0.25f * static_cast<float>(p), static_cast<float>(v) / 64.0f});
    }
    image.offsets.push_back(image.vertices.size());
  }
  return image;
}

// Reads the pool back from the GPU and checks that every resident tile's block holds its
// functions bit for bit, and that the resident blocks never overlap.
void ExpectBlocksHoldTheirTiles(const gl::GlFunctions& gl, const view::PdsmTilePool& pool,
                                view::PdsmTiles& source) {
  std::vector<uint32_t> pages(static_cast<size_t>(source.tiles_x()) * source.tiles_y());
  gl.BindBuffer(GL_SHADER_STORAGE_BUFFER, pool.page_table());
  gl.GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, static_cast<GLsizeiptr>(pages.size() * 4),
                      pages.data());
  std::vector<std::vector<uint32_t>> buffers(pool.stats().buffers);
  for (int b = 0; b < pool.stats().buffers; ++b) {
    buffers[b].resize(pool.pool_capacity_bytes(b) / 4);
    gl.BindBuffer(GL_SHADER_STORAGE_BUFFER, pool.pool(b));
    gl.GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, static_cast<GLsizeiptr>(buffers[b].size() * 4),
                        buffers[b].data());
  }
  gl.BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  ASSERT_EQ(gl.GetError(), static_cast<GLenum>(GL_NO_ERROR));
  std::vector<std::tuple<int, uint64_t, uint64_t>> blocks;  // buffer, offset, size
  for (int ty = 0; ty < source.tiles_y(); ++ty) {
    for (int tx = 0; tx < source.tiles_x(); ++tx) {
      const uint32_t page = pages[static_cast<size_t>(ty) * source.tiles_x() + tx];
      if (page >= view::kTileNotResident) continue;
      const int b = static_cast<int>(page >> view::kPoolOffsetBits);
      const uint64_t block = page & ((1u << view::kPoolOffsetBits) - 1);
      ASSERT_LT(b, pool.stats().buffers);
      const std::vector<uint32_t>& words = buffers[b];
      absl::StatusOr<std::shared_ptr<const PdsmTile>> tile = source.Tile(tx, ty);
      ASSERT_TRUE(tile.ok() && *tile);
      const PdsmTile& t = **tile;
      const uint64_t pixels = static_cast<uint64_t>(t.width) * t.height;
      blocks.push_back({b, block, pixels + t.vertices.size()});
      ASSERT_LE(2 * (block + pixels + t.vertices.size()), words.size());
      for (int y = 0; y < t.height; ++y) {
        for (int x = 0; x < t.width; ++x) {
          const size_t entry = 2 * (block + static_cast<size_t>(y) * t.width + x);
          const std::span<const Vertex> f = t.Function(x, y);
          ASSERT_EQ(words[entry + 1], f.size()) << "tile " << tx << "," << ty;
          for (size_t v = 0; v < f.size(); ++v) {
            const size_t at = 2 * (block + words[entry] + v);
            EXPECT_EQ(std::memcmp(&words[at], &f[v], sizeof(Vertex)), 0)
                << "tile " << tx << "," << ty << " vertex " << v;
          }
        }
      }
    }
  }
  std::sort(blocks.begin(), blocks.end());
  for (size_t i = 1; i < blocks.size(); ++i) {
    const auto& [b0, offset0, size0] = blocks[i - 1];
    const auto& [b1, offset1, size1] = blocks[i];
    if (b0 == b1) {
      EXPECT_LE(offset0 + size0, offset1);
    }
  }
}

// Asks for the one-pixel tiles `tiles` of part 0 (one screen pixel each), then reads the pool
// back.
void RequestAndCheck(const gl::GlFunctions& gl, view::PdsmTilePool& pool, view::PdsmTiles& source,
                     const std::vector<int>& tiles) {
  std::vector<view::TileRequest> requests;
  for (int t : tiles) requests.push_back({0, t, 0, 1});
  ASSERT_TRUE(pool.Request(requests).ok());
  ExpectBlocksHoldTheirTiles(gl, pool, source);
}

struct GlContext {
  std::optional<gl::OsMesaContext> context;
  std::optional<gl::GlFunctions> gl;
};

GlContext MakeGl() {
  GlContext c;
  absl::StatusOr<gl::OsMesaContext> context = gl::OsMesaContext::Create();
  EXPECT_TRUE(context.ok()) << context.status();
  if (!context.ok()) return c;
  c.context.emplace(*std::move(context));
  absl::StatusOr<gl::GlFunctions> gl = gl::GlFunctions::Load(&gl::OsMesaContext::GetProcAddress);
  EXPECT_TRUE(gl.ok()) << gl.status();
  if (gl.ok()) c.gl.emplace(*gl);
  return c;
}

// Tiles of 30, 30, 30, 20 and 20 units (a pixel's entry plus its vertices) in a pool of 100:
// the fourth evicts the one tile not asked for, the fifth fits only once the pool is compacted
// (20 units free, in two gaps of 10), and a tile no pool of the budget holds stays out. After
// each step the blocks read back from the GPU hold their tiles bit for bit.
TEST(PdsmTilePool, EvictsWhatIsNotAskedForCompactsAndKeepsEveryBlockExact) {
  GlContext c = MakeGl();
  ASSERT_TRUE(c.gl);
  const gl::GlFunctions& gl = *c.gl;
  std::shared_ptr<view::PdsmTiles> source =
      view::PdsmTiles::FromImage(OnePixelTiles({29, 29, 29, 19, 19, 0, 120}));
  absl::StatusOr<std::unique_ptr<view::PdsmTilePool>> created =
      view::PdsmTilePool::Create(gl, {source}, 100 * 8);
  ASSERT_TRUE(created.ok()) << created.status();
  view::PdsmTilePool& pool = **created;
  const auto request = [&](std::vector<int> tiles) { RequestAndCheck(gl, pool, *source, tiles); };
  request({0, 1, 2});
  EXPECT_EQ(pool.stats().resident_tiles, 3);
  EXPECT_EQ(pool.stats().used_bytes, 90u * 8);
  request({0, 2, 3});  // tile 1 goes: [0,30) [30,50) [60,90), gaps of 10 at 50 and 90
  EXPECT_EQ(pool.stats().tiles_evicted, 1);
  EXPECT_EQ(pool.stats().missing_tiles, 0);
  request({0, 2, 4});  // 20 free in two gaps: compaction, tile 3 stays
  EXPECT_EQ(pool.stats().compactions, 1);
  EXPECT_EQ(pool.stats().tiles_evicted, 1);
  EXPECT_EQ(pool.stats().resident_tiles, 4);
  EXPECT_EQ(pool.stats().used_bytes, 100u * 8);
  request({5, 6});  // an empty tile costs nothing; 121 units never fit a pool of 100
  EXPECT_EQ(pool.stats().empty_tiles, 1);
  EXPECT_EQ(pool.stats().missing_tiles, 1);
  EXPECT_LE(pool.stats().used_bytes, pool.stats().budget_bytes);
}

// Pool buffers capped at 40 units under a budget of 100 (buffers of 40, 40 and the 20 left):
// tiles of 30 units go one to a buffer; a third does not fit while both are asked for (the
// 20 left are too few for it), and evicts one once they are not; a 20-unit tile then opens the
// third buffer. Every block reads back bit for bit from its own buffer.
TEST(PdsmTilePool, SpreadsTilesOverSeveralBuffersWhenOneBindingHoldsLess) {
  GlContext c = MakeGl();
  ASSERT_TRUE(c.gl);
  const gl::GlFunctions& gl = *c.gl;
  std::shared_ptr<view::PdsmTiles> source =
      view::PdsmTiles::FromImage(OnePixelTiles({29, 29, 29, 19}));
  absl::StatusOr<std::unique_ptr<view::PdsmTilePool>> created =
      view::PdsmTilePool::Create(gl, {source}, 100 * 8, 40 * 8);
  ASSERT_TRUE(created.ok()) << created.status();
  view::PdsmTilePool& pool = **created;
  const auto request = [&](std::vector<int> tiles) { RequestAndCheck(gl, pool, *source, tiles); };
  request({0, 1});
  EXPECT_EQ(pool.stats().buffers, 2);
  EXPECT_EQ(pool.stats().resident_tiles, 2);
  request({0, 1, 2});
  EXPECT_EQ(pool.stats().buffers, 2);
  EXPECT_EQ(pool.stats().missing_tiles, 1);
  request({2, 3});  // tile 2 evicts tile 0; tile 3 opens the third buffer
  EXPECT_EQ(pool.stats().missing_tiles, 0);
  EXPECT_EQ(pool.stats().tiles_evicted, 1);
  EXPECT_EQ(pool.stats().buffers, 3);
  EXPECT_EQ(pool.stats().resident_tiles, 3);
  EXPECT_LE(pool.stats().used_bytes, pool.stats().budget_bytes);
}

// plates at 256^2 in 32-pixel tiles, drawn in pdsm mode with every tile it reads resident and
// under budgets that hold only part of them: every pixel either shows the very attenuation of
// the unlimited frame or is marked not resident; the marked part shrinks as the budget grows
// and is gone once the view fits; orbiting under a small budget evicts and reloads tiles and
// still draws the first view exactly.
TEST(ViewTileStreaming, UnderAnyBudgetAPixelIsExactOrMarkedNotResident) {
  const std::string pdsm_path = BakeExample("plates", "plates_streaming.exr", 256, 16, 256);
  absl::StatusOr<Scene> scene = LoadSceneFile(ExamplePath("plates"));  // its meshes
  ASSERT_TRUE(scene.ok()) << scene.status();

  view::ViewScene view;
  view.scene = *scene;
  absl::StatusOr<std::shared_ptr<view::PdsmTiles>> tiles =
      view::PdsmTiles::OpenFile(pdsm_path, "", int64_t{1} << 20);
  ASSERT_TRUE(tiles.ok()) << tiles.status();
  view.pdsm = *tiles;
  view::PrepareViewScene(&view);
  GlContext c = MakeGl();
  ASSERT_TRUE(c.gl);
  const view::Camera first{{4, 7, 6}, {0, 1, 0}, 40};
  const view::Camera others[] = {{{-6, 5, 3}, {0, 0, 0}, 30}, {{0, 12, 0.1}, {0, 0, 0}, 60}};
  constexpr int kWidth = 200, kHeight = 150;
  const auto draw = [&](int64_t budget, bool orbit, view::TilePoolStats* stats) {
    view::RenderSettings settings;
    settings.gpu_budget_bytes = budget;
    absl::StatusOr<std::unique_ptr<view::FrameRenderer>> r =
        view::FrameRenderer::Create(*c.gl, &view, settings);
    EXPECT_TRUE(r.ok()) << r.status();
    if (!r.ok()) return std::vector<float>();
    if (orbit) {
      for (const view::Camera& camera : others) {
        EXPECT_TRUE((*r)->Render(view::ViewMode::kPdsm, camera, kWidth, kHeight).ok());
      }
    }
    EXPECT_TRUE((*r)->Render(view::ViewMode::kPdsm, first, kWidth, kHeight).ok());
    absl::StatusOr<view::Frame> frame = (*r)->ReadFrame();
    EXPECT_TRUE(frame.ok());
    *stats = (*r)->pdsm_pool_stats();
    return frame.ok() ? frame->attenuation : std::vector<float>();
  };
  view::TilePoolStats full_stats;
  const std::vector<float> full = draw(int64_t{64} << 20, false, &full_stats);
  ASSERT_EQ(full.size(), static_cast<size_t>(kWidth) * kHeight);
  EXPECT_EQ(full_stats.missing_tiles, 0);
  EXPECT_EQ(std::count(full.begin(), full.end(), view::kNotResident), 0);
  const int64_t shadowed =
      std::count_if(full.begin(), full.end(), [](float a) { return a > 0.1f; });
  EXPECT_GT(shadowed, 500);
  const uint64_t needed = full_stats.used_bytes;
  // The same view from pool buffers of half what it needs (as a GL whose binding holds less
  // would give): the very same frame, from several buffers.
  {
    view::RenderSettings settings;
    settings.max_pool_buffer_bytes = static_cast<int64_t>(needed / 2);
    absl::StatusOr<std::unique_ptr<view::FrameRenderer>> r =
        view::FrameRenderer::Create(*c.gl, &view, settings);
    ASSERT_TRUE(r.ok()) << r.status();
    ASSERT_TRUE((*r)->Render(view::ViewMode::kPdsm, first, kWidth, kHeight).ok());
    absl::StatusOr<view::Frame> frame = (*r)->ReadFrame();
    ASSERT_TRUE(frame.ok());
    EXPECT_GE((*r)->pdsm_pool_stats().buffers, 3);
    EXPECT_EQ((*r)->pdsm_pool_stats().missing_tiles, 0);
    EXPECT_EQ(std::memcmp(frame->attenuation.data(), full.data(), full.size() * sizeof(float)), 0);
  }
  std::printf("the view reads %d tiles (%d empty), %.1f KiB resident\n", full_stats.requested_tiles,
              full_stats.empty_tiles, needed / 1024.0);

  int64_t previous_marked = -1;
  for (const double fraction : {0.25, 0.6}) {
    for (const bool orbit : {false, true}) {
      view::TilePoolStats stats;
      const std::vector<float> a =
          draw(static_cast<int64_t>(fraction * static_cast<double>(needed)), orbit, &stats);
      ASSERT_EQ(a.size(), full.size());
      int64_t marked = 0, differing = 0;
      for (size_t p = 0; p < a.size(); ++p) {
        if (a[p] == view::kNotResident) {
          ++marked;
        } else if (std::memcmp(&a[p], &full[p], sizeof(float)) != 0) {
          ++differing;
        }
      }
      std::printf(
          "budget %.0f%% of the view%s: %lld pixels not resident, %d tiles over, %lld "
          "uploaded, %lld evicted\n",
          100 * fraction, orbit ? " after orbiting" : "", static_cast<long long>(marked),
          stats.missing_tiles, static_cast<long long>(stats.tiles_uploaded),
          static_cast<long long>(stats.tiles_evicted));
      EXPECT_EQ(differing, 0) << "budget " << fraction << (orbit ? " after orbiting" : "");
      EXPECT_GT(marked, 0);
      EXPECT_GT(stats.missing_tiles, 0);
      EXPECT_LE(stats.used_bytes, stats.budget_bytes);
      if (orbit) {
        EXPECT_GT(stats.tiles_evicted, 0);
      } else {
        if (previous_marked >= 0) {
          EXPECT_LT(marked, previous_marked);
        }
        previous_marked = marked;
      }
    }
  }
}

}  // namespace
}  // namespace pdsm::testing
