"""Rebuild a pdsm scene in Blender and bake, with Cycles, the fraction of the light hidden from
points on its ground: an independent anchor for pdsm's attenuation (issues #11 item 8, #15
item 5; docs/accuracy.md, "An independent anchor: Blender Cycles").

  blender -b --factory-startup --python bench/cycles/pdsm_scene_to_cycles.py -- \
      SCENE.json --out A.csv (--points PTS.csv | --grid N [--crop SIDE] [--points-out PTS.csv])
      [--samples 256] [--weighting unweighted|weighted] [--threads 2] [--seed 0]
      [--light NAME] [--json STATS.json] [--repeat 1]

The scene: casters (CASTER_ONLY, CASTER_AND_RECEIVER meshes) in white diffuse; RECEIVER_ONLY
meshes left out (they cast nothing); no world light; no bounces (max_bounces 0: direct light
only); light sampling threshold and clamping off. A rect or disk light becomes a Blender area
light of that shape (single-sided, facing `normal`; a spot becomes its disk), a sun a sun lamp
with that angle. The points lie on the ground (the first RECEIVER_ONLY mesh, planar).

How irradiance is read at exact points: every point gets its own tiny triangle (side 4e-6 of
the ground's extent) in the ground's plane, facing the light, that covers the centre of one
texel of a float image; a Cycles bake of type DIFFUSE with pass_filter {'DIRECT'} (direct
light, no albedo) onto that image gives the direct irradiance at the point (the bake's
sub-texel jitter moves it by at most half the triangle). Baked twice, with the casters and
without them (unlinked), with the same seed, so both bakes draw the same light samples;
A = 1 - with / without.

Weighting (docs/accuracy.md): `weighted` is what a renderer computes, the irradiance ratio
(light points weighted by cos_light cos_receiver / r^2; a sun's directions by cos_receiver).
`unweighted` is pdsm's attenuation, the plain fraction of the light's area (sun: of its cone)
hidden: the light's emission strength is set to r^2 / (cos_light cos_receiver) (sun:
1 / cos_receiver) in its node tree (Light Path: Ray Length; Geometry: Incoming, Normal;
cos_receiver = |Incoming . ground normal|), which cancels the weighting exactly for points on
the ground plane.

Output: A.csv, `x,y,z,A` per point as `pdsm query` prints it (`nan` where nothing of the light
reaches the point); --points-out writes the grid's points as `x,y,z`; --json writes the
samples, points, CPU seconds (the process before the script ran = Blender's start-up, scene
build, each bake: time.process_time, every thread; with --repeat, the bake with casters runs
that many times and its median is reported) and the spread of the `without` bake.
"""
import argparse
import array
import json
import math
import os
import resource
import sys
import time

import bpy
from mathutils import Matrix, Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pdsm_scene  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="pdsm_scene_to_cycles.py")
    p.add_argument("scene")
    p.add_argument("--out", required=True, help="x,y,z,A CSV")
    p.add_argument("--points", help="x,y,z CSV of points on the ground")
    p.add_argument("--grid", type=int, help="bake an NxN grid of texel centres on the ground")
    p.add_argument("--crop", type=float, help="grid over a square of this side around the casters")
    p.add_argument("--points-out", help="write the grid's points here (x,y,z)")
    p.add_argument("--samples", type=int, default=256)
    p.add_argument("--weighting", choices=("unweighted", "weighted"), default="unweighted")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--light", help="name of the light, for a scene of several")
    p.add_argument("--json", help="write samples, points and CPU seconds here")
    p.add_argument("--repeat", type=int, default=1,
                   help="bake with casters this many times; its CPU-s is their median")
    args = p.parse_args(argv)
    if (args.points is None) == (args.grid is None):
        p.error("give --points or --grid")
    return args


def cpu_seconds():
    """user + system CPU of this process so far, every thread (Cycles' included)."""
    return time.process_time()


def reset_blender(args):
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    cy = sc.cycles
    cy.device = "CPU"
    cy.samples = args.samples
    cy.seed = args.seed
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.max_bounces = 0  # direct light only
    for bounces in ("diffuse", "glossy", "transmission", "volume", "transparent_max"):
        setattr(cy, bounces + ("" if bounces == "transparent_max" else "_bounces"), 0)
    cy.light_sampling_threshold = 0.0  # never drop a light sample for being dim
    cy.sample_clamp_direct = cy.sample_clamp_indirect = 0.0
    sc.render.threads_mode = "FIXED"
    sc.render.threads = args.threads
    world = bpy.data.worlds.new("black")  # no world light
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    sc.world = world
    return sc


def white_diffuse(name):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.remove(nodes["Principled BSDF"])
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (1, 1, 1, 1)
    mat.node_tree.links.new(diffuse.outputs["BSDF"], nodes["Material Output"].inputs["Surface"])
    return mat


def add_mesh(name, verts, tris, material, uvs=None):
    """A mesh object from world-space vertices (float32 in Blender) and triangles."""
    me = bpy.data.meshes.new(name)
    me.vertices.add(len(verts))
    me.vertices.foreach_set("co", array.array("f", (c for v in verts for c in v)))
    me.loops.add(3 * len(tris))
    me.loops.foreach_set("vertex_index", array.array("i", (i for t in tris for i in t)))
    me.polygons.add(len(tris))
    me.polygons.foreach_set("loop_start", array.array("i", range(0, 3 * len(tris), 3)))
    me.polygons.foreach_set("loop_total", array.array("i", [3]) * len(tris))
    if uvs is not None:
        me.uv_layers.new().data.foreach_set("uv", array.array("f", uvs))
    me.update()
    me.validate()
    me.materials.append(material)
    obj = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def frame_matrix(x, y, z, origin):
    """Object matrix whose local X, Y, Z axes are the given world vectors."""
    m = Matrix.Identity(4)
    for col, axis in enumerate((x, y, z)):
        for row in range(3):
            m[row][col] = axis[row]
    m.translation = Vector(origin)
    return m


def add_light(scene, weighting):
    """The scene's light as a Blender light; emission that cancels the weighting if asked."""
    kind, spec = scene.kind, scene.light[scene.kind]
    if kind == "sphere":
        raise ValueError("sphere lights are not rebuilt (no planar emitter to compare with)")
    if kind == "sun":
        light = bpy.data.lights.new("pdsm_light", "SUN")
        light.angle = math.radians(spec["angularDiameterDeg"])  # Blender's angle: the diameter
        n, origin = pdsm_scene.normalize(spec["direction"]), (0, 0, 0)
    else:
        light = bpy.data.lights.new("pdsm_light", "AREA")
        n, origin = pdsm_scene.normalize(spec["normal"]), spec["center"]
        light.energy = 1000.0
        if kind == "rect":
            light.shape, (light.size, light.size_y) = "RECTANGLE", spec["size"]
        else:  # disk, and a spot: its shadows are its disk's (docs/scene_format.md)
            light.shape, light.size = "DISK", 2 * spec["radius"]
    light.cycles.use_multiple_importance_sampling = False  # light samples only: no BSDF hits
    light.cycles.cast_shadow = True
    # Blender lights shine along local -Z. Rect: local X along u, Y along -v (X x Y = -n).
    up = spec.get("up") or ([0, 0, 1] if abs(n[2]) < 0.9 else [1, 0, 0])
    v = pdsm_scene.normalize(pdsm_scene.sub(up, pdsm_scene.scale(n, pdsm_scene.dot(up, n))))
    u = pdsm_scene.cross(v, n)
    obj = bpy.data.objects.new("pdsm_light", light)
    obj.matrix_world = frame_matrix(u, pdsm_scene.scale(v, -1), pdsm_scene.scale(n, -1), origin)
    bpy.context.scene.collection.objects.link(obj)
    if weighting == "unweighted":
        unweighted_emission(light, scene.ground_normal, kind == "sun")
    return obj


def unweighted_emission(light, ground_normal, sun):
    """Emission strength r^2 / (cos_light cos_receiver), sun: 1 / cos_receiver.

    In a light's shader Cycles gives Incoming = the unit direction from the light point to the
    shaded point, Normal = the light's normal, Ray Length = their distance r. A light point's
    contribution to irradiance is L cos_light cos_receiver / r^2 dA (sun: L cos_receiver
    dw), so with this L every point of the light counts the same and the baked irradiance is
    proportional to the unoccluded area (cone). cos_receiver = |Incoming . ground normal|:
    exact for every point on the ground plane, and only there.
    """
    light.use_nodes = True
    tree = light.node_tree
    nodes, link = tree.nodes, tree.links.new
    geometry = nodes.new("ShaderNodeNewGeometry")
    path = nodes.new("ShaderNodeLightPath")

    def math_node(op, a, b=None):
        node = nodes.new("ShaderNodeMath")
        node.operation = op
        for socket, value in zip(node.inputs, (a, b)):
            if value is None:
                continue
            if isinstance(value, float):
                socket.default_value = value
            else:
                link(value, socket)
        return node.outputs[0]

    def abs_dot(vector_out, constant=None, other=None):
        node = nodes.new("ShaderNodeVectorMath")
        node.operation = "DOT_PRODUCT"
        link(vector_out, node.inputs[0])
        if constant is not None:
            node.inputs[1].default_value = constant
        else:
            link(other, node.inputs[1])
        return math_node("ABSOLUTE", node.outputs["Value"])

    cos_receiver = abs_dot(geometry.outputs["Incoming"], constant=ground_normal)
    if sun:
        strength = math_node("DIVIDE", 1.0, cos_receiver)
    else:
        cos_light = abs_dot(geometry.outputs["Incoming"], other=geometry.outputs["Normal"])
        r2 = math_node("MULTIPLY", path.outputs["Ray Length"], path.outputs["Ray Length"])
        strength = math_node("DIVIDE", r2, math_node("MULTIPLY", cos_light, cos_receiver))
    link(strength, nodes["Emission"].inputs["Strength"])


def add_receivers(points, normal, axes, extent):
    """One tiny triangle per point, in the ground's plane, facing the light, each covering the
    centre of its own texel of a side x side image; the texel centre maps to the point."""
    side = max(1, math.ceil(math.sqrt(len(points))))
    h = 4e-6 * extent  # world size of a texel's footprint; float32 keeps ~1e-7 relative
    a, b = axes
    corners = ((-0.4, -0.4), (0.4, -0.4), (0.0, 0.4))  # texel-local offsets from its centre
    verts, tris, uvs = [], [], []
    for k, p in enumerate(points):
        i, j = k % side, k // side
        for du, dv in corners:
            verts.append(tuple(p[c] + h * (du * a[c] + dv * b[c]) for c in range(3)))
            uvs += [(i + 0.5 + du) / side, (j + 0.5 + dv) / side]
        tris.append((3 * k, 3 * k + 1, 3 * k + 2))
    assert pdsm_scene.dot(pdsm_scene.cross(a, b), normal) > 0  # counter-clockwise seen from the light
    mat = white_diffuse("receiver")
    image = bpy.data.images.new("irradiance", side, side, alpha=False, float_buffer=True)
    image.colorspace_settings.name = "Non-Color"
    node = mat.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    mat.node_tree.nodes.active = node  # the bake writes into the active image node
    return add_mesh("receivers", verts, tris, mat, uvs), image


def bake(receivers, image, count):
    """Direct diffuse light (no albedo) at the receivers' texels: irradiance up to a constant."""
    bpy.ops.object.select_all(action="DESELECT")
    receivers.select_set(True)
    bpy.context.view_layer.objects.active = receivers
    start = cpu_seconds()
    bpy.ops.object.bake(type="DIFFUSE", pass_filter={"DIRECT"}, margin=0, use_clear=True,
                        target="IMAGE_TEXTURES", save_mode="INTERNAL")
    seconds = cpu_seconds() - start
    pixels = array.array("f", [0.0]) * (image.size[0] * image.size[1] * 4)
    image.pixels.foreach_get(pixels)
    return [pixels[4 * k] for k in range(count)], seconds  # texel k = point k (row-major)


def main():
    args = parse_args()
    cpu_at_start = cpu_seconds()
    scene = pdsm_scene.Scene(args.scene, args.light)
    points = (pdsm_scene.read_points(args.points) if args.points
              else scene.ground_grid(args.grid, args.crop))
    if args.points_out:
        pdsm_scene.write_points(args.points_out, points)
    sc = reset_blender(args)
    casters = [add_mesh(f"caster{i}", v, t, white_diffuse("white"))
               for i, (v, t) in enumerate(scene.casters())]
    add_light(scene, args.weighting)
    _, ground_verts, _ = scene.ground()
    extent = max(max(c) - min(c) for c in zip(*ground_verts))
    receivers, image = add_receivers(points, scene.ground_normal, scene.ground_axes, extent)
    cpu_built = cpu_seconds()

    cpu_with = []
    for _ in range(args.repeat):  # the same image each time (same seed): only the time varies
        lit_with, seconds = bake(receivers, image, len(points))
        cpu_with.append(seconds)
    for obj in casters:
        sc.collection.objects.unlink(obj)
    lit_without, cpu_without = bake(receivers, image, len(points))
    hidden = [1.0 - w / wo if wo > 0 else math.nan for w, wo in zip(lit_with, lit_without)]
    pdsm_scene.write_points(args.out, points, hidden)

    usage = resource.getrusage(resource.RUSAGE_SELF)
    lit = [x for x in lit_without if x > 0]
    mean = sum(lit) / len(lit) if lit else math.nan
    stats = {
        "scene": args.scene, "weighting": args.weighting, "samples": args.samples,
        "points": len(points), "threads": args.threads, "light": scene.kind,
        "cpu_s": {"before_script": cpu_at_start, "build": cpu_built - cpu_at_start,
                  "bake_with": sorted(cpu_with)[(len(cpu_with) - 1) // 2],
                  "bake_with_runs": cpu_with, "bake_without": cpu_without,
                  "process": usage.ru_utime + usage.ru_stime},
        # Unweighted: `without` is the same at every point (the whole light), up to noise.
        "without_mean": mean,
        "without_rel_range": (max(lit) - min(lit)) / mean if lit else math.nan,
    }
    if args.json:
        json.dump(stats, open(args.json, "w"), indent=1)
    print("pdsm_scene_to_cycles:", json.dumps(stats), file=sys.stderr)


if __name__ == "__main__":
    try:
        main()
    except Exception:  # Blender would exit 0 after a Python error: make it fail
        import traceback
        traceback.print_exc()
        sys.stderr.flush()
        os._exit(1)
