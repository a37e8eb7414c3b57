"""Writes cards.gltf, the bundled foliage-card example (docs/scene_format.md, "Alpha-tested casters").

A small tree of leaf cards over a 6 x 6 ground: each card is one quad whose base-colour texture
(generated here: a 128 x 128 PNG of a few leaves, transparent around them) is alpha-tested
(alphaMode MASK, alphaCutoff 0.5), so its shadow is the leaves' and light passes between them;
a trunk (an opaque box) under them. One light, the sun (a directional light, 1.5 degrees across
from its node's extras). The buffer and the texture are embedded as data URIs, so the file
stands alone.

    /usr/bin/python3 examples/foliage/make_cards.py   # rewrites examples/foliage/cards.gltf
"""

import base64
import math
import os
import struct
import sys
import zlib

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from gltf_common import box, look_down, write_gltf  # noqa: E402  (examples/gltf_common.py)


def png_gray_alpha(width, height, texels):
    """An 8-bit gray + alpha PNG of `texels` ((gray, alpha) per texel, rows from the top)."""
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))
    rows = b""
    for y in range(height):
        rows += b"\0" + bytes(v for x in range(width) for v in texels[y * width + x])
    header = struct.pack(">IIBBBBB", width, height, 8, 4, 0, 0, 0)  # 8-bit, gray + alpha
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows, 9))
            + chunk(b"IEND", b""))


def leaf_texture(size=128):
    """A few leaves: ellipses along rotated axes, opaque inside (alpha 255), clear outside."""
    leaves = [(0.30, 0.32, 0.20, 0.09, 35), (0.70, 0.30, 0.18, 0.08, -40),
              (0.50, 0.62, 0.24, 0.10, 80), (0.22, 0.75, 0.16, 0.07, -15),
              (0.78, 0.76, 0.17, 0.08, 20)]
    texels = []
    for y in range(size):
        for x in range(size):
            u, v = (x + 0.5) / size, (y + 0.5) / size
            inside = False
            for cu, cv, a, b, deg in leaves:
                c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
                du, dv = u - cu, v - cv
                pu, pv = c * du + s * dv, -s * du + c * dv
                inside = inside or (pu / a) ** 2 + (pv / b) ** 2 <= 1
            texels.append((60, 255) if inside else (60, 0))
    return png_gray_alpha(size, size, texels)


def cards():
    """Leaf cards around the top of the trunk: quads of 1.2 x 1.2, turned and tilted."""
    positions, uvs, indices = [], [], []
    for k in range(14):
        yaw = math.radians(k * 137.5)  # golden-angle spread
        tilt = math.radians(25 + 10 * (k % 3))
        height = 2.2 + 0.12 * (k % 5)
        reach = 0.35 + 0.05 * (k % 4)
        cx, cz = reach * math.cos(yaw), reach * math.sin(yaw)
        # Card axes: `a` horizontal, `b` up the card, tilted outwards by `tilt`.
        a = (-math.sin(yaw), 0.0, math.cos(yaw))
        b = (math.cos(yaw) * math.sin(tilt), math.cos(tilt), math.sin(yaw) * math.sin(tilt))
        base = len(positions)
        for su, sv in ((0, 0), (1, 0), (1, 1), (0, 1)):
            du, dv = (su - 0.5) * 1.2, (sv - 0.5) * 1.2
            positions.append((cx + du * a[0] + dv * b[0], height + du * a[1] + dv * b[1],
                              cz + du * a[2] + dv * b[2]))
            uvs.append((su, 1 - sv))  # glTF: v = 0 at the image's top
        indices += [base, base + 1, base + 2, base, base + 2, base + 3]
    return positions, uvs, indices


def main():
    blob = b""
    views, accessors = [], []

    def add(data, target, accessor):
        nonlocal blob
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data),
                      "target": target})
        blob += data
        accessor["bufferView"] = len(views) - 1
        accessors.append(accessor)
        return len(accessors) - 1

    def vec3s(points):
        data = b"".join(struct.pack("<3f", *p) for p in points)
        return add(data, 34962, {"componentType": 5126, "count": len(points), "type": "VEC3",
                                 "min": [min(p[k] for p in points) for k in range(3)],
                                 "max": [max(p[k] for p in points) for k in range(3)]})

    def scalars(values):
        return add(b"".join(struct.pack("<I", i) for i in values), 34963,
                   {"componentType": 5125, "count": len(values), "type": "SCALAR"})

    ground = ([(-3, 0, -3), (3, 0, -3), (3, 0, 3), (-3, 0, 3)], [0, 2, 1, 0, 3, 2])
    trunk = box(0, 0, 0, 0.25, 2.4, 0.25)
    leaf_positions, leaf_uvs, leaf_indices = cards()
    uv_data = b"".join(struct.pack("<2f", *uv) for uv in leaf_uvs)
    meshes = [
        {"name": "ground", "primitives": [{"attributes": {"POSITION": vec3s(ground[0])},
                                           "indices": scalars(ground[1]), "material": 0}]},
        {"name": "trunk", "primitives": [{"attributes": {"POSITION": vec3s(trunk[0])},
                                          "indices": scalars(trunk[1]), "material": 0}]},
        {"name": "leaves", "primitives": [{
            "attributes": {"POSITION": vec3s(leaf_positions),
                           "TEXCOORD_0": add(uv_data, 34962, {"componentType": 5126,
                                                              "count": len(leaf_uvs),
                                                              "type": "VEC2"})},
            "indices": scalars(leaf_indices), "material": 1}]},
    ]
    nodes = [
        {"name": "ground", "mesh": 0},
        {"name": "trunk", "mesh": 1},
        {"name": "leaves", "mesh": 2},
        {"name": "sun", "rotation": look_down((0.3, -1.0, 0.2)),
         "extensions": {"KHR_lights_punctual": {"light": 0}},
         "extras": {"angularDiameterDeg": 1.5, "samples": 32}},
    ]
    gltf = {
        "asset": {"version": "2.0", "generator": "pdsm examples/foliage/make_cards.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "sun", "type": "directional", "intensity": 3}]}},
        "scene": 0,
        "scenes": [{"name": "foliage", "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [
            {"name": "bark", "pbrMetallicRoughness": {"baseColorFactor": [0.4, 0.3, 0.2, 1]}},
            {"name": "leaf", "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": True,
             "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}},
        ],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071}],
        "images": [{"name": "leaves", "uri": "data:image/png;base64,"
                    + base64.b64encode(leaf_texture()).decode()}],
        "accessors": accessors,
        "bufferViews": views,
    }
    write_gltf(os.path.join(os.path.dirname(os.path.abspath(__file__)), "cards.gltf"), gltf, blob)


if __name__ == "__main__":
    main()
