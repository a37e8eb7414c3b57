#!/usr/bin/env bash
# pdsm-view in a window (GLFW on GLX) under a virtual X server: renders 3 frames, writes a
# screenshot and exits 0. Exit 77 (ctest: skipped) when xvfb-run is not installed.
# Usage: window_xvfb_test.sh PDSM_CLI PDSM_VIEW SCENE.json
set -euo pipefail
pdsm=$1 view=$2 scene=$3
if ! command -v xvfb-run >/dev/null; then
  echo "SKIPPED: xvfb-run not found (apt-get install xvfb; deploy/install_deps.sh does)"
  exit 77
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$pdsm" bake "$scene" -o "$dir/p.exr" --resolution 48x48 --samples 8 --sm-resolution 256 \
  --no-preview >/dev/null 2>&1
xvfb-run -a -s "-screen 0 640x480x24" "$view" "$scene" --pdsm "$dir/p.exr" --size 320x240 \
  --frames 3 --screenshot "$dir/window.png" --sphere 1,1.2,2,0.5
# The same frame headless: the window must show what OSMesa renders.
"$view" "$scene" --pdsm "$dir/p.exr" --size 320x240 --headless --screenshot "$dir/headless.png" \
  --sphere 1,1.2,2,0.5 >/dev/null
python3 - "$dir/window.png" "$dir/headless.png" <<'PY'
import struct, sys, zlib

def read_png(path):  # 8-bit RGB or RGBA, non-interlaced (what pdsm-view writes)
    data = open(path, 'rb').read()
    assert data[:8] == b'\x89PNG\r\n\x1a\n', path + ': not a PNG'
    pos, idat = 8, b''
    while pos < len(data):
        length, kind = struct.unpack('>I4s', data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b'IHDR':
            width, height, depth, colour = struct.unpack('>IIBB', body[:10])
        if kind == b'IDAT':
            idat += body
        pos += 12 + length
    channels = {2: 3, 6: 4}[colour]
    raw, stride, rows, prev = zlib.decompress(idat), width * channels, [], bytearray(width * channels)
    for y in range(height):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b, c = prev[i], prev[i - channels] if i >= channels else 0
            p = a + b - c
            pred = [0, a, b, (a + b) // 2,
                    a if abs(p - a) <= abs(p - b) and abs(p - a) <= abs(p - c) else (b if abs(p - b) <= abs(p - c) else c)][f]
            line[i] = (line[i] + pred) & 255
        rows.append(bytes(line)); prev = line
    return width, height, channels, rows

w1, h1, c1, win = read_png(sys.argv[1])
w2, h2, c2, head = read_png(sys.argv[2])
assert (w1, h1) == (320, 240) and (w2, h2) == (320, 240), ((w1, h1), (w2, h2))
total = differing = 0
for y in range(h1):
    for x in range(w1):
        d = max(abs(win[y][x * c1 + k] - head[y][x * c2 + k]) for k in range(3))
        total += 1
        differing += d > 8
print('window vs headless: %d of %d pixels differ by more than 8/255' % (differing, total))
assert differing <= total // 100, 'the window shows another image than the headless render'
PY
