#!/usr/bin/env bash
# A map of any size (issue #12 item 5): the sparse world of bench/sparse_world.py (400 roofs
# over 4 km x 4 km under a 0.53 degree sun, 4 samples, a 4096-texel shadow-map lattice) at
# RES x RES, baked locally and through the service with 2 workers (bench/lib/bake_world.sh),
# then locally again with its previews, then 10^6 random ground points queried from the file,
# then pdsm-view headless on it (the whole world and a street, default and small budgets).
# Prints wall seconds, CPU seconds and peak RSS of every process (docs/performance.md, "Maps of
# any size").
#   bench/huge_map.sh [BUILD_DIR] [OUT_DIR] [RES=32768]
set -euo pipefail
cd "$(dirname "$0")/.."
build=$(realpath "${1:-build}")
out=$(realpath -m "${2:-$(mktemp -d)}")
res=${3:-32768}
pdsm=$build/client/pdsm

# shellcheck source=bench/lib/bake_world.sh
source bench/lib/bake_world.sh

world=$out/world
mkdir -p "$world"
/usr/bin/python3 bench/sparse_world.py "$world/scene.json" 400 4000 "$res"
echo "sparse world, ${res}x${res}:"
bake_world "$world"

/usr/bin/time -f "%e %U %S %M" -o "$world/preview.time" \
  "$pdsm" bake "$world/scene.json" -o "$world/preview.exr" --threads 2 >"$world/preview.log" 2>&1
echo "  local bake with its previews: $(times "$world/preview.time"), light view $(file -b "$world/preview.light.png" | cut -d, -f2)"

/usr/bin/python3 - "$world/points.csv" <<'PY'
import random, sys
rng = random.Random(12)
with open(sys.argv[1], "w") as f:
    for _ in range(10**6):
        f.write(f"{rng.uniform(-2000, 2000):.3f},0,{rng.uniform(-2000, 2000):.3f}\n")
PY
/usr/bin/time -f "%e %U %S %M" -o "$world/query.time" \
  "$pdsm" query "$world/local.exr" --points "$world/points.csv" >"$world/query.csv"
echo "  pdsm query, 10^6 ground points: $(times "$world/query.time")"

# pdsm-view, headless: the whole world (the default camera) and a street, with the default
# budgets and with small ones; -v prints the tile pool's line (tiles read, resident, over).
view=$build/client/view/pdsm-view
for camera in default 0,60,90,0,0,0,45; do
  for budgets in "" "--gpu-budget-mib 16 --cache-mib 16" "--gpu-budget-mib 512"; do
    args=()
    [[ $camera != default ]] && args=(--camera "$camera")
    # shellcheck disable=SC2086  # $budgets: two flags or none
    /usr/bin/time -f "%e %U %S %M" -o "$world/view.time" \
      "$view" "$world/scene.json" --pdsm "$world/local.exr" --headless --size 1280x720 \
      --screenshot "$world/view.png" -v "${args[@]}" $budgets >"$world/view.log" 2>&1
    echo "  pdsm-view, camera $camera ${budgets:-(default budgets)}: $(times "$world/view.time")"
    grep -o 'PDSM tiles on the GPU.*' "$world/view.log" | sed 's/^/    /'
  done
done
