#!/usr/bin/env bash
# The sweeps behind docs/accuracy.md: one knob at a time around a base configuration, and a
# grid for the Pareto front, on examples/plates, examples/sun_pillars and the Stanford dragon
# (SHARED/scenes/dragon.json). Each writes OUT/<name>/sweep.csv and sweep.png.
# Usage: bench/accuracy_sweeps.sh [BUILD_DIR] [OUT_DIR] [plates|sun|dragon ...]
# The shared models are looked up in $PDSM_SHARED (default ../shared).
set -euo pipefail
cd "$(dirname "$0")/.."
build=$(realpath "${1:-build}")
out=${2:-$(mktemp -d)}
shift $(( $# < 2 ? $# : 2 ))
scenes=${*:-plates sun dragon}
shared=${PDSM_SHARED:-../shared}
mkdir -p "$out"
pdsm="$build/client/pdsm"

sweep() {  # NAME SCENE ARGS...
  local name=$1 scene=$2
  shift 2
  echo "== $name: pdsm sweep $scene --out $out/$name $*" >&2
  local start=$SECONDS
  "$pdsm" sweep "$scene" --out "$out/$name" --threads 2 "$@" >"$out/$name.txt"
  echo "$name: $((SECONDS - start)) s" | tee -a "$out/runtimes.txt" >&2
}

for s in $scenes; do
  case $s in
    plates)
      p=examples/plates/scene.json
      sweep plates_samples $p --samples 1,4,16,64,256,1024 --resolution 256 --sm-resolution 1024 --epsilon 0.005
      sweep plates_resolution $p --samples 256 --resolution 64,128,256,512,1024 --sm-resolution 2048 --epsilon 0.005
      sweep plates_sm $p --samples 256 --resolution 256 --sm-resolution 128,256,512,1024,2048,4096 --epsilon 0.005
      sweep plates_epsilon $p --samples 256 --resolution 256 --sm-resolution 1024 --epsilon 0,0.002,0.005,0.01,0.02,0.05,0.1
      sweep plates_bias $p --samples 256 --resolution 256 --sm-resolution 1024 --epsilon 0.005 --depth-bias 0.00001,0.0001,0.001,0.01,0.05
      sweep plates_sampling $p --samples 4,16,64,256 --resolution 256 --sm-resolution 1024 --epsilon 0.005 --sampling STRATIFIED,UNIFORM
      sweep plates_grid $p --samples 16,64,256 --resolution 128,256,512 --sm-resolution 512,1024,2048 --epsilon 0.005
      ;;
    sun)
      p=examples/sun_pillars/scene.json
      sweep sun_samples $p --samples 1,4,16,64,256 --resolution 256 --sm-resolution 1024 --epsilon 0.005
      sweep sun_resolution $p --samples 64 --resolution 64,128,256,512,1024 --sm-resolution 2048 --epsilon 0.005
      sweep sun_sm $p --samples 64 --resolution 256 --sm-resolution 256,512,1024,2048,4096 --epsilon 0.005
      ;;
    dragon)
      p=$shared/scenes/dragon.json
      sweep dragon_samples $p --samples 4,16,64,256 --resolution 256 --sm-resolution 1024 --epsilon 0.005
      sweep dragon_resolution $p --samples 64 --resolution 128,256,512,1024 --sm-resolution 1024 --epsilon 0.005
      sweep dragon_sm $p --samples 64 --resolution 256 --sm-resolution 256,512,1024,2048 --epsilon 0.005
      ;;
  esac
done
echo "sweeps in $out" >&2
