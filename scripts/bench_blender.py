"""Peers in the same sitting: Blender's cloth next to `drapery bench` on the same scenes.

Run it with a Python that has the `bpy` module (Blender as a Python module, from PyPI):

    bash scripts/bench-peers.sh                # installs bpy into target/bpy-venv if missing
    target/bpy-venv/bin/python scripts/bench_blender.py --scenes hang-64,drape-64 --runs 3
    bash scripts/bench-peers.sh --runs 5 --tolerance 1e-3,1e-2   # drapery also at Blender's 1e-2

For every scene and every run it runs `drapery bench --scenes SCENE --runs 1` and then the same
scene in Blender, one after the other (the machine is shared and noisy, so the two sides are
alternated run by run rather than one block after the other), and prints the median ms per frame
of each side and their ratio.

The scenes are those of crates/drapery/src/presets.rs: a 1 m square cloth of n x n vertices,
0.1 kg, stretch 1000 N/m, shear 100 N/m, bend 1 N/m, damping 0.01 N s/m per spring, no air
drag, gravity 9.81 m/s^2, dt = 1/60 s and one implicit step per frame. `hang-N` hangs from its
two top corners; `drape-N` starts horizontal 0.4 m above the centre of a fixed sphere of radius
0.3 m, with collisions (thickness 5 mm, self-collision, friction 0.3). Blender is z-up, drapery
y-up: the scenes are built turned accordingly (drapery's y is Blender's z).

How drapery's numbers become Blender's (from Blender's source: blenkernel/intern/cloth.cc,
simulation/intern/SIM_mass_spring.cc and implicit_blender.cc):

* Time. Blender's cloth solver runs in its own time unit: one frame is `time_scale` units
  (independent of the scene's fps), a step is `time_scale / quality` units, and gravity enters
  as `0.001 * g` per unit squared. So one unit is tau = sqrt(0.001) s = 31.6 ms of physical
  time (checked here: a free cloth at quality 1 falls 0.00981 m in its first frame, whatever
  the fps). One step of 1/60 s per frame is `quality = 1`, `time_scale = (1/60) / tau`.
* Mass. `settings.mass` is the mass of each vertex in kg: 0.1 / n^2. (drapery lumps an area
  density of 0.1 kg/m^2 to the vertices, so its border vertices are lighter; the total is the
  same 0.1 kg.)
* Springs. A structural spring's force is `(tension / L_avg) * (length - rest)` in Blender's
  units (kg m / tau^2), where L_avg is the mean rest length of the mesh edges; one such unit
  of force is 1/tau^2 = 1000 N. So a spring of k N/m needs `tension = k * tau^2 * L_avg`, and
  the same for shear (`shear = k_shear * tau^2 * L_avg`). Damping along a spring is
  `damping * (relative velocity . direction)` with the velocity in m/tau, so c N s/m needs
  `damping = c * tau`.
* Bending. With `bending_model = 'LINEAR'` (used here: every force then has its Jacobian in
  the implicit solve, as in drapery) Blender's bend springs resist compression only, with the
  Choi-Ko law; for the compressions of a cloth this small it is the linear branch
  `cb * (length - rest)` with `cb = bending * bending_damping / (20 * L_avg)`. With
  `bending_damping = 1`, a bend spring of k_b N/m needs `bending = 20 * k_b * tau^2 * L_avg`.
* Collisions. The cloth keeps `distance_min` from the collider plus the collider's
  `thickness_outer` (times 8/9); two cloth layers keep `2 * self_distance_min` (times 8/9).
  Friction is `friction * 0.01` (Coulomb): 0.3 is 30.

What is not matched (see BENCHMARKS.md): Blender's structural and shear springs push back
only when stretched (drapery's resist compression too); its linear bend springs also join
vertices two apart along the quad diagonals and resist only compression; it solves in single
precision with unpreconditioned CG to a relative residual of 1e-2 and at most 100 iterations
(drapery: f64, multigrid-preconditioned CG to 1e-3); its collisions are impulses after the
solve against a triangulated sphere (drapery: penalty forces inside the solve against the
analytic sphere, plus its fail-safe). Blender's frame also includes its depsgraph evaluation
and the point cache write (in memory).
"""

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time

TAU = math.sqrt(0.001)  # Blender cloth's time unit, in seconds (gravity enters as 0.001 g)
DT = 1.0 / 60.0  # drapery's step, s

# drapery's preset (crates/drapery/src/presets.rs)
MASS = 0.1  # kg, whole cloth
STRETCH = 1000.0  # N/m
SHEAR = 100.0  # N/m
BEND = 1.0  # N/m
DAMPING = 0.01  # N s/m per spring
THICKNESS = 0.005  # m
FRICTION = 0.3
SPHERE_RADIUS = 0.3  # m
WARM_UP = {"hang": 5, "drape": 30}  # drapery's warm-up frames per kind


def parse_scene(name):
    kind, _, n = name.partition("-")
    if kind not in WARM_UP or not n.isdigit() or int(n) < 2:
        raise SystemExit(f"scene '{name}': expected hang-N or drape-N with N >= 2")
    return kind, int(n)


def blender_settings(n):
    """Blender cloth settings equal to drapery's preset at n x n vertices (see the docstring)."""
    l_avg = 1.0 / (n - 1)  # every mesh edge of the grid has this rest length
    return {
        "quality": 1,
        "time_scale": DT / TAU,
        "mass": MASS / (n * n),
        "air_damping": 0.0,
        "bending_model": "LINEAR",
        "tension_stiffness": STRETCH * TAU**2 * l_avg,
        "tension_stiffness_max": STRETCH * TAU**2 * l_avg,
        "compression_stiffness": STRETCH * TAU**2 * l_avg,
        "compression_stiffness_max": STRETCH * TAU**2 * l_avg,
        "shear_stiffness": SHEAR * TAU**2 * l_avg,
        "shear_stiffness_max": SHEAR * TAU**2 * l_avg,
        "bending_damping": 1.0,
        "bending_stiffness": 20.0 * BEND * TAU**2 * l_avg,
        "bending_stiffness_max": 20.0 * BEND * TAU**2 * l_avg,
        "tension_damping": DAMPING * TAU,
        "compression_damping": DAMPING * TAU,
        "shear_damping": DAMPING * TAU,
    }


def build_scene(kind, n):
    """A fresh Blender scene with the cloth (and the sphere for drape); returns (scene, cloth)."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 60
    scene.gravity = (0.0, 0.0, -9.81)
    scene.frame_start = 1
    scene.frame_end = 100000
    # row 0 first, columns left to right, as drapery's Mesh::grid: vertex 0 and n-1 are the top
    # corners of the hanging cloth
    verts = []
    for r in range(n):
        for c in range(n):
            u = c / (n - 1) - 0.5
            v = 0.5 - r / (n - 1)
            if kind == "hang":
                verts.append((u, 0.0, 1.0 + v))  # vertical, in the xz plane
            else:
                verts.append((u, v, 0.4))  # horizontal, 0.4 m above the sphere's centre
    faces = [
        (r * n + c, (r + 1) * n + c, (r + 1) * n + c + 1, r * n + c + 1)
        for r in range(n - 1)
        for c in range(n - 1)
    ]
    mesh = bpy.data.meshes.new("cloth")
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    cloth = bpy.data.objects.new("cloth", mesh)
    scene.collection.objects.link(cloth)
    mod = cloth.modifiers.new("cloth", "CLOTH")
    s = mod.settings
    for key, value in blender_settings(n).items():
        setattr(s, key, value)
    s.effector_weights.gravity = 1.0
    c = mod.collision_settings
    if kind == "hang":
        group = cloth.vertex_groups.new(name="pin")
        group.add([0, n - 1], 1.0, "REPLACE")
        s.vertex_group_mass = "pin"
        c.use_collision = False
        c.use_self_collision = False
    else:
        bpy.ops.mesh.primitive_uv_sphere_add(
            segments=64, ring_count=32, radius=SPHERE_RADIUS, location=(0.0, 0.0, 0.0)
        )
        sphere = bpy.context.active_object
        sphere.modifiers.new("collision", "COLLISION")
        sphere.collision.thickness_outer = 0.001  # Blender's smallest
        sphere.collision.cloth_friction = FRICTION * 100.0
        c.use_collision = True
        c.distance_min = THICKNESS - 0.001
        c.use_self_collision = True
        c.self_distance_min = THICKNESS / 2.0
        c.self_friction = FRICTION * 100.0
    mod.point_cache.frame_start = 1
    mod.point_cache.frame_end = 100000
    scene.frame_set(1)
    return scene, cloth


def lowest(scene, cloth):
    """Lowest vertex height (Blender z = drapery y) of the evaluated cloth, m."""
    import bpy

    depsgraph = bpy.context.evaluated_depsgraph_get()
    ev = cloth.evaluated_get(depsgraph)
    return min(v.co.z for v in ev.data.vertices)


def blender_run(name, frames, warm_up=None):
    """One run of a scene in Blender: ms per timed frame, the CG iterations of each timed step
    (Blender stops at 100), and the lowest height at the end."""
    import bpy

    kind, n = parse_scene(name)
    scene, cloth = build_scene(kind, n)
    warm = WARM_UP[kind] if warm_up is None else warm_up
    frame = 1
    for _ in range(warm):
        frame += 1
        scene.frame_set(frame)
    seconds, iterations = 0.0, []
    for _ in range(frames):
        frame += 1
        start = time.perf_counter()
        scene.frame_set(frame)
        seconds += time.perf_counter() - start
        # one step per frame: the frame's maximum is that step's count (read outside the timing)
        ev = cloth.evaluated_get(bpy.context.evaluated_depsgraph_get())
        result = ev.modifiers["cloth"].solver_result
        if result is None:
            raise RuntimeError(f"{name}: Blender did not step frame {frame} (no solver result)")
        iterations.append(result.max_iterations)
    return seconds * 1e3 / frames, iterations, lowest(scene, cloth)


def drapery_run(binary, name, frames, tolerance, warm_up=None):
    """One run of `drapery bench` on one scene: its ms per frame and CG iterations per step."""
    cmd = [binary, "bench", "--scenes", name, "--frames", str(frames), "--runs", "1"]
    cmd += ["--tolerance", str(tolerance)]
    if warm_up is not None:
        cmd += ["--warm-up", str(warm_up)]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    for line in out.splitlines():
        cols = line.split()
        if cols and cols[0] == name:
            return float(cols[2]), float(cols[4])
    raise RuntimeError(f"no line for {name} in drapery bench's output:\n{out}")


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scenes", default="hang-64,drape-64,hang-128,drape-128")
    p.add_argument("--frames", type=int, default=10, help="timed frames per run")
    p.add_argument("--runs", type=int, default=3, help="runs per scene and side (median)")
    p.add_argument("--warm-up", type=int, default=None, help="untimed frames (default: drapery's)")
    p.add_argument(
        "--tolerance",
        default="1e-3",
        help="drapery's PCG tolerance; a comma-separated list gives one drapery column each",
    )
    p.add_argument("--drapery", default=os.path.join(root, "target", "release", "drapery"))
    p.add_argument("--json", help="also write the runs to this file")
    args = p.parse_args()
    if args.frames < 1 or args.runs < 1:
        raise SystemExit("--frames and --runs must be at least 1")
    scenes = args.scenes.split(",")
    for s in scenes:
        parse_scene(s)
    tolerances = [float(t) for t in args.tolerance.split(",")]
    import bpy

    print(
        f"Blender {bpy.app.version_string} (bpy), Python {sys.version.split()[0]}; "
        f"{args.frames} timed frames x {args.runs} runs per scene and side, drapery and Blender "
        f"alternated run by run; drapery tolerance {', '.join(f'{t:g}' for t in tolerances)}",
        flush=True,
    )
    results = {}
    for s in scenes:
        kind, n = parse_scene(s)
        r = {"vertices": n * n, "drapery": {t: [] for t in tolerances}, "blender": []}
        for run in range(args.runs):
            line = f"  {s} run {run + 1}:"
            for t in tolerances:
                ms, cg = drapery_run(args.drapery, s, args.frames, t, args.warm_up)
                r["drapery"][t].append({"ms": ms, "cg": cg})
                line += f" drapery@{t:g} {ms:.2f} ms/frame ({cg:.1f} CG/step),"
            ms, its, z = blender_run(s, args.frames, args.warm_up)
            r["blender"].append({"ms": ms, "cg": its, "lowest": z})
            line += f" Blender {ms:.2f} ms/frame (CG/step {its}, lowest cloth point {z:.3f} m)"
            print(line, flush=True)
        results[s] = r
    med = statistics.median
    print()
    head = f"{'scene':<10} {'vertices':>8}"
    for t in tolerances:
        head += f" {'drapery@' + format(t, 'g'):>14} {'CG':>6}"
    head += f" {'Blender':>10} {'CG':>6} {'at cap':>7}"
    for t in tolerances:
        head += f" {'B/d@' + format(t, 'g'):>10}"
    print(head + "   (ms/frame; CG: iterations per step, median; at cap: Blender steps that hit 100)")
    for s, r in results.items():
        b = med([x["ms"] for x in r["blender"]])
        its = [i for x in r["blender"] for i in x["cg"]]
        line = f"{s:<10} {r['vertices']:>8}"
        ds = []
        for t in tolerances:
            d = med([x["ms"] for x in r["drapery"][t]])
            ds.append(d)
            line += f" {d:>14.2f} {med([x['cg'] for x in r['drapery'][t]]):>6.1f}"
        line += f" {b:>10.2f} {med(its):>6.0f} {sum(i >= 100 for i in its):>3}/{len(its):<3}"
        for d in ds:
            line += f" {b / d:>10.2f}"
        print(line)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"blender": bpy.app.version_string, "results": results}, f, indent=1)


if __name__ == "__main__":
    main()
