#!/usr/bin/python3
"""What PDSM resolution the shadows near contacts need (issue #15 item 2, groundwork for
adaptive resolution): pdsm bakes of a scene at its own resolution and at 2x, 4x, ... in each
axis, measured on ground points near where the casters touch the ground, against Embree at
4096 samples per point (std. dev. <= 0.008; `--reference exact` for rect and disk lights:
noiseless, but hours for the dragon's 59,000 points), with each bake's CPU seconds and bytes.
Each factor is baked twice: the PDSM alone refined (the scene's shadow maps), and the PDSM with
its shadow maps refined by the same factor (capped at 16384 texels across).

Adaptive resolution's target: P99 of the penumbra error within 0.3 of a caster's footprint
<= 0.05, at no more than 2x the bytes and 1.5x the time of the unrefined bake. A uniform bake
that meets it says what refinement the contacts need; its bytes and time are what refining
every tile would cost, the ceiling adaptive refinement must stay far under.

  /usr/bin/python3 bench/contact_resolution.py [--pdsm build/client/pdsm] [--out DIR]
      [--shared ../shared] [--scenes sun_pillars,dragon] [--factors 1,2,4]
      [--refinements 2,4,8] [--repeat 3] [--surface-points 6000]
      [--radius 0.3] [--band 0.02] [--step 0.01] [--reference embree|exact]

--refinements: adaptive resolution (issue #15 item 2): bakes at the scene's own resolution with
`--max-refinement R`, interleaved with the unrefined bake --repeat times (CPU medians), with
the bytes and the errors at the same points; and, on --surface-points points on the casters'
surfaces that face the light (2e-3 off them, where self-shadows fall), the same errors. Where
--factors and --refinements are both given, the uniform bakes come first.

Footprint: the parts of caster triangles within --band of the ground plane (along its normal),
rasterized onto the ground at --step. Points: the centres of --step cells within --radius of
the footprint, split into "beside" (not covered: ground anyone can see) and "under" (covered:
inside or right under a solid, where no point can be seen and no object can go). Penumbra: the
reference strictly between 0.01 and 0.99. Output: a markdown table on stdout and in
OUT/summary.md, OUT/rows.json, and each scene's points, reference and query CSVs.
"""
import argparse
import json
import math
import os
import statistics
import sys

import numpy as np
from scipy.spatial import cKDTree

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "cycles"))
sys.path.insert(0, HERE)
import pdsm_scene  # noqa: E402
from cycles_compare import errors, read_values, run_timed  # noqa: E402

# The bundled and shared scenes whose casters stand on their ground (plates' hover above it).
SCENES = {"sun_pillars": "examples/sun_pillars/scene.json", "dragon": None}


def footprint_cells(model, band, step):
    """(cells covered by caster material within `band` of the ground, as integer (i, j) pairs
    on the ground axes; the ground origin and axes)."""
    _, gverts, _ = model.ground()
    origin = np.array(gverts[0])
    n = np.array(model.ground_normal)
    a, b = (np.array(x) for x in model.ground_axes)
    covered = set()
    for verts, tris in model.casters():
        v = np.array(verts)
        t = np.array(tris)
        h = (v - origin) @ n
        low = h[t].min(axis=1) <= band
        for tri in t[low]:
            p = v[tri]
            longest = max(np.linalg.norm(p[1] - p[0]), np.linalg.norm(p[2] - p[1]),
                          np.linalg.norm(p[0] - p[2]))
            k = max(1, math.ceil(2 * longest / step))
            i, j = np.meshgrid(np.arange(k + 1), np.arange(k + 1))
            keep = i + j <= k
            wa, wb = i[keep] / k, j[keep] / k
            q = p[0] + np.outer(wa, p[1] - p[0]) + np.outer(wb, p[2] - p[0])
            q = q[(q - origin) @ n <= band]
            for u, w in zip(np.floor((q - origin) @ a / step), np.floor((q - origin) @ b / step)):
                covered.add((int(u), int(w)))
    return covered, origin, a, b


def contact_points(model, radius, band, step):
    covered, origin, a, b = footprint_cells(model, band, step)
    if not covered:
        sys.exit(f"{model.path}: no caster lies within {band} of the ground")
    cells = np.array(sorted(covered))
    tree = cKDTree(cells * step)
    r = math.ceil(radius / step)
    lo, hi = cells.min(axis=0) - r, cells.max(axis=0) + r
    i, j = np.meshgrid(np.arange(lo[0], hi[0] + 1), np.arange(lo[1], hi[1] + 1))
    candidates = np.stack([i.ravel(), j.ravel()], axis=1)
    distance, _ = tree.query(candidates * step)
    near = candidates[distance <= radius]
    points, under = [], []
    for u, w in near:
        centre = origin + (u + 0.5) * step * a + (w + 0.5) * step * b
        points.append(tuple(centre))
        under.append((int(u), int(w)) in covered)
    return points, under


def surface_points(model, count, seed=4):
    """Points on the casters' surfaces that face the light, area-weighted, 2e-3 off them."""
    rng = np.random.default_rng(seed)
    tris, normals, areas = [], [], []
    for verts, faces in model.casters():
        v = np.array(verts)
        t = np.array(faces)
        a, b = v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]
        n = np.cross(a, b)
        area = np.linalg.norm(n, axis=1)
        centre = v[t].mean(axis=1)
        light = np.array([model.toward_light(list(c)) for c in centre])
        facing = (n * light).sum(axis=1) > 0.2 * area
        keep = np.where(facing & (area > 0))[0]
        tris.append(v[t[keep]])
        normals.append(n[keep] / area[keep, None])
        areas.append(area[keep])
    if not tris:
        return []
    tris, normals, areas = np.concatenate(tris), np.concatenate(normals), np.concatenate(areas)
    pick = rng.choice(len(areas), size=count, p=areas / areas.sum())
    r1, r2 = rng.random(count), rng.random(count)
    flip = r1 + r2 > 1
    r1[flip], r2[flip] = 1 - r1[flip], 1 - r2[flip]
    t = tris[pick]
    p = t[:, 0] + r1[:, None] * (t[:, 1] - t[:, 0]) + r2[:, None] * (t[:, 2] - t[:, 0])
    return [tuple(x) for x in p + 2e-3 * normals[pick]]


def ground_only_scene(scene, folder):
    """A copy of `scene` in `folder` whose receiving meshes but the ground (the first
    RECEIVER_ONLY one) have `"refine": false`: adaptive resolution refines the ground alone."""
    data = json.load(open(scene))
    base = os.path.dirname(os.path.abspath(scene))
    ground = next(i for i, m in enumerate(data["meshes"]) if m.get("role") == "RECEIVER_ONLY")
    for i, mesh in enumerate(data["meshes"]):
        if "path" in mesh:
            mesh["path"] = os.path.join(base, mesh["path"])
        if i != ground and mesh.get("role", "CASTER_AND_RECEIVER") != "CASTER_ONLY":
            mesh["refine"] = False
    path = os.path.join(folder, "scene_ground_only.json")
    json.dump(data, open(path, "w"), indent=1)
    return path


def refined_rows(args, name, scene, folder, csv, sets, exact, reference_method):
    """The unrefined bake and one per --refinements, interleaved --repeat times; with
    --ground-only, also one per refinement of the ground alone (ground_only_scene)."""
    tags = [1] + [int(r) for r in args.refinements.split(",")]
    if args.ground_only:
        ground_scene = ground_only_scene(scene, folder)
        tags += [f"{r}g" for r in args.refinements.split(",")]
    surface = None
    if args.surface_points > 0:
        points = surface_points(pdsm_scene.Scene(scene), args.surface_points)
        surface_csv = os.path.join(folder, "surface_points.csv")
        pdsm_scene.write_points(surface_csv, points)
        ref = os.path.join(folder, "surface_reference.csv")
        run_timed([args.pdsm, "reference", scene, "--points", surface_csv] + reference_method, ref)
        surface = (surface_csv, read_values(ref))
    cpu = {r: [] for r in tags}
    for _ in range(args.repeat):
        for r in tags:
            exr = os.path.join(folder, f"refined{r}.exr")
            source = ground_scene if str(r).endswith("g") else scene
            cpu[r].append(run_timed([args.pdsm, "bake", source, "-o", exr, "--no-preview",
                                     "--max-refinement", str(r).rstrip("g")]))
    rows = []
    for r in tags:
        exr = os.path.join(folder, f"refined{r}.exr")
        out = os.path.join(folder, f"refined{r}.csv")
        run_timed([args.pdsm, "query", exr, "--points", csv], out)
        row = {"scene": name, "refinement": r, "cpu": statistics.median(cpu[r]), "cpu_runs": cpu[r],
               "bytes": os.path.getsize(exr)}
        baked = read_values(out)
        for key, keep in sets.items():
            row[key] = errors(baked, exact, keep)
        if surface:
            surface_out = os.path.join(folder, f"refined{r}_surface.csv")
            run_timed([args.pdsm, "query", exr, "--points", surface[0]], surface_out)
            values = read_values(surface_out)
            row["surface"] = errors(values, surface[1],
                                    [i for i, x in enumerate(surface[1]) if 0.01 < x < 0.99])
        rows.append(row)
        print(f"{name} refinement {r}: {json.dumps(row)}", file=sys.stderr, flush=True)
    return rows


def measure(args, name, scene):
    folder = os.path.join(args.out, name)
    os.makedirs(folder, exist_ok=True)
    model = pdsm_scene.Scene(scene)
    points, under = contact_points(model, args.radius, args.band, args.step)
    csv = os.path.join(folder, "points.csv")
    pdsm_scene.write_points(csv, points)
    method = ["--method", "embree", "--samples", "4096", "--seed", "1"] \
        if args.reference == "embree" else ["--method", "exact"]
    ref = os.path.join(folder, "reference.csv")
    ref_cpu = run_timed([args.pdsm, "reference", scene, "--points", csv] + method, ref)
    exact = read_values(ref)
    penumbra = [i for i, x in enumerate(exact) if 0.01 < x < 0.99]
    sets = {"beside": [i for i in penumbra if not under[i]], "under": [i for i in penumbra if under[i]]}
    base = json.load(open(scene)).get("bake", {}).get("resolution", [512, 512])
    bake = json.load(open(scene)).get("bake", {})
    base_sm = bake.get("shadowMapResolution", 512)
    rows = []
    for factor in [int(f) for f in args.factors.split(",") if f]:
        res = f"{base[0] * factor}x{base[1] * factor}"
        for maps in sorted({base_sm, min(16384, base_sm * factor)}):  # one bake at 1x
            tag = f"x{factor}_sm{maps}"
            exr = os.path.join(folder, f"{tag}.exr")
            cmd = [args.pdsm, "bake", scene, "-o", exr, "--no-preview", "--resolution", res,
                   "--sm-resolution", str(maps)]
            cpu = [run_timed(cmd) for _ in range(args.repeat)]
            out = os.path.join(folder, f"{tag}.csv")
            run_timed([args.pdsm, "query", exr, "--points", csv], out)
            baked = read_values(out)
            row = {"scene": name, "factor": factor, "resolution": res, "shadow_maps": maps,
                   "cpu": statistics.median(cpu), "cpu_runs": cpu, "bytes": os.path.getsize(exr),
                   "points": len(points), "reference_cpu": ref_cpu}
            for key, keep in sets.items():
                row[key] = errors(baked, exact, keep)
            rows.append(row)
            print(f"{name} {tag}: {json.dumps(row)}", file=sys.stderr, flush=True)
    if args.refinements:
        rows += refined_rows(args, name, scene, folder, csv, sets, exact, method)
    return rows


def fmt(e):
    if not e.get("n"):
        return "—"
    return f"{e['mae']:.4f} / {e['p95']:.3f} / {e['p99']:.3f} / {e['max']:.2f} ({e['n']})"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--pdsm", default="build/client/pdsm")
    p.add_argument("--out", default="/tmp/contact_resolution")
    p.add_argument("--shared", default=os.environ.get("PDSM_SHARED", "../shared"))
    p.add_argument("--scenes", default="sun_pillars,dragon")
    p.add_argument("--factors", default="1,2,4")
    p.add_argument("--radius", type=float, default=0.3)
    p.add_argument("--band", type=float, default=0.02)
    p.add_argument("--step", type=float, default=0.01)
    p.add_argument("--repeat", type=int, default=1, help="bakes per resolution (CPU median)")
    p.add_argument("--refinements", default="", help="adaptive resolution: --max-refinement values")
    p.add_argument("--surface-points", type=int, default=0,
                   help="with --refinements: points on the casters' lit surfaces")
    p.add_argument("--reference", choices=("embree", "exact"), default="embree")
    p.add_argument("--ground-only", action="store_true",
                   help="with --refinements: also refine the ground alone (`refine: false` on "
                        "the other receivers), tagged Rg")
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    rows = []
    for name in args.scenes.split(","):
        scene = SCENES[name]
        if scene is None:
            scene = os.path.join(args.shared, "scenes", "dragon.json")
            if not os.path.exists(scene):
                print(f"{name}: skipped ({scene} is absent)", file=sys.stderr)
                continue
        rows += measure(args, name, scene)
    lines = ["Penumbra points near contacts: |pdsm - reference| as MAE / P95 / P99 / max (points)",
             "", "| scene | PDSM | shadow maps | beside the footprint | under it | CPU-s | bytes |",
             "|---|---|---|---|---|---|---|"]
    uniform = [r for r in rows if "refinement" not in r]
    for r in uniform:
        lines.append(f"| {r['scene']} | {r['resolution']} | {r['shadow_maps']} | {fmt(r['beside'])} "
                     f"| {fmt(r['under'])} | {r['cpu']:.2f} | {r['bytes']:,} |")
    refined = [r for r in rows if "refinement" in r]
    if refined:
        lines += ["", "Adaptive resolution (`--max-refinement R`), CPU-s the median of interleaved runs",
                  "", "| scene | R | near contacts (beside) | casters' lit surfaces | CPU-s | x | bytes | x |",
                  "|---|---|---|---|---|---|---|---|"]
        base = {r["scene"]: r for r in refined if r["refinement"] == 1}
        for r in refined:
            b = base[r["scene"]]
            lines.append(f"| {r['scene']} | {r['refinement']} | {fmt(r['beside'])} | "
                         f"{fmt(r.get('surface', {}))} | {r['cpu']:.2f} | {r['cpu'] / b['cpu']:.2f} | "
                         f"{r['bytes']:,} | {r['bytes'] / b['bytes']:.2f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    open(os.path.join(args.out, "summary.md"), "w").write(text)
    json.dump(rows, open(os.path.join(args.out, "rows.json"), "w"), indent=1)


if __name__ == "__main__":
    main()
