"""What the example generators (world/make_world.py, foliage/make_cards.py) share: a box, the
rotation that points a glTF light, and writing a glTF file with its buffer embedded."""

import base64
import json
import math


def box(cx, cy, cz, sx, sy, sz):
    """A closed box standing on y = cy, 8 corners and 12 outward triangles."""
    xs, ys, zs = (cx - sx / 2, cx + sx / 2), (cy, cy + sy), (cz - sz / 2, cz + sz / 2)
    corners = [(x, y, z) for y in ys for z in zs for x in xs]
    # corner index = 4 * (y) + 2 * (z) + (x)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = []
    for a, b, c, d in quads:
        tris += [a, b, c, a, c, d]
    return corners, tris


def look_down(direction):
    """A rotation quaternion (x, y, z, w) taking the light's -Z onto `direction`."""
    d = [c / math.sqrt(sum(c * c for c in direction)) for c in direction]
    axis = (d[1], -d[0], 0.0)  # (0, 0, -1) x d
    s = math.sqrt(sum(c * c for c in axis))
    angle = math.atan2(s, -d[2])
    if s < 1e-12:
        return [0.0, 0.0, 0.0, 1.0]
    k = math.sin(angle / 2) / s
    return [axis[0] * k, axis[1] * k, axis[2] * k, math.cos(angle / 2)]


def write_gltf(path, gltf, blob):
    """Writes `gltf` with `blob` as its one buffer, embedded as base64: the file stands alone."""
    gltf["buffers"] = [{"byteLength": len(blob),
                        "uri": "data:application/octet-stream;base64,"
                               + base64.b64encode(blob).decode()}]
    with open(path, "w") as f:
        json.dump(gltf, f, indent=1)
        f.write("\n")
