#!/usr/bin/env bash
# pdsm-view frame times (docs/performance.md): every mode at 1280x720, headless (OSMesa;
# llvmpipe here, so the ratios between modes are what counts), on examples/plates (its own
# bake settings: 256^2, 64 samples) and on the dragon (../shared/scenes/dragon.json at 512^2,
# 64 samples, 512^2 shadow maps; skipped when ../shared is absent). Also the PDSM upload time
# and its GPU bytes, and a side-by-side image of all modes per scene in OUT_DIR.
# Usage: bench/view.sh [BUILD_DIR] [OUT_DIR] [FRAMES]   ($PDSM_SHARED_DIR: default ../shared)
set -euo pipefail
cd "$(dirname "$0")/.."
build=$(realpath "${1:-build}")
out=${2:-$(mktemp -d)}
frames=${3:-5}
mkdir -p "$out"
pdsm=$build/client/pdsm
view=$build/client/view/pdsm-view

run() {  # NAME SCENE BAKE_OVERRIDES...
  local name=$1 scene=$2
  shift 2
  echo "== $name: $scene $*"
  "$pdsm" bake "$scene" -o "$out/$name.exr" --no-preview "$@" >"$out/$name.bake.log" 2>&1
  "$pdsm" info "$out/$name.exr" | sed -n 's/^  functions/functions/p'
  "$view" "$scene" --pdsm "$out/$name.exr" --headless --size 1280x720 --bench "$frames"
  "$view" "$scene" --pdsm "$out/$name.exr" --headless --size 480x270 \
    --compare pdsm,cpu,hard,pcf,pcss,vsm,multi-sm --screenshot "$out/$name.compare.png" \
    >/dev/null
  echo
}

run plates examples/plates/scene.json
shared=${PDSM_SHARED_DIR:-../shared}
if [[ -f $shared/scenes/dragon.json ]]; then
  run dragon "$shared/scenes/dragon.json" --resolution 512x512 --samples 64 --sm-resolution 512
else
  echo "== dragon: skipped ($shared/scenes/dragon.json not found)"
fi
echo "images: $out/*.compare.png"
