#!/usr/bin/python3
"""How far pdsm's attenuation sits from a renderer's shadow ratio, per definition (issue #15
item 4): the unweighted hidden fraction (what pdsm bakes), the emitter-weighted one (the hidden
share of the light's solid angle: what a PDSM could store) and the irradiance-weighted one (the
shadowed / unshadowed direct irradiance of the ground, what Cycles or Lightmass computes), all
three by `pdsm reference --weighting` on the same ground points. Rect and disk lights are exact
(no sampling noise at all); a sun uses Embree with the same seed for every weighting, so the
gaps between definitions are measured on the same rays.

  /usr/bin/python3 bench/weighting_gap.py [--pdsm build/client/pdsm] [--out DIR]
      [--shared ../shared] [--scenes plates,large_light,sun_pillars,dragon] [--grid N]
    [--repeat 3]

Points: cycles_compare.py's grids (texel centres over the ground at the PDSM's density; the
dragon a 10x10 crop, skipped without SHARED/scenes/dragon.json); large_light is plates with its
3x3 light grown to 10x10 (written to OUT/large_light/scene.json). Penumbra: the unweighted
reference strictly between 0.01 and 0.99. pdsm: `pdsm bake --weighting unweighted` and
`pdsm bake --weighting emitter` at the scene's settings (their CPU seconds interleaved,
--repeat times, medians), then `pdsm query`, each measured against each definition. Output: two
markdown tables on stdout and in OUT/summary.md.
"""
import argparse
import json
import os
import statistics
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "cycles"))
import pdsm_scene  # noqa: E402
from cycles_compare import SCENES, errors, read_values, run_timed  # noqa: E402

WEIGHTINGS = ("unweighted", "emitter", "irradiance")


def large_light_scene(out):
    """plates with a 10x10 light at the same place: the light large seen from the casters."""
    doc = json.load(open("examples/plates/scene.json"))
    doc["name"] = "large_light"
    doc["light"]["rect"]["size"] = [10, 10]
    folder = os.path.join(out, "large_light")
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, "scene.json")
    json.dump(doc, open(path, "w"), indent=1)
    return path


def measure(args, name, scene, grid, crop):
    folder = os.path.join(args.out, name)
    os.makedirs(folder, exist_ok=True)
    model = pdsm_scene.Scene(scene)
    points = os.path.join(folder, "points.csv")
    pdsm_scene.write_points(points, model.ground_grid(args.grid or grid, crop))
    method = ["--method", "embree", "--samples", "4096", "--seed", "1"] if model.kind == "sun" \
        else ["--method", "exact"]
    normal = ",".join(f"{c:.17g}" for c in model.ground_normal)
    refs, cpu = {}, {}
    for w in WEIGHTINGS:
        extra = ["--normal", normal] if w == "irradiance" else []
        out = os.path.join(folder, f"reference_{w}.csv")
        cpu[w] = run_timed([args.pdsm, "reference", scene, "--points", points, "--weighting", w]
                           + method + extra, out)
        refs[w] = read_values(out)
    penumbra = [i for i, a in enumerate(refs["unweighted"]) if 0.01 < a < 0.99]
    bakes = ("unweighted", "emitter")
    bake_cpu = {b: [] for b in bakes}
    for _ in range(args.repeat):  # interleaved: the machine's load hits both alike
        for b in bakes:
            exr = os.path.join(folder, f"pdsm_{b}.exr")
            bake_cpu[b].append(run_timed([args.pdsm, "bake", scene, "-o", exr, "--no-preview",
                                          "--weighting", b]))
    pdsm = {}
    for b in bakes:
        exr = os.path.join(folder, f"pdsm_{b}.exr")
        csv = os.path.join(folder, f"pdsm_{b}.csv")
        run_timed([args.pdsm, "query", exr, "--points", points], csv)
        baked = read_values(csv)
        pdsm[b] = {w: errors(baked, refs[w], penumbra) for w in WEIGHTINGS}
        pdsm[b]["bytes"] = os.path.getsize(exr)
    row = {"name": name, "points": len(refs["unweighted"]), "penumbra": len(penumbra),
           "method": method[1], "reference_cpu": cpu,
           "bake_cpu": {b: statistics.median(v) for b, v in bake_cpu.items()},
           "bake_cpu_runs": bake_cpu,
           "gap_unweighted": errors(refs["unweighted"], refs["irradiance"], penumbra),
           "gap_emitter": errors(refs["emitter"], refs["irradiance"], penumbra),
           "pdsm": pdsm}
    print(f"{name}: {json.dumps(row)}", file=sys.stderr, flush=True)
    return row


def fmt(e):
    return f"{e['mae']:.4f} / {e['p95']:.4f} / {e['p99']:.4f} / {e['max']:.3f}"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--pdsm", default="build/client/pdsm")
    p.add_argument("--out", default="/tmp/weighting_gap")
    p.add_argument("--shared", default=os.environ.get("PDSM_SHARED", "../shared"))
    p.add_argument("--scenes", default="plates,large_light,sun_pillars,dragon")
    p.add_argument("--grid", type=int, help="an NxN grid for every scene (quick checks)")
    p.add_argument("--repeat", type=int, default=3, help="bakes of each weighting, interleaved")
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    table = {name: (path, grid, crop) for name, path, grid, crop, _ in SCENES}
    table["large_light"] = (large_light_scene(args.out), 256, None)
    rows = []
    for name in args.scenes.split(","):
        path, grid, crop = table[name]
        if path is None:
            path = os.path.join(args.shared, "scenes", "dragon.json")
            if not os.path.exists(path):
                print(f"{name}: skipped ({path} is absent)", file=sys.stderr)
                continue
        rows.append(measure(args, name, path, grid, crop))
    lines = ["Definitions, exactly (references): MAE / P95 / P99 / max on penumbra points", "",
             "| scene (penumbra points) | unweighted vs irradiance | emitter vs irradiance |",
             "|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['name']} ({r['penumbra']}) | {fmt(r['gap_unweighted'])} "
                     f"| {fmt(r['gap_emitter'])} |")
    lines += ["", "Bakes: MAE / P99 against each reference; CPU-s (median), file bytes", "",
              "| scene | bake | vs unweighted | vs emitter | vs irradiance | CPU-s | bytes |",
              "|---|---|---|---|---|---|---|"]
    for r in rows:
        for b, pd in r["pdsm"].items():
            lines.append(f"| {r['name']} | {b} "
                         + " ".join(f"| {pd[w]['mae']:.4f} / {pd[w]['p99']:.4f}"
                                    for w in WEIGHTINGS)
                         + f" | {r['bake_cpu'][b]:.2f} | {pd['bytes']:,} |")
    text = "\n".join(lines) + "\n"
    print(text)
    open(os.path.join(args.out, "summary.md"), "w").write(text)
    json.dump(rows, open(os.path.join(args.out, "rows.json"), "w"), indent=1)


if __name__ == "__main__":
    main()
