#!/usr/bin/env bash
# A generated world of ~10^6 triangles, a sun and 54 local lights (bench/large_world.py), baked
# in one job locally and through the service with 2 workers (issue #12 item 7); then the same
# at twice the area, to see how the cost grows (docs/performance.md, "A generated world").
# Prints, per run: wall seconds, CPU seconds (user + system) and peak RSS of every process, the
# file's size, its largest parts, and whether the service's file is byte-identical to the local.
#   bench/large_world.sh [BUILD_DIR] [OUT_DIR] [SIDE=1000]
set -euo pipefail
cd "$(dirname "$0")/.."
build=$(realpath "${1:-build}")
out=$(realpath -m "${2:-$(mktemp -d)}")
side=${3:-1000}
mkdir -p "$out"
pdsm=$build/client/pdsm

# shellcheck source=bench/lib/bake_world.sh
source bench/lib/bake_world.sh

for scale in 1 2; do
  # Twice the area: the side times sqrt(2), the sun's pixels per side too (same pixel size).
  world_side=$(awk -v s="$side" -v k="$scale" 'BEGIN {printf "%d", s * sqrt(k)}')
  sun_res=$(awk -v k="$scale" 'BEGIN {printf "%d", 4096 * sqrt(k)}')
  lights=$((54 * scale))
  world=$out/world_$scale
  /usr/bin/python3 bench/large_world.py "$world" "$world_side" "$lights" "$sun_res" | sed 's/^/world: /'
  bake_world "$world"
done
