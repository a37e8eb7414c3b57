#!/usr/bin/python3
"""pdsm against Blender Cycles on the ground's penumbrae, both against the exact (or Embree)
reference: issue #11 item 8 (CPU seconds at matching error, docs/performance.md) and issue #15
item 5 (the anchor's table and the definition gap, docs/accuracy.md).

  /usr/bin/python3 bench/cycles_compare.py [--pdsm build/client/pdsm] [--blender blender]
      [--out DIR] [--shared ../shared] [--scenes plates,sun_pillars,dragon] [--repeat 3]
      [--max-samples 8192] [--validate-samples 4096] [--threads 2] [--grid N]

Per scene: a grid of texel centres on the ground at the PDSM's own density (the dragon: a
10x10 crop around it; skipped with a message when SHARED/scenes/dragon.json is absent); the
reference there (`pdsm reference --method exact`, a sun `--method embree --samples 4096`);
penumbra points = reference strictly between 0.01 and 0.99. pdsm: `pdsm bake --threads T
--no-preview` at the scene's settings, CPU seconds (user + system, /usr/bin/time) median of
--repeat runs, then `pdsm query` at the points. Cycles (bench/cycles/pdsm_scene_to_cycles.py,
unweighted: pdsm's definition) at 16, 32, 64, ... samples until its MAE, P95 and P99 on the
penumbra points are all at or below pdsm's (or --max-samples), then once weighted at the last
count: the definition gap |weighted - unweighted|. Cycles' CPU seconds are those of its bake
with the casters (Cycles' scene sync, BVH and render, measured in the process); Blender's
start-up (a trivial run, median of --repeat), the scene import and the bake without casters
(only the ratio's denominator) are reported apart. On the grid the bake with casters runs
--repeat times in its process: its CPU-s is their median.

Output: the tables on stdout (markdown) and in DIR/summary.md; DIR/SCENE/ keeps the points,
the reference, pdsm's and every Cycles run's x,y,z,A CSV and each run's JSON.
"""
import argparse
import datetime
import json
import math
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "cycles"))
import pdsm_scene  # noqa: E402

TO_CYCLES = os.path.join(HERE, "cycles", "pdsm_scene_to_cycles.py")
# name, scene (None: under --shared), grid side (the PDSM's pixels across the same ground),
# crop side (None: the whole ground), pdsm bakes (tag, flags): the scene's own settings, and a
# second step along pdsm's own trade (more samples where its penumbra error is sampling noise;
# on the dragon fewer, since its penumbra error is not). The dragon's PDSM is 512 px over 30
# units: 171 over the 10x10 crop.
SCENES = [("plates", "examples/plates/scene.json", 256, None,
           [("scene", []), ("s256", ["--samples", "256"])]),
          ("sun_pillars", "examples/sun_pillars/scene.json", 256, None,
           [("scene", []), ("s256r1024", ["--samples", "256", "--resolution", "1024x1024"])]),
          ("dragon", None, 171, 10.0,
           [("scene", []), ("s64", ["--samples", "64"])])]


def run_timed(cmd, stdout=os.devnull):
    """Runs cmd (stdout to that file, stderr beside it in .err); returns its user + system
    CPU seconds (/usr/bin/time -f '%U %S')."""
    timing = os.path.join(os.path.dirname(os.path.abspath(stdout)) if stdout != os.devnull
                          else "/tmp", "last.time")
    err = stdout + ".err" if stdout != os.devnull else os.devnull
    with open(stdout, "w") as out, open(err, "w") as err_file:
        done = subprocess.run(["/usr/bin/time", "-f", "%U %S", "-o", timing] + cmd, stdout=out,
                              stderr=err_file)
    if done.returncode != 0:
        sys.exit(f"failed ({done.returncode}): {' '.join(cmd)}; see {err}")
    user, system = open(timing).read().split()[-2:]
    return float(user) + float(system)


def median(values):
    v = sorted(values)
    return (v[(len(v) - 1) // 2] + v[len(v) // 2]) / 2


def read_values(path):
    """The last column of x,y,z,A lines (pdsm query / reference / the Cycles script)."""
    return [float(line.strip().split(",")[-1]) for line in open(path) if line.strip()]


def percentile(sorted_values, q):
    """Linear interpolation between closest ranks (numpy's default)."""
    pos = q * (len(sorted_values) - 1)
    lo = math.floor(pos)
    hi = min(lo + 1, len(sorted_values) - 1)
    return sorted_values[lo] + (pos - lo) * (sorted_values[hi] - sorted_values[lo])


def errors(values, truth, subset):
    """MAE, P95, P99, max of |values - truth| over the subset's indices (NaNs skipped); only
    n = 0 for an empty subset."""
    e = sorted(abs(values[i] - truth[i]) for i in subset
               if not math.isnan(values[i]) and not math.isnan(truth[i]))
    if not e:
        return {"n": 0}
    return {"n": len(e), "mae": sum(e) / len(e), "p95": percentile(e, 0.95),
            "p99": percentile(e, 0.99), "max": e[-1]}


def loadavg():
    return open("/proc/loadavg").read().split()[0]


def cycles(args, scene, points, samples, weighting, folder, tag, repeat=1):
    """One run of the Cycles script: its x,y,z,A values and its JSON (CPU seconds added)."""
    stem = os.path.join(folder, f"cycles_{tag}_{weighting}_{samples}")
    cmd = [args.blender, "-b", "--factory-startup", "--python-exit-code", "1",
           "--python", TO_CYCLES, "--", scene, "--points", points, "--out", stem + ".csv",
           "--samples", str(samples), "--weighting", weighting, "--threads", str(args.threads),
           "--json", stem + ".json", "--repeat", str(repeat)]
    process = run_timed(cmd, stem + ".log")  # Blender's messages: .log and .log.err
    stats = json.load(open(stem + ".json"))
    stats["cpu_s"]["process_time_cmd"] = process
    return read_values(stem + ".csv"), stats


def pdsm_bake(args, scene, flags, points, folder, tag):
    """Median CPU-s of --repeat bakes, and pdsm query's values at the points."""
    exr = os.path.join(folder, f"pdsm_{tag}.exr")
    cpu = median([run_timed([args.pdsm, "bake", scene, "-o", exr, "--threads",
                             str(args.threads), "--no-preview"] + flags)
                  for _ in range(args.repeat)])
    run_timed([args.pdsm, "query", exr, "--points", points], os.path.join(folder, f"pdsm_{tag}.csv"))
    return cpu, read_values(os.path.join(folder, f"pdsm_{tag}.csv"))


def compare(args, name, scene, grid, crop, configs):
    folder = os.path.join(args.out, name)
    os.makedirs(folder, exist_ok=True)
    model = pdsm_scene.Scene(scene)
    grid_points = model.ground_grid(grid, crop)
    points = os.path.join(folder, "points.csv")
    pdsm_scene.write_points(points, grid_points)
    log = lambda *words: print(f"{name}:", *words, file=sys.stderr, flush=True)

    method = ["--method", "embree", "--samples", "4096"] if model.kind == "sun" else \
        ["--method", "exact"]
    ref_cpu = run_timed([args.pdsm, "reference", scene, "--points", points] + method,
                        os.path.join(folder, "reference.csv"))
    truth = read_values(os.path.join(folder, "reference.csv"))
    penumbra = [i for i, a in enumerate(truth) if 0.01 < a < 0.99]
    log(f"{len(truth)} points, {len(penumbra)} in penumbrae; reference {method[1]} "
        f"{ref_cpu:.1f} CPU-s")

    bakes = []
    for tag, flags in configs:
        cpu, values = pdsm_bake(args, scene, flags, points, folder, tag)
        bakes.append({"tag": tag, "flags": " ".join(flags) or "scene settings", "cpu": cpu,
                      "err": errors(values, truth, penumbra)})
        log(f"pdsm {tag} {cpu:.2f} CPU-s, penumbra {bakes[-1]['err']}")

    # Cycles on every grid point (the lightmap's cost) until it meets every bake's errors.
    sweep, samples = [], 16
    while True:
        values, stats = cycles(args, scene, points, samples, "unweighted", folder, "grid",
                               args.repeat)
        err = errors(values, truth, penumbra)
        sweep.append({"samples": samples, "err": err, "cpu": stats["cpu_s"]})
        log(f"cycles {samples} samples, bake {stats['cpu_s']['bake_with']:.2f} CPU-s, {err}")
        if samples >= args.max_samples or all(err[k] <= b["err"][k] for b in bakes
                                              for k in ("mae", "p95", "p99")):
            break
        samples *= 2

    # Validation and the definition gap, on the penumbra points only (cheap at high counts).
    pen_points = os.path.join(folder, "penumbra_points.csv")
    pdsm_scene.write_points(pen_points, [grid_points[i] for i in penumbra])
    pen_truth = [truth[i] for i in penumbra]
    everything = range(len(penumbra))
    validation = []
    for s in [16 * 2 ** k for k in range(20) if 16 * 2 ** k <= args.validate_samples]:
        values, stats = cycles(args, scene, pen_points, s, "unweighted", folder, "penumbra")
        err = errors(values, pen_truth, everything)
        err["bias"] = sum(v - t for v, t in zip(values, pen_truth)) / len(values)
        validation.append({"samples": s, "err": err, "cpu": stats["cpu_s"],
                           "without_rel_range": stats["without_rel_range"]})
        log(f"validation {s} samples, {err}")
    weighted, wstats = cycles(args, scene, pen_points, s, "weighted", folder, "penumbra")
    gap = {"samples": s, "gap": errors(weighted, values, everything),
           "weighted_vs_reference": errors(weighted, pen_truth, everything),
           "without_rel_range": wstats["without_rel_range"]}
    return {"name": name, "scene": scene, "grid": grid, "crop": crop, "points": len(truth),
            "penumbra": len(penumbra), "reference": method[1], "reference_cpu": ref_cpu,
            "bakes": bakes, "sweep": sweep, "validation": validation, "gap": gap}


def first_meeting(sweep, target, metric):
    """The first swept Cycles run whose penumbra error is at or below the target's."""
    return next((r for r in sweep if r["err"][metric] <= target[metric]), None)


def interpolated_cpu(sweep, target):
    """Cycles' bake CPU-s at exactly the target MAE: samples interpolated log-log between the
    two runs around it, CPU-s linearly in samples between them (None outside the sweep)."""
    for lo, hi in zip(sweep, sweep[1:]):
        if lo["err"]["mae"] > target >= hi["err"]["mae"]:
            t = math.log(lo["err"]["mae"] / target) / math.log(lo["err"]["mae"] / hi["err"]["mae"])
            samples = lo["samples"] * (hi["samples"] / lo["samples"]) ** t
            w = (samples - lo["samples"]) / (hi["samples"] - lo["samples"])
            return (1 - w) * lo["cpu"]["bake_with"] + w * hi["cpu"]["bake_with"]
    return None


def slope(rows):
    """Least-squares exponent k of MAE ~ samples^k."""
    xs = [math.log(r["samples"]) for r in rows]
    ys = [math.log(r["err"]["mae"]) for r in rows]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)


def report(results, startup, header):
    f = lambda e: f"{e['mae']:.4f} / {e['p95']:.4f} / {e['p99']:.4f}"
    out = [header, "",
           "pdsm against Cycles at matching error. Penumbra points (reference strictly in "
           "(0.01, 0.99)), unweighted (pdsm's definition); MAE / P95 / P99 of |A - reference|. "
           "Cycles: the first of 16, 32, 64, ... samples per point at or below pdsm's error, "
           "and the CPU-s of its bake with casters over every grid point.", "",
           "| scene | grid points (penumbra) | reference | pdsm bake | pdsm CPU-s | "
           "pdsm MAE / P95 / P99 | Cycles at pdsm's MAE: samples, CPU-s (interpolated) | "
           "at P95 | at P99 | Cycles MAE / P95 / P99 at the MAE match |",
           "|---|---|---|---|---:|---|---|---|---|---|"]
    for r in results:
        for b in r["bakes"]:
            cells = []
            for metric in ("mae", "p95", "p99"):
                m = first_meeting(r["sweep"], b["err"], metric)
                cells.append(f"{m['samples']}, {m['cpu']['bake_with']:.2f}" if m else
                             f"> {r['sweep'][-1]['samples']}")
            exact = interpolated_cpu(r["sweep"], b["err"]["mae"])
            cells[0] += f" (≈ {exact:.2f})" if exact is not None else ""
            m = first_meeting(r["sweep"], b["err"], "mae") or r["sweep"][-1]
            out.append(f"| {r['name']} | {r['points']} ({r['penumbra']}) | {r['reference']} | "
                       f"{b['flags']} | {b['cpu']:.2f} | {f(b['err'])} | {' | '.join(cells)} | "
                       f"{f(m['err'])} |")
    out += ["", "Cycles on every grid point, by samples (CPU-s: bake with casters, median; bake "
            "without casters; the whole Blender process, its start-up, scene import and every "
            "bake included):", "",
            "| scene | samples | penumbra MAE / P95 / P99 | with | without | process |",
            "|---|---:|---|---:|---:|---:|"]
    for r in results:
        for s in r["sweep"]:
            c = s["cpu"]
            out.append(f"| {r['name']} | {s['samples']} | {f(s['err'])} | {c['bake_with']:.2f} | "
                       f"{c['bake_without']:.2f} | {c['process_time_cmd']:.2f} |")
    out += ["", "Validation of the unweighted rebuild, penumbra points only: Cycles against the "
            "reference as samples grow (bias = mean signed error; `without` spread = "
            "(max - min) / mean of the bake without casters, 0 when the weighting is cancelled "
            "exactly and the light is sampled by area):", "",
            "| scene | samples | MAE | P95 | P99 | bias | `without` spread | MAE ~ samples^k |",
            "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in results:
        k = slope(r["validation"])
        for v in r["validation"]:
            e = v["err"]
            out.append(f"| {r['name']} | {v['samples']} | {e['mae']:.5f} | {e['p95']:.5f} | "
                       f"{e['p99']:.5f} | {e['bias']:+.5f} | {v['without_rel_range']:.1e} | "
                       f"{k:.2f} |")
    out += ["", "The definition gap on the penumbra points: Cycles weighted (the irradiance "
            "ratio, what a renderer computes) against Cycles unweighted, same samples and seed:",
            "", "| scene | samples | gap MAE / P95 / P99 / max | weighted vs reference MAE | "
            "weighted `without` spread |", "|---|---:|---|---:|---:|"]
    for r in results:
        g, e = r["gap"], r["gap"]["gap"]
        out.append(f"| {r['name']} | {g['samples']} | {f(e)} / {e['max']:.4f} | "
                   f"{g['weighted_vs_reference']['mae']:.4f} | {g['without_rel_range']:.2f} |")
    out += ["", f"Blender start-up (a trivial run, median): {startup:.2f} CPU-s per process."]
    return "\n".join(out)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--pdsm", default="build/client/pdsm")
    p.add_argument("--blender", default="blender")
    p.add_argument("--out", default="/tmp/cycles_compare")
    p.add_argument("--shared", default=os.environ.get("PDSM_SHARED", "../shared"),
                   help="holds scenes/dragon.json (relative: to the repository's root)")
    p.add_argument("--scenes", default="plates,sun_pillars,dragon")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--max-samples", type=int, default=8192)
    p.add_argument("--validate-samples", type=int, default=4096,
                   help="the validation sweep on penumbra points goes up to this count")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--grid", type=int, help="an NxN grid for every scene (quick checks)")
    args = p.parse_args()
    args.out = os.path.abspath(args.out)
    os.chdir(os.path.dirname(HERE))  # the repository's root: scene and default paths
    args.pdsm, args.shared = os.path.abspath(args.pdsm), os.path.abspath(args.shared)
    if not shutil.which(args.blender):
        sys.exit(f"{args.blender} not found: apt-get install blender "
                 "(or PDSM_WITH_BLENDER=1 deploy/install_deps.sh)")
    if not os.access(args.pdsm, os.X_OK):
        sys.exit(f"{args.pdsm} not found: build pdsm first, or give --pdsm")
    os.makedirs(args.out, exist_ok=True)
    started = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    load_before = loadavg()
    startup = median([run_timed([args.blender, "-b", "--factory-startup", "--python-expr",
                                 "import bpy"]) for _ in range(args.repeat)])
    results = []
    for name, scene, grid, crop, configs in SCENES:
        if name not in args.scenes.split(","):
            continue
        if scene is None:
            scene = os.path.join(args.shared, "scenes", "dragon.json")
            if not os.path.exists(scene):
                print(f"{name}: skipped, {scene} is absent (set --shared)", file=sys.stderr)
                continue
        results.append(compare(args, name, scene, args.grid or grid, crop, configs))
    header = (f"Measured {started}, load average {load_before} before, {loadavg()} after; "
              f"{os.cpu_count()} cores, --threads {args.threads}, CPU-s medians of {args.repeat} (pdsm bakes, Cycles grid bakes).")
    text = report(results, startup, header)
    open(os.path.join(args.out, "summary.md"), "w").write(text + "\n")
    json.dump(results, open(os.path.join(args.out, "results.json"), "w"), indent=1)
    print(text)


if __name__ == "__main__":
    main()
