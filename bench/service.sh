#!/usr/bin/env bash
# The distributed service on this machine (docs/performance.md):
#  1. coordinator merge + compression throughput: `pdsm bake` reports the events it merged
#     and the thread-seconds its tile assembly (AssembleTile, the coordinator's per-tile work)
#     took; events/s per core = merged events / those seconds.
#  2. end to end: one coordinator, 1 then 2 workers (1 thread each), submit -> SUCCEEDED,
#     against `pdsm bake --threads 1` and `--threads 2` of the same scene; the fetched file is
#     checked byte-identical to the local one.
# Usage: bench/service.sh [BUILD_DIR] [SCENE] [OUT_DIR]   (default scene: the dragon from
# ../shared/scenes/dragon.json at 512^2 x 64 samples, else examples/plates at 512^2 x 256)
set -euo pipefail
cd "$(dirname "$0")/.."
build=$(realpath "${1:-build}")
scene=${2:-}
out=${3:-$(mktemp -d)}
mkdir -p "$out"
overrides=()
if [[ -z $scene ]]; then
  if [[ -f ../shared/scenes/dragon.json ]]; then
    scene=../shared/scenes/dragon.json
    overrides=(--resolution 512x512 --samples 64 --sm-resolution 512)
  else
    scene=examples/plates/scene.json
    overrides=(--resolution 512x512 --samples 256 --sm-resolution 1024)
  fi
fi
pdsm=$build/client/pdsm

now() { date +%s.%N; }

echo "scene: $scene ${overrides[*]}"
for threads in 1 2; do
  start=$(now)
  "$pdsm" bake "$scene" -o "$out/local.exr" --no-preview --threads "$threads" \
    "${overrides[@]}" >"$out/local_$threads.log" 2>&1
  end=$(now)
  echo "local bake, $threads thread(s): $(awk -v a="$start" -v b="$end" 'BEGIN {printf "%.2f", b - a}') s"
done
merged=$(sed -n 's/^  events [0-9]* -> \([0-9]*\) merged.*/\1/p' "$out/local_1.log")
assembly=$(sed -n 's/.*merge+compress \([0-9.]*\) thread-s.*/\1/p' "$out/local_1.log")
echo "tile assembly: $merged merged events in $assembly thread-s:" \
  "$(awk -v e="$merged" -v s="$assembly" 'BEGIN {printf "%.3g", e / s}') events/s per core"

for workers in 1 2; do
  data=$out/data_$workers
  rm -rf "$data" "$out/ready"
  "$build"/server/pdsm-coordinator --listen 127.0.0.1:0 --data-dir "$data" \
    --ready-file "$out/ready" --log-level warn >"$out/coordinator_$workers.log" 2>&1 &
  coordinator=$!
  while [[ ! -s $out/ready ]]; do sleep 0.05; done
  address=$(cat "$out/ready")
  pids=()
  for ((w = 0; w < workers; ++w)); do
    "$build"/worker/pdsm-worker --coordinator "$address" --threads 1 \
      --cache-dir "$out/cache_$w" --log-level warn >"$out/worker_${workers}_$w.log" 2>&1 &
    pids+=($!)
  done
  start=$(now)
  job=$("$pdsm" submit "$scene" --server "$address" "${overrides[@]}" 2>/dev/null | tail -1)
  "$pdsm" watch "$job" --server "$address" >/dev/null 2>&1
  end=$(now)
  "$pdsm" fetch "$job" -o "$out/remote.exr" --server "$address" >/dev/null
  same=$(cmp -s "$out/remote.exr" "$out/local.exr" && echo "byte-identical" || echo "DIFFERENT")
  echo "service, $workers worker(s): $(awk -v a="$start" -v b="$end" 'BEGIN {printf "%.2f", b - a}') s submit->SUCCEEDED ($same to the local bake)"
  kill "${pids[@]}" "$coordinator"
  wait "${pids[@]}" "$coordinator" 2>/dev/null || true
done
