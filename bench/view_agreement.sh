#!/usr/bin/env bash
# GPU vs CPU evaluation of one PDSM (docs/viewer.md "GPU layout and its precision"): renders
# `pdsm` and `cpu` modes of the same view with --save-attenuation and prints the largest
# |A_gpu - A_cpu| over the pixels on the PDSM, and how many exceed 1e-4 / 1e-6.
# Usage: bench/view_agreement.sh SCENE.json PDSM.exr [WxH] [BUILD_DIR] [extra pdsm-view flags]
set -euo pipefail
scene=$1 pdsm=$2 size=${3:-1280x720} build=${4:-build}
shift $(( $# < 4 ? $# : 4 ))
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for mode in pdsm cpu; do
  "$build/client/view/pdsm-view" "$scene" --pdsm "$pdsm" --headless --size "$size" --mode "$mode" \
    --screenshot "$out/$mode.png" --save-attenuation "$out/$mode.pfm" "$@" >/dev/null
done
python3 - "$out/pdsm.pfm" "$out/cpu.pfm" <<'PY'
import array, sys

def read_pfm(path):
    data = open(path, 'rb').read()
    header = data.split(b'\n', 3)
    width, height = map(int, header[1].split())
    values = array.array('f')
    values.frombytes(header[3][:width * height * 4])
    return values

gpu, cpu = read_pfm(sys.argv[1]), read_pfm(sys.argv[2])
pairs = [(g, c) for g, c in zip(gpu, cpu) if g >= 0 and c >= 0]
coverage_mismatch = sum(1 for g, c in zip(gpu, cpu) if (g < 0 or c < 0) and g != c)
diffs = [abs(g - c) for g, c in pairs]
print('pixels on the PDSM: %d, max |A_gpu - A_cpu|: %.3g, > 1e-4: %d, > 1e-6: %d, '
      'coverage mismatches: %d' % (len(pairs), max(diffs, default=0),
                                  sum(d > 1e-4 for d in diffs), sum(d > 1e-6 for d in diffs),
                                  coverage_mismatch))
PY
