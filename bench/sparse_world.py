#!/usr/bin/python3
"""Writes a sparse large world as a pdsm scene: N flat roofs (5-20 units a side, 4-30 high)
scattered over a SIDE x SIDE ground under a 0.53-degree sun, baked at RES x RES with 4
samples (docs/performance.md, "A sparse world"). Most of its map is lit ground: it measures
what a large map costs where nothing happens, in the bake and in the readers.

Usage: bench/sparse_world.py OUT.json [ROOFS=400] [SIDE=4000] [RES=16384]
"""
import json
import random
import sys


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    roofs = int(sys.argv[2]) if len(sys.argv) > 2 else 400
    side = float(sys.argv[3]) if len(sys.argv) > 3 else 4000.0
    res = int(sys.argv[4]) if len(sys.argv) > 4 else 16384
    rng = random.Random(7)
    positions, indices = [], []
    for _ in range(roofs):
        x, z = rng.uniform(-side / 2, side / 2), rng.uniform(-side / 2, side / 2)
        w, d, h = rng.uniform(5, 20), rng.uniform(5, 20), rng.uniform(4, 30)
        base = len(positions) // 3
        positions += [x - w / 2, h, z - d / 2, x + w / 2, h, z - d / 2,
                      x + w / 2, h, z + d / 2, x - w / 2, h, z + d / 2]
        indices += [base, base + 1, base + 2, base, base + 2, base + 3]
    s = side / 2 + 50
    scene = {
        "name": "sparse-world",
        "meshes": [
            {"inline": {"positions": [-s, 0, -s, s, 0, -s, s, 0, s, -s, 0, s],
                        "indices": [0, 2, 1, 0, 3, 2]}, "role": "RECEIVER_ONLY"},
            {"inline": {"positions": positions, "indices": indices}, "role": "CASTER_ONLY"},
        ],
        "light": {"sun": {"direction": [0.3, -1, 0.2], "angularDiameterDeg": 0.53}},
        "bake": {"resolution": [res, res], "samples": 4, "shadowMapResolution": 4096,
                 "epsilon": 0.02},
    }
    with open(out, "w") as f:
        json.dump(scene, f)


if __name__ == "__main__":
    main()
