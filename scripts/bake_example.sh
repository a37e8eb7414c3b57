#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine: install dependencies, build, bake the bundled
# "plates" example locally, and say where the PDSM and its two pictures are.
set -euo pipefail
cd "$(dirname "$0")/.."
bash deploy/install_deps.sh
bash scripts/build.sh
mkdir -p out
./build/client/pdsm bake examples/plates/scene.json -o out/plates.exr
echo
echo "PDSM:       $(pwd)/out/plates.exr"
echo "look at:    $(pwd)/out/plates.png        (the scene with its baked soft shadows)"
echo "light view: $(pwd)/out/plates.light.png  (the map seen from the light)"
echo "try:        ./build/client/pdsm info out/plates.exr"
