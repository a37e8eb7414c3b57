#!/usr/bin/env bash
# The cost of baking a scene's lights in one job (one multipart file) against baking each light
# alone (one single-part file each): CPU seconds (user + system) and peak RSS of `pdsm bake`,
# the two alternated REPEAT times, medians (docs/performance.md, "Several lights").
#   bench/several_lights.sh [PDSM_CLI] [SCENE] [RESOLUTION] [REPEAT]
# SCENE must use "lights"; every entry is cut out into a one-light scene of its own.
set -euo pipefail
cli=${1:-build/client/pdsm}
scene=${2:-examples/courtyard/scene.json}
resolution=${3:-1024x1024}
repeat=${4:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# One-light scenes: the same meshes and bake, `light` = lights[i] (its name and own bake kept).
count=$(/usr/bin/python3 - "$scene" "$work" <<'PY'
import json, os, sys
scene = json.load(open(sys.argv[1]))
folder = os.path.dirname(os.path.abspath(sys.argv[1]))
for i, light in enumerate(scene["lights"]):
    one = {k: v for k, v in scene.items() if k != "lights"}
    one["light"] = light
    for mesh in one.get("meshes", []):
        if "path" in mesh and not os.path.isabs(mesh["path"]):
            mesh["path"] = os.path.join(folder, mesh["path"])
    json.dump(one, open(os.path.join(sys.argv[2], f"light{i}.json"), "w"))
print(len(scene["lights"]))
PY
)

median() { sort -g | awk '{v[NR]=$1} END {print (NR%2 ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2)}'; }
measure() {  # prints "cpu_seconds peak_rss_kib" of one command
  /usr/bin/time -f "%U %S %M" -o "$work/time" "$@" >/dev/null 2>&1
  awk '{printf "%.3f %d\n", $1 + $2, $3}' "$work/time"
}
: >"$work/together"
: >"$work/alone"
for r in $(seq "$repeat"); do
  measure "$cli" bake "$scene" -o "$work/all.exr" --no-preview --resolution "$resolution" \
    >>"$work/together"
  cpu=0; rss=0
  for i in $(seq 0 $((count - 1))); do
    read -r c m < <(measure "$cli" bake "$work/light$i.json" -o "$work/one$i.exr" --no-preview \
      --resolution "$resolution")
    cpu=$(awk -v a="$cpu" -v b="$c" 'BEGIN {print a + b}')
    rss=$((m > rss ? m : rss))
  done
  echo "$cpu $rss" >>"$work/alone"
done
together_cpu=$(cut -d' ' -f1 "$work/together" | median)
alone_cpu=$(cut -d' ' -f1 "$work/alone" | median)
together_rss=$(cut -d' ' -f2 "$work/together" | median)
alone_rss=$(cut -d' ' -f2 "$work/alone" | median)
bytes_together=$(stat -c %s "$work/all.exr")
bytes_alone=0
for i in $(seq 0 $((count - 1))); do bytes_alone=$((bytes_alone + $(stat -c %s "$work/one$i.exr"))); done
echo "scene $scene, $count lights, --resolution $resolution, medians of $repeat"
printf "one job, %d lights:   CPU %.2f s, peak RSS %d MiB, file %d bytes\n" "$count" \
  "$together_cpu" $((together_rss / 1024)) "$bytes_together"
printf "each light alone:     CPU %.2f s (sum), peak RSS %d MiB (max), files %d bytes (sum)\n" \
  "$alone_cpu" $((alone_rss / 1024)) "$bytes_alone"
awk -v a="$together_cpu" -v b="$alone_cpu" 'BEGIN {printf "CPU ratio (one job / alone): %.3f\n", a / b}'
