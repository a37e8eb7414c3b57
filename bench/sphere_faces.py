#!/usr/bin/python3
"""The error of a sphere light's faces (issue #12 item 2; docs/scene_format.md, "Sphere lights").

A sphere is baked as six cube faces, each sampling the disk of the sphere's radius that faces
its axis. This splits the error of the bake against the Embree reference that samples the true
sphere into its two parts, per angle off the face's axis:
  - approximation: the face's disk (Embree, the same disk light) against the true sphere;
  - bake: the PDSM against the face's disk (what the bake sets out to compute);
  - total: the PDSM against the true sphere.
Points: the floor under a sphere of radius R at height 4 over a 2 x 2 plate at height 2 and a
wall at x = 4; only penumbra points (the true sphere's value in (0.02, 0.98)) are counted.

Usage: bench/sphere_faces.py BUILD_DIR OUT_DIR [RADIUS=0.3] [RES=256] [SAMPLES=256]
"""
import csv
import json
import math
import os
import subprocess
import sys

FACES = [("+x", (1, 0, 0)), ("-x", (-1, 0, 0)), ("+y", (0, 1, 0)), ("-y", (0, -1, 0)),
         ("+z", (0, 0, 1)), ("-z", (0, 0, -1))]
CENTER = (0.5, 4.0, 0.0)
MESHES = [
    {"inline": {"positions": [-8, 0, -8, 8, 0, -8, 8, 0, 8, -8, 0, 8],
                "indices": [0, 1, 2, 0, 2, 3]}, "role": "RECEIVER_ONLY"},
    {"inline": {"positions": [-1, 2, -1, 1, 2, -1, 1, 2, 1, -1, 2, 1],
                "indices": [0, 1, 2, 0, 2, 3]}, "role": "CASTER_ONLY"},
    {"inline": {"positions": [4, 0, -1, 4, 0, 1, 4, 2, 1, 4, 2, -1],
                "indices": [0, 1, 2, 0, 2, 3]}, "role": "CASTER_ONLY"},
]


def run(args):
    return subprocess.run(args, check=True, capture_output=True, text=True).stdout


def values(text):
    return [float(line.split(",")[3]) for line in text.splitlines() if line]


def face_of(p):
    d = [p[k] - CENTER[k] for k in range(3)]
    best = max(range(6), key=lambda f: sum(FACES[f][1][k] * d[k] for k in range(3)))
    axis = FACES[best][1]
    cos = sum(axis[k] * d[k] for k in range(3)) / math.sqrt(sum(x * x for x in d))
    return best, math.degrees(math.acos(min(1.0, cos)))


def stats(errors):
    if not errors:
        return "-"
    errors = sorted(errors)
    mean = sum(errors) / len(errors)
    p95 = errors[min(len(errors) - 1, int(0.95 * len(errors)))]
    return f"{mean:.4f} / {p95:.4f} / {errors[-1]:.3f}"


def main():
    build, out = sys.argv[1], sys.argv[2]
    radius = float(sys.argv[3]) if len(sys.argv) > 3 else 0.3
    res = int(sys.argv[4]) if len(sys.argv) > 4 else 256
    samples = int(sys.argv[5]) if len(sys.argv) > 5 else 256
    os.makedirs(out, exist_ok=True)
    pdsm = os.path.join(build, "client", "pdsm")
    bake = {"resolution": [res, res], "samples": samples, "epsilon": 0.005}
    scene = {"name": "sphere", "meshes": MESHES, "bake": bake,
             "lights": [{"name": "lamp", "sphere": {"center": list(CENTER), "radius": radius}}]}
    scene_path = os.path.join(out, "sphere.json")
    with open(scene_path, "w") as f:
        json.dump(scene, f)
    points = [(x / 16, 0.0, z / 4) for x in range(-120, 121) for z in range(-30, 31)]
    points_path = os.path.join(out, "points.csv")
    with open(points_path, "w") as f:
        f.writelines(f"{p[0]},{p[1]},{p[2]}\n" for p in points)
    exr = os.path.join(out, "sphere.exr")
    before = os.times()
    run([pdsm, "bake", scene_path, "-o", exr, "--no-preview"])
    after = os.times()
    bake_cpu = (after.children_user + after.children_system
                - before.children_user - before.children_system)
    baked = values(run([pdsm, "query", exr, "--points", points_path]))
    sphere = values(run([pdsm, "reference", scene_path, "--points", points_path,
                         "--samples", "4096"]))
    disks = []
    for label, axis in FACES:
        disk_scene = dict(scene, lights=[{"name": "disk", "disk": {
            "center": list(CENTER), "normal": list(axis), "radius": radius}}])
        path = os.path.join(out, f"disk{label}.json")
        with open(path, "w") as f:
            json.dump(disk_scene, f)
        disks.append(values(run([pdsm, "reference", path, "--points", points_path,
                                 "--method", "embree", "--samples", "4096"])))
    bins = [(0, 15), (15, 30), (30, 45), (45, 55)]
    rows = {b: {"approximation": [], "bake": [], "total": []} for b in bins}
    with open(os.path.join(out, "points_errors.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["x", "y", "z", "face", "theta_deg", "sphere", "disk", "pdsm"])
        for i, p in enumerate(points):
            face, theta = face_of(p)
            disk = disks[face][i]
            w.writerow([*p, FACES[face][0], f"{theta:.2f}", sphere[i], disk, baked[i]])
            if not (0.02 < sphere[i] < 0.98) or math.isnan(baked[i]):
                continue
            b = next(b for b in bins if b[0] <= theta < b[1])
            rows[b]["approximation"].append(abs(disk - sphere[i]))
            rows[b]["bake"].append(abs(baked[i] - disk))
            rows[b]["total"].append(abs(baked[i] - sphere[i]))
    print(f"sphere radius {radius}, {res}^2 per face, {samples} samples: bake {bake_cpu:.1f} "
          f"CPU-s, {os.path.getsize(exr) / 2**20:.1f} MiB; penumbra points; mean / P95 / max "
          "of |error|")
    print("| angle off the face's axis | points | face disk vs sphere | PDSM vs face disk "
          "| PDSM vs sphere |")
    print("|---|---|---|---|---|")
    for b in bins:
        r = rows[b]
        print(f"| {b[0]}-{b[1]} deg | {len(r['total'])} | {stats(r['approximation'])} "
              f"| {stats(r['bake'])} | {stats(r['total'])} |")


if __name__ == "__main__":
    main()
