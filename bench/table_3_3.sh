#!/usr/bin/env bash
# Thesis table 3.3 set-up: Stanford dragon (202,520 triangles, ~6 units) on a ground plane
# under a 3x3 square light (../shared/scenes/dragon.json), PDSM 256^2 / 512^2 / 1024^2 x
# 4 / 16 / 64 / 256 samples, 512^2 shadow maps. Prints a Markdown table: the thesis' seconds
# (where it gives them), ours, our shadow-map thread-seconds, peak RSS and file size.
# Usage: bench/table_3_3.sh [BUILD_DIR] [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
build=$(realpath "${1:-build}")
out=${2:-$(mktemp -d)}
mkdir -p "$out"
scene=../shared/scenes/dragon.json
if [[ ! -f $scene ]]; then
  echo "table_3_3: $scene not found (the shared test meshes are not here)" >&2
  exit 1
fi
declare -A thesis=([512x256]=147 [1024x256]=529)
echo "| PDSM | samples | thesis s | our s | our shadow-map thread-s | peak RSS MiB | file MiB |"
echo "|---|---|---|---|---|---|---|"
for res in 256 512 1024; do
  for samples in 4 16 64 256; do
    log="$out/dragon_${res}_${samples}.log"
    /usr/bin/time -f "peak_rss_kib %M" "$build"/client/pdsm bake "$scene" \
      -o "$out/dragon_${res}_${samples}.exr" --resolution "${res}x${res}" \
      --samples "$samples" --sm-resolution 512 --no-preview >"$log" 2>&1
    seconds=$(sed -n 's/^  time \([0-9.]*\)s; shadow maps \([0-9.]*\) thread-s.*/\1/p' "$log")
    sm_seconds=$(sed -n 's/^  time [0-9.]*s; shadow maps \([0-9.]*\) thread-s.*/\1/p' "$log")
    rss=$(awk '/peak_rss_kib/ {printf "%.0f", $2 / 1024}' "$log")
    bytes=$(stat -c %s "$out/dragon_${res}_${samples}.exr")
    mib=$(awk -v b="$bytes" 'BEGIN {printf "%.2f", b / 1048576}')
    echo "| ${res}² | $samples | ${thesis[${res}x${samples}]:-–} | $seconds | $sm_seconds | $rss | $mib |"
  done
done
