#include "core/pipeline/tile_assembly.h"

#include <chrono>
#include <optional>
#include <vector>

#include "core/bake/surface_function.h"
#include "core/events/consolidation.h"
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

PdsmTile AssembleTile(const PdsmHeader& header, std::span<const TileEvents> parts, int tile_samples,
                      AssemblyStats* stats, const TileWindows* windows) {
  const auto start = std::chrono::steady_clock::now();
  static const TileEvents kNoTile;
  const TileEvents& shape = parts.empty() ? kNoTile : parts.front();
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
  // Merged pixel by pixel: a tile's merged lists (tens of MiB at thousands of samples) are
  // never all in memory.
  std::vector<std::span<const Event>> pixel_parts(parts.size());
  for (size_t p = 0; p < shape.PixelCount(); ++p) {
    for (size_t k = 0; k < parts.size(); ++k) pixel_parts[k] = parts[k].Pixel(p);
    const std::vector<Event> merged = MergeEventLists(pixel_parts);
    const std::vector<Event> events = ConsolidateEvents(merged);
    std::vector<Vertex> compressed;
    if (windows != nullptr) {
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

PdsmTile AssemblePlanTile(const BakePlan& plan, std::span<const TileEvents> parts, int tile_samples,
                          AssemblyStats* stats) {
  std::optional<TileWindows> windows;
  if (plan.header.surfaces_only) {
    windows = ComputeReceiverWindows(plan, plan.tiles.at(parts.front().tile_index));
  }
  const TileWindows* tile_windows = windows ? &*windows : nullptr;
  return tile_samples > 0 ? AssembleTile(plan.header, parts, tile_samples, stats, tile_windows)
                          : AssembleTile(plan.header, parts, stats, tile_windows);
}

}  // namespace pdsm
