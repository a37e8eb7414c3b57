#!/usr/bin/python3
"""Writes a world of many small lights as a pdsm scene: a SIDE x SIDE grid of cells 10 units
apart on one shared ground, each with a 1 x 1 plate 1.5 up and a spot light (radius 0.2, 30
degree cone) 3 up, so that each light reaches 4 triangles (its plate and the ground). Every
light bakes RES x RES with 4 samples. It measures what a light costs besides its shadows
(docs/performance.md, "Ten thousand lights"); the extremes suite bakes the same world
(ExtremesLight.TenThousandLightsOfFourTrianglesEach).

Usage: bench/many_lights.py OUT.json [SIDE=100] [RES=16]
"""
import json
import sys


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    side = int(sys.argv[2]) if len(sys.argv) > 2 else 100
    res = int(sys.argv[3]) if len(sys.argv) > 3 else 16
    pitch = 10.0
    far = side * pitch - 5
    plates, indices, lights = [], [], []
    for i in range(side):
        for j in range(side):
            x, z = i * pitch, j * pitch
            base = len(plates) // 3
            plates += [x - 0.5, 1.5, z - 0.5, x + 0.5, 1.5, z - 0.5,
                       x + 0.5, 1.5, z + 0.5, x - 0.5, 1.5, z + 0.5]
            indices += [base, base + 1, base + 2, base, base + 2, base + 3]
            lights.append({"name": f"l{i}_{j}",
                           "spot": {"center": [x + 0.3, 3, z], "normal": [0, -1, 0],
                                    "radius": 0.2, "coneHalfAngleDeg": 30}})
    scene = {
        "name": f"many_lights_{side * side}",
        "meshes": [
            {"inline": {"positions": [-5, 0, -5, far, 0, -5, far, 0, far, -5, 0, far],
                        "indices": [0, 1, 2, 0, 2, 3]},
             "role": "RECEIVER_ONLY"},
            {"inline": {"positions": plates, "indices": indices}},
        ],
        "lights": lights,
        "bake": {"resolution": [res, res], "samples": 4, "shadowMapResolution": 4 * res,
                 "tileSize": res, "epsilon": 0.01},
    }
    with open(out, "w") as f:
        json.dump(scene, f)


if __name__ == "__main__":
    main()
