"""Writes world.gltf, the bundled glTF world (docs/scene_format.md, "A world file as the scene").

A 16 x 16 ground (with a lightmap UV set, TEXCOORD_1, for `pdsm shadowmask`), a unit box resting on it, a pillar and a tilted bar; a sun (a directional
light, 2 degrees across from the node's extras), a spot with a radius from its node's extras
and its own sample count, and a point light (a bulb: baked as a sphere, its radius and samples
from its node's extras). One buffer, embedded as base64, so the file stands alone.

    /usr/bin/python3 examples/world/make_world.py   # rewrites examples/world/world.gltf
"""

import math
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from gltf_common import box, look_down, write_gltf  # noqa: E402  (examples/gltf_common.py)


def main():
    meshes = {
        "ground": ([(-8, 0, -8), (8, 0, -8), (8, 0, 8), (-8, 0, 8)], [0, 2, 1, 0, 3, 2]),
        "box": box(0, 0, 0, 1, 1, 1),
        "pillar": box(0, 0, 0, 0.4, 3, 0.4),
        "bar": box(0, 0, 0, 3, 0.2, 0.2),
    }
    blob = b""
    views, accessors, gltf_meshes = [], [], []
    for name, (positions, indices) in meshes.items():
        pos = b"".join(struct.pack("<3f", *p) for p in positions)
        idx = b"".join(struct.pack("<I", i) for i in indices)
        for data, target in ((pos, 34962), (idx, 34963)):
            views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data),
                          "target": target})
            blob += data
        lo = [min(p[k] for p in positions) for k in range(3)]
        hi = [max(p[k] for p in positions) for k in range(3)]
        accessors.append({"bufferView": len(views) - 2, "componentType": 5126,
                          "count": len(positions), "type": "VEC3", "min": lo, "max": hi})
        accessors.append({"bufferView": len(views) - 1, "componentType": 5125,
                          "count": len(indices), "type": "SCALAR"})
        attributes = {"POSITION": len(accessors) - 2}
        if name == "ground":
            # A material UV set that tiles (TEXCOORD_0, a 1-unit texture) and the lightmap's
            # own unwrap (TEXCOORD_1, the quad over [0, 1]^2, v = 0 at z = -8): what
            # `pdsm shadowmask` lays the ground's texture out in.
            for k, uv_of in enumerate((lambda x, z: (x, z), lambda x, z: ((x + 8) / 16, (z + 8) / 16))):
                data = b"".join(struct.pack("<2f", *uv_of(p[0], p[2])) for p in positions)
                views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data),
                              "target": 34962})
                blob += data
                accessors.append({"bufferView": len(views) - 1, "componentType": 5126,
                                  "count": len(positions), "type": "VEC2"})
                attributes["TEXCOORD_%d" % k] = len(accessors) - 1
        gltf_meshes.append({"name": name, "primitives": [
            {"attributes": attributes, "indices": len(accessors) - 1 - (2 if name == "ground" else 0)}]})

    nodes = [
        {"name": "ground", "mesh": 0},
        {"name": "box", "mesh": 1, "translation": [-2, 0, 1]},
        {"name": "pillar", "mesh": 2, "translation": [2, 0, -1]},
        {"name": "bar", "mesh": 3, "translation": [0, 2.2, -2.5],
         "rotation": [0.0, 0.0, math.sin(math.radians(10)), math.cos(math.radians(10))]},
        {"name": "sun", "rotation": look_down([0.35, -1.0, 0.25]),
         "extensions": {"KHR_lights_punctual": {"light": 0}},
         "extras": {"angularDiameterDeg": 2.0}},
        {"name": "spot", "translation": [-4, 6, 4], "rotation": look_down([0.45, -1.0, -0.4]),
         "extensions": {"KHR_lights_punctual": {"light": 1}},
         "extras": {"radius": 0.3, "samples": 32}},
        {"name": "bulb", "translation": [0, 3, 3],
         "extensions": {"KHR_lights_punctual": {"light": 2}},
         "extras": {"radius": 0.2, "samples": 32}},
    ]
    gltf = {
        "asset": {"version": "2.0", "generator": "pdsm examples/world/make_world.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "sun", "type": "directional", "intensity": 3},
            {"name": "spot", "type": "spot", "intensity": 200,
             "spot": {"innerConeAngle": 0.3, "outerConeAngle": math.radians(40)}},
            {"name": "bulb", "type": "point", "intensity": 50},
        ]}},
        "scene": 0,
        "scenes": [{"name": "world", "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": gltf_meshes,
        "accessors": accessors,
        "bufferViews": views,
    }
    write_gltf(os.path.join(os.path.dirname(os.path.abspath(__file__)), "world.gltf"), gltf, blob)


if __name__ == "__main__":
    main()
