#include "core/pipeline/stage_rule.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "core/bake/adaptive_sampling.h"
#include "core/util/fault_injecting_file_system.h"

namespace pdsm {
namespace {

// A one-pixel tile whose samples [begin, end) are in shadow over [z_in, 8).
TileEvents Shadowed(int begin, int end, float z_in) {
  TileEvents out{.tile_index = 0, .x0 = 0, .y0 = 0, .width = 1, .height = 1};
  if (end > begin) out.events = {{z_in, end - begin}, {8.0f, begin - end}};
  out.offsets = {0, out.events.size()};
  return out;
}

PdsmHeader Header(int samples, double tolerance = 0, int min_samples = 0) {
  PdsmHeader h;
  h.samples = samples;
  h.geometry.z_near = 1;
  h.geometry.z_far = 10;
  h.adaptive_tolerance = tolerance;
  h.adaptive_min_samples = min_samples;
  return h;
}

// Each range's parts merged into one list (runs read back from `spill`).
std::vector<TileEvents> Merged(std::vector<TileParts> ranges, EventSpill* spill = nullptr) {
  std::vector<TileEvents> out;
  for (TileParts& parts : ranges) {
    for (const SpilledRun& run : parts.spilled) {
      absl::StatusOr<TileEvents> read = spill->ReadAndRelease(run, parts.shape);
      EXPECT_TRUE(read.ok()) << read.status();
      if (read.ok()) parts.in_memory.push_back(*std::move(read));
    }
    out.push_back(MergeTileEvents(parts.in_memory, EventKeying::kCounts));
  }
  return out;
}

// The verdict, which cannot fail without runs.
StageVerdict Judge(const PdsmHeader& header, TileStageState state, std::vector<TileParts> ranges) {
  absl::StatusOr<StageVerdict> verdict =
      JudgeStage(header, std::move(state), std::move(ranges), nullptr);
  EXPECT_TRUE(verdict.ok()) << verdict.status();
  return verdict.ok() ? *std::move(verdict) : StageVerdict{};
}

TEST(StageAccumulator, MergesBatchesOfARangeWhateverTheirOrder) {
  StageAccumulator a(Header(8), 0), b(Header(8), 0);
  a.Add(4, Shadowed(4, 8, 3));
  a.Add(0, Shadowed(0, 4, 2));
  b.Add(0, Shadowed(0, 2, 2));
  b.Add(6, Shadowed(6, 8, 3));
  b.Add(2, Shadowed(2, 4, 2));
  b.Add(4, Shadowed(4, 6, 3));
  const std::vector<TileEvents> ra = Merged(a.TakeRanges()), rb = Merged(b.TakeRanges());
  ASSERT_EQ(ra.size(), 1u);
  ASSERT_EQ(rb.size(), 1u);
  EXPECT_EQ(ra[0].events, rb[0].events);
  EXPECT_EQ(ra[0].events, (std::vector<Event>{{2.0f, 4}, {3.0f, 4}, {8.0f, -8}}));
}

TEST(StageAccumulator, AdaptivePilotKeepsItsTwoHalvesApart) {
  StageAccumulator acc(Header(64, 0.01, 4), 0);  // ranges [0, 2) and [2, 4)
  acc.Add(2, Shadowed(2, 4, 5));
  acc.Add(0, Shadowed(0, 2, 2));
  const std::vector<TileEvents> ranges = Merged(acc.TakeRanges());
  ASSERT_EQ(ranges.size(), 2u);
  EXPECT_EQ(ranges[0].events.front(), (Event{2.0f, 2}));
  EXPECT_EQ(ranges[1].events.front(), (Event{5.0f, 2}));
}

TEST(JudgeStage, FixedCountStageIsTheTile) {
  StageAccumulator acc(Header(8), 0);
  acc.Add(4, Shadowed(4, 8, 3));
  acc.Add(0, Shadowed(0, 4, 2));
  const StageVerdict v = Judge(Header(8), {}, acc.TakeRanges());
  ASSERT_TRUE(v.done);
  EXPECT_EQ(v.tile_samples, 0);
  EXPECT_EQ(v.samples_skipped, 0);
  ASSERT_EQ(v.events.in_memory.size(), 1u);
  EXPECT_EQ(v.events.in_memory[0].events.front(), (Event{2.0f, 4}));
}

TEST(JudgeStage, AdaptivePilotThatAgreesIsDone) {
  StageAccumulator acc(Header(64, 0.01, 4), 0);
  acc.Add(2, Shadowed(2, 4, 2));
  acc.Add(0, Shadowed(0, 2, 2));
  const StageVerdict v = Judge(Header(64, 0.01, 4), {}, acc.TakeRanges());
  ASSERT_TRUE(v.done);
  EXPECT_EQ(v.tile_samples, 4);
  EXPECT_EQ(v.samples_skipped, 60);
  ASSERT_EQ(v.events.in_memory.size(), 1u);  // one merged list of every sample so far
  EXPECT_EQ(v.events.in_memory[0].events.front(), (Event{2.0f, 4}));
}

TEST(JudgeStage, AdaptivePilotThatDisagreesGoesOnWithItsEventsKept) {
  StageAccumulator pilot(Header(64, 0.01, 4), 0);
  pilot.Add(0, Shadowed(0, 2, 2));
  pilot.Add(2, Shadowed(2, 4, 5));  // the second half sees another shadow
  const StageVerdict v = Judge(Header(64, 0.01, 4), {}, pilot.TakeRanges());
  ASSERT_FALSE(v.done);
  EXPECT_EQ(v.next.stage, 1);
  ASSERT_EQ(v.next.earlier.size(), 1u);
  EXPECT_EQ(v.next.earlier[0].events.size(), 3u);  // 2 (+2), 5 (+2), 8 (-4)

  // Stage 1 is [4, 8); cut into two batches, which changes nothing.
  const std::vector<SampleRange> ranges = StageRanges(Header(64, 0.01, 4), 1);
  ASSERT_EQ(ranges.size(), 1u);
  EXPECT_EQ(ranges[0].begin, 4);
  EXPECT_EQ(ranges[0].end, 8);
  StageAccumulator stage1(Header(64, 0.01, 4), 1);
  stage1.Add(6, Shadowed(6, 8, 2));
  stage1.Add(4, Shadowed(4, 6, 5));
  const StageVerdict w = Judge(Header(64, 0.01, 4), v.next, stage1.TakeRanges());
  EXPECT_TRUE(w.done);  // the same mix as the first four: A_8 = A_4
  EXPECT_EQ(w.tile_samples, 8);
}

TEST(JudgeStage, LastAdaptiveStageIsDoneWhateverTheEstimate) {
  StageAccumulator acc(Header(2, 1e-9, 2), 0);
  acc.Add(0, Shadowed(0, 1, 2));
  acc.Add(1, Shadowed(1, 2, 6));
  const StageVerdict v = Judge(Header(2, 1e-9, 2), {}, acc.TakeRanges());
  EXPECT_TRUE(v.done);
  EXPECT_EQ(v.tile_samples, 2);
  EXPECT_EQ(v.samples_skipped, 0);
}

// A tile of `pixels` pixels, each with a few events at random depths for samples [begin, end).
TileEvents RandomBatch(std::mt19937_64& rng, int width, int height) {
  TileEvents out{.tile_index = 3, .x0 = 16, .y0 = 8, .width = width, .height = height};
  std::uniform_real_distribution<float> depth(1.0f, 9.0f);
  std::uniform_int_distribution<int> count(0, 5);
  out.offsets.push_back(0);
  for (int p = 0; p < width * height; ++p) {
    std::vector<Event> pixel;
    for (int k = count(rng); k > 0; --k) pixel.push_back({depth(rng), k % 2 ? 1 : -1});
    NormalizeEvents(&pixel, EventKeying::kCounts);
    out.events.insert(out.events.end(), pixel.begin(), pixel.end());
    out.offsets.push_back(out.events.size());
  }
  return out;
}

TEST(StageAccumulator, SpilledRunsMergeBackToTheSameLists) {
  const std::string dir = ::testing::TempDir();
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    StageAccumulator memory(Header(64), 0), spilled(Header(64), 0);
    EventSpill spill(dir);
    for (int batch = 0; batch < 16; ++batch) {
      const TileEvents events = RandomBatch(rng, 4, 3);
      memory.Add(batch * 4, events);
      spilled.Add(batch * 4, events);
      if ((batch + trial) % 3 == 0) {
        ASSERT_TRUE(spilled.Spill(&spill).ok());
        EXPECT_EQ(spilled.MemoryBytes(), 0);
      }
    }
    EXPECT_GT(spill.bytes_written(), 0);
    const std::vector<TileEvents> a = Merged(memory.TakeRanges());
    const std::vector<TileEvents> b = Merged(spilled.TakeRanges(), &spill);
    ASSERT_EQ(a.size(), 1u);
    ASSERT_EQ(b.size(), 1u);
    EXPECT_EQ(b[0].tile_index, 3);
    EXPECT_EQ(b[0].x0, 16);
    EXPECT_EQ(b[0].height, 3);
    EXPECT_EQ(a[0].offsets, b[0].offsets) << "trial " << trial;
    EXPECT_EQ(a[0].events, b[0].events) << "trial " << trial;
  }
}

TEST(StageAccumulator, AFailedSpillKeepsTheListsAndNamesTheFolder) {
  FaultInjectingFileSystem fs;
  EventSpill spill(::testing::TempDir(), &fs);
  std::mt19937_64 rng(5);
  StageAccumulator acc(Header(8), 0), reference(Header(8), 0);
  TileEvents batch = RandomBatch(rng, 8, 8);
  while (batch.events.empty()) batch = RandomBatch(rng, 8, 8);
  acc.Add(0, batch);
  reference.Add(0, batch);
  fs.SetDiskFullAfter(16);
  const absl::Status full = acc.Spill(&spill);
  EXPECT_EQ(full.code(), absl::StatusCode::kResourceExhausted) << full;
  EXPECT_NE(full.message().find("scratch file"), std::string::npos) << full;
  EXPECT_GT(acc.MemoryBytes(), 0);
  fs.Reset();
  fs.FailNth(FileOp::kCreate, 1, EACCES);
  EventSpill unwritable(::testing::TempDir(), &fs);
  EXPECT_EQ(acc.Spill(&unwritable).code(), absl::StatusCode::kPermissionDenied);
  // The lists are whole: a spill that works now gives back the same events.
  ASSERT_TRUE(acc.Spill(&unwritable).ok());
  EXPECT_EQ(Merged(acc.TakeRanges(), &unwritable)[0].events,
            Merged(reference.TakeRanges())[0].events);
}

TEST(EventSpill, LeavesNoFileBehind) {
  const std::filesystem::path dir =
      std::filesystem::path(::testing::TempDir()) / "spill_leaves_nothing";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  {
    EventSpill spill(dir.string());
    std::mt19937_64 rng(3);
    TileEvents batch = RandomBatch(rng, 8, 8);
    const absl::StatusOr<SpilledRun> run = spill.Write(batch);
    ASSERT_TRUE(run.ok()) << run.status();
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir),
                            std::filesystem::directory_iterator()),
              0)
        << "the scratch file has no name";
    const absl::StatusOr<TileEvents> back = spill.ReadAndRelease(*run, batch);
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(back->events, batch.events);
    EXPECT_EQ(back->offsets, batch.offsets);
  }
  std::filesystem::remove_all(dir);
}

TEST(SpilledRunReader, ReadsEveryPixelInPiecesWhateverItsSize) {
  // 40 pixels of 0 to 3000 events, and one of 3 pieces' worth: the reader crosses piece
  // boundaries inside pixels and reads the big pixel whole.
  TileEvents run_events{.tile_index = 1, .x0 = 0, .y0 = 0, .width = 41, .height = 1};
  run_events.offsets.push_back(0);
  std::mt19937_64 rng(9);
  for (int p = 0; p < 41; ++p) {
    const size_t n = p == 17 ? 3 * SpilledRunReader::kPieceEvents : rng() % 3000;
    for (size_t k = 0; k < n; ++k) {
      run_events.events.push_back({static_cast<float>(k), static_cast<int32_t>(p + 1)});
    }
    run_events.offsets.push_back(run_events.events.size());
  }
  EventSpill spill(::testing::TempDir());
  const absl::StatusOr<SpilledRun> run = spill.Write(run_events);
  ASSERT_TRUE(run.ok()) << run.status();
  for (const int stride : {1, 3}) {
    SpilledRunReader reader(&spill, *run);
    for (size_t p = 0; p < 41; p += stride) {
      const std::span<const Event> got = reader.Pixel(p);
      const std::span<const Event> want = run_events.Pixel(p);
      ASSERT_EQ(std::vector<Event>(got.begin(), got.end()),
                std::vector<Event>(want.begin(), want.end()))
          << "stride " << stride << " pixel " << p;
    }
    EXPECT_TRUE(reader.status().ok()) << reader.status();
  }
}

TEST(EventSpill, MissingFolderIsNotFoundNamingIt) {
  EventSpill spill("/nonexistent-pdsm-folder/x");
  std::mt19937_64 rng(3);
  const absl::StatusOr<SpilledRun> run = spill.Write(RandomBatch(rng, 2, 2));
  EXPECT_EQ(run.status().code(), absl::StatusCode::kNotFound);
  EXPECT_NE(run.status().message().find("/nonexistent-pdsm-folder/x"), std::string::npos);
}

}  // namespace
}  // namespace pdsm
