"""A pdsm scene JSON in plain Python (no Blender, no numpy), for the Cycles anchor.

Shared by bench/cycles/pdsm_scene_to_cycles.py (inside Blender) and bench/cycles_compare.py
(/usr/bin/python3). It reads what docs/scene_format.md describes as far as the anchor needs:
meshes inline or from PLY (ASCII or binary little-endian) and OBJ files, relative to the scene
file, placed by their row-major 4x4 `transform` in double; `role`; the one light (`light`, or
`lights[]` with a name to pick). It also lays the receiver points: a grid of texel centres on
the ground, the first RECEIVER_ONLY mesh, which must be planar.
"""
import json
import math
import os
import struct

IDENTITY = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]


def sub(a, b): return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
def dot(a, b): return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
def cross(a, b): return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                         a[0] * b[1] - a[1] * b[0]]
def scale(a, s): return [a[0] * s, a[1] * s, a[2] * s]


def normalize(a):
    n = math.sqrt(dot(a, a))
    return [a[0] / n, a[1] / n, a[2] / n]


def read_ply(path):
    """Vertices (x, y, z) and triangles (polygons fanned) of an ASCII or binary LE PLY file."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header") + len(b"end_header")
    end = data.index(b"\n", end) + 1
    header = data[:end].decode("ascii").split("\n")
    fmt = next(l.split()[1] for l in header if l.startswith("format"))
    elements, current = [], None
    for line in header:
        words = line.split()
        if words[:1] == ["element"]:
            current = (words[1], int(words[2]), [])
            elements.append(current)
        elif words[:1] == ["property"]:
            current[2].append(words[1:])
    if fmt == "ascii":
        return _ply_ascii(data[end:].decode("ascii").split(), elements)
    if fmt != "binary_little_endian":
        raise ValueError(f"{path}: PLY format {fmt} not supported")
    return _ply_binary(data, end, elements)


_PLY_TYPES = {"char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h",
              "ushort": "H", "uint16": "H", "int": "i", "int32": "i", "uint": "I",
              "uint32": "I", "float": "f", "float32": "f", "double": "d", "float64": "d"}


def _ply_binary(data, pos, elements):
    verts, tris = [], []
    for name, count, props in elements:
        if all(p[0] != "list" for p in props):  # fixed-size rows: unpack them in one go
            row = "<" + "".join(_PLY_TYPES[p[0]] for p in props)
            rows = struct.iter_unpack(row, data[pos:pos + count * struct.calcsize(row)])
            pos += count * struct.calcsize(row)
            if name == "vertex":
                ix = [next(i for i, p in enumerate(props) if p[1] == c) for c in "xyz"]
                verts = [(r[ix[0]], r[ix[1]], r[ix[2]]) for r in rows]
            continue
        for _ in range(count):  # rows with lists (faces): one at a time
            polygon = None
            for p in props:
                if p[0] == "list":
                    n = struct.unpack_from("<" + _PLY_TYPES[p[1]], data, pos)[0]
                    pos += struct.calcsize(_PLY_TYPES[p[1]])
                    items = struct.unpack_from(f"<{n}{_PLY_TYPES[p[2]]}", data, pos)
                    pos += n * struct.calcsize(_PLY_TYPES[p[2]])
                    if name == "face" and p[3] in ("vertex_indices", "vertex_index"):
                        polygon = items
                else:
                    pos += struct.calcsize(_PLY_TYPES[p[0]])
            if polygon:
                tris += [(polygon[0], polygon[i], polygon[i + 1]) for i in range(1, len(polygon) - 1)]
    return verts, tris


def _ply_ascii(words, elements):
    verts, tris, pos = [], [], 0
    for name, count, props in elements:
        for _ in range(count):
            values = {}
            for p in props:
                if p[0] == "list":
                    n = int(words[pos])
                    values[p[3]] = [int(w) for w in words[pos + 1:pos + 1 + n]]
                    pos += 1 + n
                else:
                    values[p[1]] = float(words[pos])
                    pos += 1
            if name == "vertex":
                verts.append((values["x"], values["y"], values["z"]))
            elif name == "face":
                poly = values.get("vertex_indices") or values.get("vertex_index")
                tris += [(poly[0], poly[i], poly[i + 1]) for i in range(1, len(poly) - 1)]
    return verts, tris


def read_obj(path):
    """Vertices and triangles (polygons fanned) of an OBJ file; other statements ignored."""
    verts, tris = [], []
    with open(path) as f:
        for line in f:
            words = line.split()
            if words[:1] == ["v"]:
                verts.append(tuple(float(w) for w in words[1:4]))
            elif words[:1] == ["f"]:
                idx = [int(w.split("/")[0]) for w in words[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                tris += [(idx[0], idx[i], idx[i + 1]) for i in range(1, len(idx) - 1)]
    return verts, tris


def load_mesh(mesh, folder):
    """World-space vertices (transform applied in double) and triangles of one scene mesh."""
    if "inline" in mesh:
        p = mesh["inline"]["positions"]
        verts = [tuple(p[i:i + 3]) for i in range(0, len(p), 3)]
        ix = mesh["inline"]["indices"]
        tris = [tuple(ix[i:i + 3]) for i in range(0, len(ix), 3)]
    else:
        path = os.path.join(folder, mesh["path"])
        ext = os.path.splitext(path)[1].lower()
        if ext not in (".ply", ".obj"):
            raise ValueError(f"{path}: only PLY and OBJ meshes are read here")
        verts, tris = (read_ply if ext == ".ply" else read_obj)(path)
    m = mesh.get("transform") or IDENTITY
    world = [(m[0] * x + m[1] * y + m[2] * z + m[3], m[4] * x + m[5] * y + m[6] * z + m[7],
              m[8] * x + m[9] * y + m[10] * z + m[11]) for x, y, z in verts]
    return world, tris


class Scene:
    """The meshes (world space, with roles) and the one light of a pdsm scene file."""

    def __init__(self, path, light_name=None):
        self.path = path
        doc = json.load(open(path))
        folder = os.path.dirname(os.path.abspath(path))
        self.meshes = []
        for mesh in doc.get("meshes", []):
            verts, tris = load_mesh(mesh, folder)
            self.meshes.append((mesh.get("role", "CASTER_AND_RECEIVER"), verts, tris))
        lights = [doc["light"]] if "light" in doc else doc.get("lights", [])
        if light_name is not None:
            lights = [l for l in lights if l.get("name") == light_name]
        if len(lights) != 1:
            raise ValueError(f"{path}: needs one light (several: pick one by name)")
        self.light = lights[0]
        self.kind = next(k for k in ("rect", "disk", "spot", "sun", "sphere") if k in self.light)
        self.ground_normal, self.ground_axes = self._ground()

    def casters(self):
        return [(v, t) for role, v, t in self.meshes if role != "RECEIVER_ONLY"]

    def ground(self):
        return next(m for m in self.meshes if m[0] == "RECEIVER_ONLY")

    def toward_light(self, point):
        """Unit vector from a point toward the light's centre (the sun: against its direction)."""
        if self.kind == "sun":
            return normalize(scale(self.light["sun"]["direction"], -1))
        return normalize(sub(self.light[self.kind]["center"], point))

    def _ground(self):
        """Unit normal (facing the light) and two in-plane unit axes (a, b = n x a) of the ground."""
        _, verts, tris = self.ground()
        v0, v1, v2 = (verts[i] for i in tris[0])
        n = normalize(cross(sub(v1, v0), sub(v2, v0)))
        if dot(n, self.toward_light(v0)) < 0:
            n = scale(n, -1)
        extent = max(max(abs(c) for c in sub(v, v0)) for v in verts)
        if any(abs(dot(sub(v, v0), n)) > 1e-9 * extent for v in verts):
            raise ValueError(f"{self.path}: the ground (first RECEIVER_ONLY mesh) is not planar")
        # In-plane axes along the world axis most parallel to the plane: a world-aligned grid.
        e = min(([1, 0, 0], [0, 1, 0], [0, 0, 1]), key=lambda e: abs(dot(e, n)))
        a = normalize(sub(e, scale(n, dot(e, n))))
        return n, (a, cross(n, a))

    def ground_grid(self, n, crop=None):
        """n x n texel centres over the ground's extent in its plane, row after row; with crop,
        over a square of that side centred on the casters' bounding box projected on it."""
        _, verts, _ = self.ground()
        (a, b), origin = self.ground_axes, verts[0]
        us = [dot(sub(v, origin), a) for v in verts]
        vs = [dot(sub(v, origin), b) for v in verts]
        lo, hi = [min(us), min(vs)], [max(us), max(vs)]
        if crop:
            cs = [p for v, _ in self.casters() for p in v]
            centre = []
            for axis in (a, b):
                along = [dot(sub(p, origin), axis) for p in cs]
                centre.append((min(along) + max(along)) / 2)
            lo = [max(lo[i], centre[i] - crop / 2) for i in range(2)]
            hi = [min(hi[i], centre[i] + crop / 2) for i in range(2)]
        points = []
        for j in range(n):
            for i in range(n):
                u = lo[0] + (i + 0.5) * (hi[0] - lo[0]) / n
                v = lo[1] + (j + 0.5) * (hi[1] - lo[1]) / n
                points.append(tuple(origin[k] + u * a[k] + v * b[k] for k in range(3)))
        return points


def read_points(path):
    """x,y,z per line (a header row allowed), as pdsm query and pdsm reference read them."""
    points = []
    for line in open(path):
        words = line.strip().split(",")
        if len(words) >= 3:
            try:
                points.append(tuple(float(w) for w in words[:3]))
            except ValueError:
                pass  # the header row
    return points


def write_points(path, points, values=None):
    """x,y,z lines, or x,y,z,A lines as pdsm query prints them (`nan` where A is undefined)."""
    with open(path, "w") as f:
        for i, p in enumerate(points):
            row = [f"{c:.9g}" for c in p]
            if values is not None:
                row.append("nan" if values[i] is None or math.isnan(values[i]) else f"{values[i]:.6g}")
            f.write(",".join(row) + "\n")
