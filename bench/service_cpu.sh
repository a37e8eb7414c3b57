#!/usr/bin/env bash
# CPU seconds of a service bake against the local bake (issue #11 item 7): one coordinator
# and 2 workers of 1 thread each on this machine, against `pdsm bake --threads 2`, for the
# same scene. The service is measured after its first job (the mesh uploaded and cached by
# every worker, as on a farm re-baking a world): the CPU of the coordinator and the workers
# (utime + stime from /proc, read before and after) plus the client's submit and watch.
# Rounds alternate local and service; medians are printed. Every fetched file must be
# byte-identical to the local bake.
# Usage: bench/service_cpu.sh [BUILD_DIR] [SCENE] [ROUNDS] [OVERRIDES...]
#   default: the dragon (../shared/scenes/dragon.json) at its own settings, 3 rounds
#   $COORDINATOR_FLAGS: more pdsm-coordinator flags (e.g. "--verify-fraction 1")
set -euo pipefail
cd "$(dirname "$0")/.."
build=$(realpath "${1:-build}")
scene=${2:-../shared/scenes/dragon.json}
rounds=${3:-3}
overrides=("${@:4}")
pdsm=$build/client/pdsm
out=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$out"' EXIT
tick=$(getconf CLK_TCK)

# CPU seconds (user + system) a process has used so far.
cpu_of() { awk -v t="$tick" '{print ($14 + $15) / t}' "/proc/$1/stat"; }
# CPU seconds of a command's run (user + system of it and its children).
timed() { /usr/bin/time -f "%U %S" -o "$out/time" "$@" >/dev/null 2>&1; awk '{print $1 + $2}' "$out/time"; }
median() { sort -g | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }

"$build"/server/pdsm-coordinator --listen 127.0.0.1:0 --data-dir "$out/data" \
  --ready-file "$out/ready" --log-level warn ${COORDINATOR_FLAGS:-} >"$out/coordinator.log" 2>&1 &
coordinator=$!
while [[ ! -s $out/ready ]]; do sleep 0.05; done
address=$(cat "$out/ready")
workers=()
for w in 0 1; do
  "$build"/worker/pdsm-worker --coordinator "$address" --threads 1 --cache-dir "$out/cache_$w" \
    --log-level warn >"$out/worker_$w.log" 2>&1 &
  workers+=($!)
done

bake_job() {  # submits the scene and waits for its end; prints the job id
  local job
  job=$("$pdsm" submit "$scene" --server "$address" "${overrides[@]}" 2>/dev/null | tail -1)
  "$pdsm" watch "$job" --server "$address" >/dev/null 2>&1
  echo "$job"
}
echo "scene: $scene ${overrides[*]}; coordinator flags: ${COORDINATOR_FLAGS:-none};" \
  "warm-up job (uploads the mesh)"
bake_job >/dev/null

: >"$out/local" && : >"$out/service"
for ((r = 1; r <= rounds; ++r)); do
  local_cpu=$(timed "$pdsm" bake "$scene" -o "$out/local.exr" --no-preview --threads 2 "${overrides[@]}")
  before=0 && starts=()
  for p in "$coordinator" "${workers[@]}"; do
    starts+=("$(cpu_of "$p")")
    before=$(awk -v a="$before" -v b="$(cpu_of "$p")" 'BEGIN {print a + b}')
  done
  client_start=$(awk '{print $14 + $15 + $16 + $17}' /proc/$$/stat)
  wall_start=$(date +%s.%N)
  job=$(bake_job)
  wall=$(awk -v a="$wall_start" -v b="$(date +%s.%N)" 'BEGIN {printf "%.1f", b - a}')
  client_cpu=$(awk -v s="$client_start" -v t="$tick" '{print ($14 + $15 + $16 + $17 - s) / t}' /proc/$$/stat)
  after=0
  for p in "$coordinator" "${workers[@]}"; do after=$(awk -v a="$after" -v b="$(cpu_of "$p")" 'BEGIN {print a + b}'); done
  service_cpu=$(awk -v a="$before" -v b="$after" -v c="$client_cpu" 'BEGIN {print b - a + c}')
  parts="client $client_cpu"
  for i in 0 1 2; do
    p=$([[ $i == 0 ]] && echo "$coordinator" || echo "${workers[$((i - 1))]}")
    parts+=", $([[ $i == 0 ]] && echo coordinator || echo "worker $((i - 1))") $(awk -v a="${starts[$i]}" -v b="$(cpu_of "$p")" 'BEGIN {printf "%.2f", b - a}')"
  done
  "$pdsm" fetch "$job" -o "$out/remote.exr" --server "$address" >/dev/null
  same=$(cmp -s "$out/remote.exr" "$out/local.exr" && echo "byte-identical" || echo "DIFFERENT")
  echo "round $r: local $local_cpu CPU-s, service $service_cpu CPU-s ($parts; submit->end ${wall} s; $same)"
  echo "$local_cpu" >>"$out/local" && echo "$service_cpu" >>"$out/service"
done
l=$(median <"$out/local") && s=$(median <"$out/service")
echo "median: local $l CPU-s, service (coordinator + 2 workers + client) $s CPU-s:" \
  "service / local = $(awk -v a="$l" -v b="$s" 'BEGIN {printf "%.2f", b / a}')"
"$pdsm" stats --server "$address" | grep verification || true
