#!/usr/bin/env bash
# Admission alone (docs/performance.md, "A generated world"): a coordinator, one `pdsm submit`
# of the world, no worker; then SIGTERM. Prints the coordinator's CPU-s and peak RSS and the
# submit call's wall seconds.
#   bench/admission.sh BUILD_DIR WORLD_DIR TAG   (WORLD_DIR from bench/large_world.py)
set -euo pipefail
build=$1; world=$2; tag=$3
d=$(mktemp -d)
/usr/bin/time -f "%e %U %S %M" -o "$d/c.time" "$build"/server/pdsm-coordinator --listen 127.0.0.1:0 \
  --data-dir "$d/data" --ready-file "$d/ready" --log-level warn > "$d/c.log" 2>&1 &
c=$!
while [[ ! -s $d/ready ]]; do sleep 0.05; done
s=$(date +%s.%N)
"$build"/client/pdsm submit "$world/scene.json" --server "$(cat $d/ready)" > /dev/null 2>&1
e=$(date +%s.%N)
pkill -TERM -P "$c" || true
wait "$c" 2>/dev/null || true
awk -v t="$tag" -v a="$s" -v b="$e" '{printf "%s: coordinator %.1f CPU-s, %d MiB; submit %.1f s\n", t, $2 + $3, $4 / 1024, b - a}' "$d/c.time"
rm -rf "$d"
