#!/usr/bin/python3
"""Writes a generated village as a pdsm scene (issue #12 item 7): a SIDE x SIDE ground, houses
with gabled roofs and round trees scattered over it at a fixed density (so the triangle count
grows with the area), under a 0.53-degree sun and LIGHTS local lights of three shapes: street
lamps (spot lights pointing down), porch lights (rect lights under the eaves) and yard lights
(disk lights on poles), each with a bounded reach (its own `bake.frustum`, as an artist sets a
light's attenuation radius in an engine). No download: everything comes from a seeded RNG.

The meshes go to binary PLY files beside the scene (Assimp reads them): ground.ply
(RECEIVER_ONLY), houses.ply and trees.ply. Prints the counts.

Usage: bench/large_world.py OUT_DIR [SIDE=1000] [LIGHTS=54] [SUN_RES=4096]
  SIDE in metres; the sun's PDSM keeps SIDE / SUN_RES metres per pixel.
"""
import json
import math
import os
import random
import struct
import sys

HOUSES_PER_KM2 = 400   # one per 2,500 m^2
TREES_PER_KM2 = 2500   # one per 400 m^2


class Mesh:
    def __init__(self):
        self.positions = []  # (x, y, z)
        self.triangles = []  # (a, b, c)

    def vertex(self, p):
        self.positions.append(p)
        return len(self.positions) - 1

    def quad(self, a, b, c, d, nu=1, nv=1):
        """A quad a-b-c-d (counter-clockwise seen from outside), split nu x nv."""
        grid = []
        for j in range(nv + 1):
            row = []
            for i in range(nu + 1):
                u, v = i / nu, j / nv
                p = [(1 - u) * (1 - v) * a[k] + u * (1 - v) * b[k] + u * v * c[k] +
                     (1 - u) * v * d[k] for k in range(3)]
                row.append(self.vertex(tuple(p)))
            grid.append(row)
        for j in range(nv):
            for i in range(nu):
                p00, p10, p11, p01 = grid[j][i], grid[j][i + 1], grid[j + 1][i + 1], grid[j + 1][i]
                self.triangles += [(p00, p10, p11), (p00, p11, p01)]

    def write_ply(self, path):
        with open(path, "wb") as f:
            f.write(("ply\nformat binary_little_endian 1.0\n"
                     f"element vertex {len(self.positions)}\n"
                     "property float x\nproperty float y\nproperty float z\n"
                     f"element face {len(self.triangles)}\n"
                     "property list uchar int vertex_indices\nend_header\n").encode())
            for p in self.positions:
                f.write(struct.pack("<3f", *p))
            for t in self.triangles:
                f.write(struct.pack("<B3i", 3, *t))


def house(mesh, x, z, w, d, h, roof, angle):
    """A box w x d x h with a gabled roof `roof` high, turned by `angle` about y."""
    c, s = math.cos(angle), math.sin(angle)

    def at(px, py, pz):
        return (x + c * px - s * pz, py, z + s * px + c * pz)
    hw, hd = w / 2, d / 2
    corners = [(-hw, -hd), (hw, -hd), (hw, hd), (-hw, hd)]
    for k in range(4):  # walls, 4 x 3 tiles each (window rows)
        (ax, az), (bx, bz) = corners[k], corners[(k + 1) % 4]
        mesh.quad(at(ax, 0, az), at(bx, 0, bz), at(bx, h, bz), at(ax, h, az), 4, 3)
    ridge = h + roof
    mesh.quad(at(-hw, h, -hd), at(hw, h, -hd), at(hw, ridge, 0), at(-hw, ridge, 0), 6, 3)
    mesh.quad(at(hw, h, hd), at(-hw, h, hd), at(-hw, ridge, 0), at(hw, ridge, 0), 6, 3)
    for sx in (-hw, hw):  # gables
        a, b, t = mesh.vertex(at(sx, h, -hd)), mesh.vertex(at(sx, h, hd)), mesh.vertex(at(sx, ridge, 0))
        mesh.triangles.append((a, b, t) if sx > 0 else (b, a, t))


def tree(mesh, x, z, trunk_h, crown_r, sides=10, rings=10):
    """A trunk (a `sides`-gon prism) under a crown (a UV sphere of `rings` rings)."""
    r = 0.15 + 0.05 * crown_r
    for k in range(sides):
        a0, a1 = 2 * math.pi * k / sides, 2 * math.pi * (k + 1) / sides
        p0, p1 = (x + r * math.cos(a0), z + r * math.sin(a0)), (x + r * math.cos(a1), z + r * math.sin(a1))
        mesh.quad((p0[0], 0, p0[1]), (p1[0], 0, p1[1]), (p1[0], trunk_h, p1[1]), (p0[0], trunk_h, p0[1]))
    cy = trunk_h + crown_r * 0.8
    ring_vertices = []
    for j in range(1, rings):
        phi = math.pi * j / rings
        ring_vertices.append([mesh.vertex((x + crown_r * math.sin(phi) * math.cos(2 * math.pi * k / (2 * sides)),
                                           cy + crown_r * math.cos(phi),
                                           z + crown_r * math.sin(phi) * math.sin(2 * math.pi * k / (2 * sides))))
                              for k in range(2 * sides)])
    top, bottom = mesh.vertex((x, cy + crown_r, z)), mesh.vertex((x, cy - crown_r, z))
    n = 2 * sides
    for k in range(n):
        mesh.triangles.append((top, ring_vertices[0][(k + 1) % n], ring_vertices[0][k]))
        mesh.triangles.append((bottom, ring_vertices[-1][k], ring_vertices[-1][(k + 1) % n]))
    for j in range(len(ring_vertices) - 1):
        for k in range(n):
            a, b = ring_vertices[j][k], ring_vertices[j][(k + 1) % n]
            c, d = ring_vertices[j + 1][(k + 1) % n], ring_vertices[j + 1][k]
            mesh.triangles += [(a, b, c), (a, c, d)]


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    side = float(sys.argv[2]) if len(sys.argv) > 2 else 1000.0
    light_count = int(sys.argv[3]) if len(sys.argv) > 3 else 54
    sun_res = int(sys.argv[4]) if len(sys.argv) > 4 else 4096
    os.makedirs(out, exist_ok=True)
    rng = random.Random(12)
    km2 = side * side / 1e6
    half = side / 2

    ground = Mesh()
    cells = max(1, int(side / 16))
    ground.quad((-half, 0, half), (half, 0, half), (half, 0, -half), (-half, 0, -half), cells, cells)

    houses, sites = Mesh(), []
    for _ in range(int(round(HOUSES_PER_KM2 * km2))):
        x, z = rng.uniform(-half + 10, half - 10), rng.uniform(-half + 10, half - 10)
        w, d = rng.uniform(6, 14), rng.uniform(6, 10)
        h, roof, angle = rng.uniform(3, 9), rng.uniform(1.5, 4), rng.uniform(0, math.pi)
        house(houses, x, z, w, d, h, roof, angle)
        sites.append((x, z, w, d, h, angle))
    trees = Mesh()
    for _ in range(int(round(TREES_PER_KM2 * km2))):
        tree(trees, rng.uniform(-half, half), rng.uniform(-half, half), rng.uniform(1.5, 4),
             rng.uniform(1.5, 4))

    # Local lights, in thirds: spots (street lamps), rects (porch lights), disks (yard lights).
    lights = [{"name": "sun", "sun": {"direction": [0.35, -1, 0.25], "angularDiameterDeg": 0.53},
               "bake": {"resolution": [sun_res, sun_res], "samples": 8,
                        "shadowMapResolution": 4096}}]
    local_bake = {"resolution": [256, 256], "samples": 16, "shadowMapResolution": 512}
    reach = {"window": [-1.5, 1.5, -1.5, 1.5], "depthRange": [0.2, 12]}
    for k in range(light_count):
        kind = ("spot", "rect", "disk")[k % 3]
        if kind == "rect":  # under a house's eave, facing down, 1.2 m out from a wall
            x, z, w, d, h, angle = sites[k % len(sites)]
            c, s = math.cos(angle), math.sin(angle)
            px, pz = 0.0, d / 2 + 1.2
            center = [x + c * px - s * pz, h - 0.3, z + s * px + c * pz]
            light = {"rect": {"center": center, "normal": [0, -1, 0], "up": [0, 0, 1],
                              "size": [0.8, 0.3]}, "bake": dict(local_bake, frustum=reach)}
        else:
            center = [rng.uniform(-half * 0.9, half * 0.9), 6.0 if kind == "spot" else 4.0,
                      rng.uniform(-half * 0.9, half * 0.9)]
            if kind == "spot":
                light = {"spot": {"center": center, "normal": [0, -1, 0], "radius": 0.15,
                                  "coneHalfAngleDeg": 50}, "bake": dict(local_bake)}
            else:
                light = {"disk": {"center": center, "normal": [0, -1, 0], "radius": 0.4},
                         "bake": dict(local_bake, frustum=reach)}
        light["name"] = f"{kind}_{k}"
        lights.append(light)

    for name, mesh in (("ground", ground), ("houses", houses), ("trees", trees)):
        mesh.write_ply(os.path.join(out, name + ".ply"))
    scene = {
        "name": f"village-{int(side)}m",
        "meshes": [{"path": "ground.ply", "role": "RECEIVER_ONLY"}, {"path": "houses.ply"},
                   {"path": "trees.ply"}],
        "lights": lights,
        "bake": {"epsilon": 0.02},
    }
    with open(os.path.join(out, "scene.json"), "w") as f:
        json.dump(scene, f, indent=1)
    total = len(ground.triangles) + len(houses.triangles) + len(trees.triangles)
    print(f"{out}/scene.json: {side:g} m x {side:g} m, {len(sites)} houses, "
          f"{int(round(TREES_PER_KM2 * km2))} trees, {total} triangles "
          f"(ground {len(ground.triangles)}, houses {len(houses.triangles)}, "
          f"trees {len(trees.triangles)}), 1 sun at {sun_res}^2 + {light_count} local lights")


if __name__ == "__main__":
    main()
