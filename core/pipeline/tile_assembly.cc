#include "core/pipeline/tile_assembly.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <optional>
#include <vector>

#include "core/bake/scan_windows.h"
#include "core/bake/surface_function.h"
#include "core/events/consolidation.h"
#include "core/events/emitter_weighting.h"
#include "core/pdsm/compression.h"

namespace pdsm {

void AssemblyStats::Add(const AssemblyStats& o) {
  merged_events += o.merged_events;
  consolidated_events += o.consolidated_events;
  vertices += o.vertices;
  seconds += o.seconds;
}

PdsmTile AssembleTile(const PdsmHeader& header, std::span<const TileEvents> parts,
                      AssemblyStats* stats, const TileWindows* windows) {
  PdsmTile tile = AssembleTile(header, parts, header.samples, stats, windows);
  tile.samples = 0;  // fixed-count bake: the header's count
  return tile;
}

namespace {

// The assembly of one tile whose pixel p's lists `parts_of(p, &lists)` gives: merged,
// consolidated, turned into attenuation and compressed pixel by pixel, so a tile's merged
// lists (tens of MiB at thousands of samples) are never all in memory.
template <typename PartsOf>
PdsmTile Assemble(const PdsmHeader& header, std::span<const glm::dvec2> samples,
                  const TileEvents& shape, int tile_samples, AssemblyStats* stats,
                  const TileWindows* windows, PartsOf&& parts_of) {
  const auto start = std::chrono::steady_clock::now();
  PdsmTile tile;
  tile.x0 = shape.x0;
  tile.y0 = shape.y0;
  tile.width = shape.width;
  tile.height = shape.height;
  tile.samples = tile_samples;
  tile.offsets.assign(shape.PixelCount() + 1, 0);
  // Compression's perpendicular metric measures depth in units of the baked depth range.
  const PdsmGeometry& g = header.geometry;
  const double depth_scale = std::max(g.z_far - g.z_near, 1e-30);
  const EventKeying keying = KeyingOf(header);
  // Sample-keyed events: each pixel's shares come from its ray (emitter weighting).
  std::optional<EmitterRay> emitter;
  if (keying == EventKeying::kSampleKeys) emitter.emplace(samples, tile_samples);
  const double tolerance = EmitterTolerance(header.epsilon);
  const double quantum = EmitterQuantum(tolerance);
  std::vector<std::span<const Event>> lists;
  for (size_t p = 0; p < shape.PixelCount(); ++p) {
    parts_of(p, &lists);
    // A ray no sample shadows holds no vertex (outside surfaces-only bakes, whose windows
    // bracket every function): most of a large world's rays, so no list is made for them.
    if (windows == nullptr &&
        std::all_of(lists.begin(), lists.end(), [](const auto& l) { return l.empty(); })) {
      tile.offsets[p + 1] = tile.vertices.size();
      continue;
    }
    const std::vector<Event> merged = MergeEventLists(lists, keying);
    const std::vector<Event> events = ConsolidateEvents(merged, keying);
    std::vector<Vertex> compressed;
    if (emitter) {
      const int x = shape.x0 + static_cast<int>(p % shape.width);
      const int y = shape.y0 + static_cast<int>(p / shape.width);
      emitter->SetRay(g.PixelCenterS(x), g.PixelCenterT(y));
      if (windows != nullptr) {
        compressed = EmitterSurfaceFunction(events, windows->Pixel(p), &*emitter, tolerance,
                                            header.epsilon, header.compression_metric, depth_scale);
      } else {
        const std::vector<Vertex> function =
            EmitterWeightedFunction(events, &*emitter, g.z_far, tolerance);
        compressed =
            CompressFunction(function, header.epsilon, header.compression_metric, depth_scale);
      }
      RoundAttenuation(quantum, &compressed);
    } else if (windows != nullptr) {
      compressed = SurfaceFunction(events, windows->Pixel(p), tile_samples, header.epsilon,
                                   header.compression_metric, depth_scale);
    } else {
      const std::vector<Vertex> function = FunctionFromEvents(events, tile_samples);
      compressed =
          CompressFunction(function, header.epsilon, header.compression_metric, depth_scale);
    }
    tile.vertices.insert(tile.vertices.end(), compressed.begin(), compressed.end());
    tile.offsets[p + 1] = tile.vertices.size();
    stats->merged_events += static_cast<int64_t>(merged.size());
    stats->consolidated_events += static_cast<int64_t>(events.size());
  }
  stats->vertices += static_cast<int64_t>(tile.vertices.size());
  stats->seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return tile;
}

}  // namespace

PdsmTile AssembleTile(const PdsmHeader& header, std::span<const TileEvents> parts, int tile_samples,
                      AssemblyStats* stats, const TileWindows* windows) {
  static const TileEvents kNoTile;
  const TileEvents& shape = parts.empty() ? kNoTile : parts.front();
  assert(KeyingOf(header) == EventKeying::kCounts);  // sample-keyed: AssemblePlanTile
  return Assemble(header, {}, shape, tile_samples, stats, windows,
                  [&](size_t p, std::vector<std::span<const Event>>* lists) {
                    lists->clear();
                    for (const TileEvents& part : parts) lists->push_back(part.Pixel(p));
                  });
}

absl::StatusOr<PdsmTile> AssemblePlanTile(const BakePlan& plan, const TileParts& parts,
                                          EventSpill* spill, int tile_samples,
                                          AssemblyStats* stats) {
  if (!plan.header.surfaces_only && parts.spilled.empty() &&
      std::all_of(parts.in_memory.begin(), parts.in_memory.end(),
                  [](const TileEvents& e) { return e.events.empty(); })) {
    // No sample shadows any of its rays (most tiles of a large world): every function empty.
    PdsmTile tile;
    tile.x0 = parts.shape.x0;
    tile.y0 = parts.shape.y0;
    tile.width = parts.shape.width;
    tile.height = parts.shape.height;
    tile.samples = tile_samples;
    tile.offsets.assign(parts.shape.PixelCount() + 1, 0);
    return tile;
  }
  const std::optional<TileWindows> windows = ScanWindows(plan, plan.tile(parts.shape.tile_index));
  std::vector<SpilledRunReader> readers;
  readers.reserve(parts.spilled.size());
  for (const SpilledRun& run : parts.spilled) readers.emplace_back(spill, run);
  const int samples = tile_samples > 0 ? tile_samples : plan.header.samples;
  PdsmTile tile = Assemble(plan.header, plan.samples, parts.shape, samples, stats,
                           windows ? &*windows : nullptr,
                           [&](size_t p, std::vector<std::span<const Event>>* lists) {
                             lists->clear();
                             for (const TileEvents& part : parts.in_memory) {
                               lists->push_back(part.Pixel(p));
                             }
                             for (SpilledRunReader& reader : readers) {
                               lists->push_back(reader.Pixel(p));
                             }
                           });
  for (const SpilledRunReader& reader : readers) {
    if (!reader.status().ok()) return reader.status();
  }
  for (const SpilledRun& run : parts.spilled) spill->Release(run);
  tile.samples = tile_samples;  // 0 for a fixed-count bake: the header's count
  return tile;
}

}  // namespace pdsm
