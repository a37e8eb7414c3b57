# Shared by the world benchmarks (bench/large_world.sh, bench/huge_map.sh): bake_world bakes
# "$1/scene.json" locally and through the service (a coordinator and 2 one-thread workers on
# loopback) and prints time, CPU and peak RSS of every process and whether the files match.
# Source it after setting `build` (the build folder) and `pdsm` (its pdsm binary).
# "wall cpu rss_mib" of the time(1) output file $1.
times() { awk '{printf "%.1f s wall, %.1f CPU-s, %d MiB peak RSS", $1, $2 + $3, $4 / 1024}' "$1"; }

bake_world() {  # $1: the world's folder
  local world=$1
  /usr/bin/time -f "%e %U %S %M" -o "$world/local.time" \
    "$pdsm" bake "$world/scene.json" -o "$world/local.exr" --no-preview --threads 2 \
    >"$world/local.log" 2>&1
  echo "  local bake (2 threads): $(times "$world/local.time"), file $(stat -c %s "$world/local.exr") bytes"
  sed -n 's/^  \(time\|shadow maps\|events\).*/  &/p' "$world/local.log"
  # Where the time goes: the five slowest lights.
  grep '^  light' "$world/local.log" |
    awk '{for (i = 1; i <= NF; ++i) if ($i ~ /s;$/) {t = $i; sub("s;", "", t)}; print t, $0}' |
    sort -g -r | head -5 | cut -d' ' -f2- | sed 's/^/  slowest:/' || true  # none for one light

  # The service: one coordinator, 2 workers of 1 thread each, on loopback.
  local data=$world/data
  rm -rf "$data" "$world/ready"
  /usr/bin/time -f "%e %U %S %M" -o "$world/coordinator.time" \
    "$build"/server/pdsm-coordinator --listen 127.0.0.1:0 --data-dir "$data" \
    --ready-file "$world/ready" --log-level warn >"$world/coordinator.log" 2>&1 &
  local coordinator=$!
  while [[ ! -s $world/ready ]]; do sleep 0.05; done
  local address pids=()
  address=$(cat "$world/ready")
  for w in 0 1; do
    /usr/bin/time -f "%e %U %S %M" -o "$world/worker$w.time" \
      "$build"/worker/pdsm-worker --coordinator "$address" --threads 1 \
      --cache-dir "$world/cache$w" --log-level warn >"$world/worker$w.log" 2>&1 &
    pids+=($!)
  done
  local start end job
  start=$(date +%s.%N)
  job=$("$pdsm" submit "$world/scene.json" --server "$address" 2>/dev/null | tail -1)
  "$pdsm" watch "$job" --server "$address" >/dev/null 2>&1
  end=$(date +%s.%N)
  "$pdsm" fetch "$job" -o "$world/remote.exr" --server "$address" >/dev/null
  local same
  same=$(cmp -s "$world/remote.exr" "$world/local.exr" && echo "byte-identical" || echo "DIFFERENT")
  # SIGTERM to the processes under time(1) (not time itself, which would die without writing):
  # the workers hand back and exit 0, the coordinator shuts down; time(1) then writes.
  for p in "${pids[@]}" "$coordinator"; do pkill -TERM -P "$p" || true; done
  wait "${pids[@]}" "$coordinator" 2>/dev/null || true
  echo "  service, 2 workers: $(awk -v a="$start" -v b="$end" 'BEGIN {printf "%.1f", b - a}') s submit->SUCCEEDED, fetched file $same to the local bake"
  echo "    coordinator: $(times "$world/coordinator.time")"
  for w in 0 1; do echo "    worker $w:    $(times "$world/worker$w.time")"; done
}
