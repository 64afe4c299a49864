#!/usr/bin/env python3
"""Writes examples/mannequin/ (a mannequin turning and raising its arms) and
examples/mannequin_walk/ (the same body in an A-pose, walking in place and turning), as OBJ
sequences.

The body is the zero level set of the signed distance to a smooth union (polynomial smooth
minimum, blend width 4 cm) of capsules and spheres: head, neck, shoulders, chest, hips, upper
arms, forearms, hands, thighs, shins and feet; 1.74 m tall, standing on y = 0, facing +z. It
is polygonized once per sequence, in that sequence's rest pose, by surface nets on a 3 cm grid
(one vertex per grid cell the surface crosses, at the mean of the crossings of the cell's
edges, projected onto the surface; one quad per grid edge the surface crosses, split along its
shorter diagonal): about 5 000 triangles, closed, watertight and wound counter-clockwise seen
from outside. The script checks that (and retries with a shifted grid if a grid face is
ambiguous). Each animation moves those vertices (same vertices and faces in every frame).

mannequin/: the arms hang at rest. They turn about the shoulders, sideways and up, by
65 (1 - cos(2 pi t / T)) / 2 degrees (from about 13 degrees away from the body to about 78,
and back), and the whole body turns about the vertical axis by 0.5 sin(2 pi t / T) rad;
period T = 2 s, 30 frames per second, 61 frames (t = 0 to 2 s, the last one the pose of the
first): mannequin_0001.obj ... mannequin_0061.obj. A vertex follows its arm with a weight that
is 1 on the arm and blends to 0 over the shoulder (linear blend skinning), so the armpit
stretches instead of tearing.

mannequin_walk/: the arms are turned 30 degrees further out about the shoulders before
polygonizing (an A-pose, hands about 0.66 m from the vertical axis: room for a skirt; they do
not move relative to the body). The body walks in place: with phase p = 2 pi t / 1 s and a
ramp r(t) rising smoothly (smoothstep) from 0 at t = 0 to 1 at 0.3 s, the right thigh swings
forward by 20 r sin p degrees about the hip axis (the horizontal line along x at y = 0.92 m,
z = 0) and the left one by the opposite angle; each shin bends back about the knee axis
(y = 0.50 m) by 45 r max(0, +-cos p)^2 degrees (right +, left -: the knee bends while its
leg swings forward). Skinning as for the arms: a vertex follows its thigh with a weight
blending from 0 at y = 0.95 m to 1 at 0.80 m (only within 0.3-0.4 m of the middle, so never
the hands), the right and left legs sharing it over |x| < 4 cm, and its shin with a weight
blending from 0 at y = 0.56 m to 1 at 0.44 m, the shin's turn applied before the thigh's. Each
frame the whole body is then lowered so that its lowest point stays on the ground (the lower
foot stands; the body bobs up to about 5 cm), and turned about the vertical axis by
90 (1 - cos(pi min(t, 1.6 s) / 1.6 s)) / 2 degrees: a quarter turn to its left, starting and
ending at rest, held from 1.6 s. 20 frames per second, 41 frames (t = 0 to 2 s, the first one
the rest pose), 6 decimals: mannequin_walk_0001.obj ... mannequin_walk_0041.obj.

Standard library only; run from anywhere:

    python3 scripts/make_mannequin.py [examples directory]
"""

import math
import os
import sys

PERIOD = 2.0
FPS = 30
FRAMES = 61
CELL = 0.03  # m, grid spacing
BLEND = 0.04  # m, smooth-union width
RAISE = math.radians(65.0)  # how far the arms go up
TURN = 0.5  # rad
# the walking sequence
WALK_FPS = 20
WALK_FRAMES = 41
A_POSE = math.radians(30.0)  # arms turned this much further out than at rest
STRIDE = 1.0  # s, one step of each leg
HIP = math.radians(20.0)  # hip flexion amplitude, forward and back
KNEE = math.radians(45.0)  # largest knee bend
GAIT_RAMP = 0.3  # s, the gait's amplitude grows from 0 to full over this time
HIP_Y, KNEE_Y = 0.92, 0.50  # m, heights of the hip and knee joints (axes along x, at z = 0)
YAW = math.radians(90.0)  # the walking body turns a quarter turn to its left
YAW_TIME = 1.6  # s, over this time (zero turning speed at both ends)

# (kind, data): capsules ("c", a, b, r), spheres ("s", c, r); `part` tags the arms
BODY = [
    ("head", ("s", (0.0, 1.62, 0.01), 0.11)),
    ("body", ("c", (0.0, 1.40, 0.0), (0.0, 1.52, 0.0), 0.05)),  # neck
    ("body", ("c", (-0.13, 1.37, 0.0), (0.13, 1.37, 0.0), 0.075)),  # shoulders
    ("body", ("c", (0.0, 1.02, 0.0), (0.0, 1.28, 0.0), 0.14)),  # chest
    ("body", ("c", (-0.08, 0.95, 0.0), (0.08, 0.95, 0.0), 0.11)),  # hips
]
for side in (-1.0, 1.0):
    BODY += [
        ("arm+" if side > 0 else "arm-",
         ("c", (side * 0.21, 1.37, 0.0), (side * 0.28, 1.10, 0.0), 0.045)),  # upper arm
        ("arm+" if side > 0 else "arm-",
         ("c", (side * 0.28, 1.10, 0.0), (side * 0.33, 0.86, 0.02), 0.038)),  # forearm
        ("arm+" if side > 0 else "arm-", ("s", (side * 0.345, 0.80, 0.02), 0.045)),  # hand
        ("body", ("c", (side * 0.09, 0.92, 0.0), (side * 0.11, 0.50, 0.0), 0.065)),  # thigh
        ("body", ("c", (side * 0.11, 0.50, 0.0), (side * 0.12, 0.10, 0.0), 0.045)),  # shin
        ("body", ("c", (side * 0.12, 0.05, -0.02), (side * 0.13, 0.05, 0.12), 0.045)),  # foot
    ]
SHOULDER = {1.0: (0.21, 1.37, 0.0), -1.0: (-0.21, 1.37, 0.0)}


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    return math.sqrt(dot(a, a))


def prim_distance(prim, p):
    if prim[0] == "s":
        return norm(sub(p, prim[1])) - prim[2]
    _, a, b, r = prim
    ab, ap = sub(b, a), sub(p, a)
    s = max(0.0, min(1.0, dot(ap, ab) / dot(ab, ab)))
    return norm(sub(ap, (ab[0] * s, ab[1] * s, ab[2] * s))) - r


def smin(a, b, k):
    h = max(k - abs(a - b), 0.0) / k
    return min(a, b) - h * h * k * 0.25


def parts_distance(p, body=BODY):
    """Smooth-union distance of the body without the arms, and of each arm."""
    d = {"head": None, "body": None, "arm+": None, "arm-": None}
    for part, prim in body:
        key = "body" if part == "head" else part
        v = prim_distance(prim, p)
        d[key] = v if d[key] is None else smin(d[key], v, BLEND)
    return d["body"], d["arm+"], d["arm-"]


def sdf(p, body=BODY):
    trunk, right, left = parts_distance(p, body)
    return smin(smin(trunk, right, BLEND), left, BLEND)


def gradient(p, body):
    e = 1e-5
    return tuple(
        (sdf(tuple(p[j] + (e if j == i else 0.0) for j in range(3)), body)
         - sdf(tuple(p[j] - (e if j == i else 0.0) for j in range(3)), body)) / (2 * e)
        for i in range(3)
    )


def surface_nets(origin, body, lo, hi):
    n = [int(math.ceil((hi[i] - lo[i]) / CELL)) + 1 for i in range(3)]
    o = tuple(lo[i] + origin[i] for i in range(3))
    point = lambda i, j, k: (o[0] + i * CELL, o[1] + j * CELL, o[2] + k * CELL)
    f = {}
    for i in range(n[0]):
        for j in range(n[1]):
            for k in range(n[2]):
                f[i, j, k] = sdf(point(i, j, k), body)
    corners = [(a, b, c) for a in (0, 1) for b in (0, 1) for c in (0, 1)]
    cube_edges = [(u, v) for u in range(8) for v in range(u + 1, 8)
                  if sum(abs(corners[u][t] - corners[v][t]) for t in range(3)) == 1]
    verts, index = [], {}
    for i in range(n[0] - 1):
        for j in range(n[1] - 1):
            for k in range(n[2] - 1):
                vals = [f[i + a, j + b, k + c] for a, b, c in corners]
                if all(v < 0 for v in vals) or all(v >= 0 for v in vals):
                    continue
                acc, cnt = [0.0, 0.0, 0.0], 0
                for u, v in cube_edges:
                    fu, fv = vals[u], vals[v]
                    if (fu < 0) != (fv < 0):
                        s = fu / (fu - fv)
                        pu = point(i + corners[u][0], j + corners[u][1], k + corners[u][2])
                        pv = point(i + corners[v][0], j + corners[v][1], k + corners[v][2])
                        for t in range(3):
                            acc[t] += pu[t] + s * (pv[t] - pu[t])
                        cnt += 1
                p = tuple(a / cnt for a in acc)
                # one projection step onto the surface, kept within half a cell
                g = gradient(p, body)
                gg = dot(g, g)
                if gg > 0:
                    step = sdf(p, body) / gg
                    move = (g[0] * step, g[1] * step, g[2] * step)
                    m = norm(move)
                    if m > 0.5 * CELL:
                        move = tuple(c * 0.5 * CELL / m for c in move)
                    p = sub(p, move)
                index[i, j, k] = len(verts)
                verts.append(p)
    tris = []
    for (i, j, k), f0 in f.items():
        for a in range(3):
            q = [i, j, k]
            q[a] += 1
            f1 = f.get(tuple(q))
            if f1 is None or (f0 < 0) == (f1 < 0):
                continue
            u, v = (a + 1) % 3, (a + 2) % 3
            cells = []
            for du, dv in ((-1, -1), (0, -1), (0, 0), (-1, 0)):
                c = [i, j, k]
                c[u] += du
                c[v] += dv
                cells.append(index[tuple(c)])
            if f0 >= 0:  # outside at the lower end: the outward normal points along -a
                cells.reverse()
            c0, c1, c2, c3 = cells
            if norm(sub(verts[c0], verts[c2])) <= norm(sub(verts[c1], verts[c3])):
                tris += [(c0, c1, c2), (c0, c2, c3)]
            else:
                tris += [(c0, c1, c3), (c1, c2, c3)]
    return verts, tris


def closed(tris):
    directed = {}
    for a, b, c in tris:
        for e in ((a, b), (b, c), (c, a)):
            directed[e] = directed.get(e, 0) + 1
    return all(n == 1 and directed.get((b, a)) == 1 for (a, b), n in directed.items())


def volume(verts, tris):
    return sum(dot(verts[a], cross(verts[b], verts[c])) for a, b, c in tris) / 6.0


def smoothstep(e0, e1, x):
    s = max(0.0, min(1.0, (x - e0) / (e1 - e0)))
    return s * s * (3.0 - 2.0 * s)


def arm_weights(verts):
    """Per vertex: (side, weight) of the arm it follows."""
    out = []
    for p in verts:
        body, right, left = parts_distance(p)
        side, arm = (1.0, right) if right < left else (-1.0, left)
        # membership: 1 where the arm is clearly the nearer part, 0 where the body is
        member = max(0.0, min(1.0, 0.5 + (body - arm) / (2.0 * BLEND)))
        # along the arm from the shoulder: 0 above the joint, 1 past it
        s = SHOULDER[side]
        axis = sub((side * 0.28, 1.10, 0.0), s)
        along = dot(sub(p, s), axis) / norm(axis)
        out.append((side, member * smoothstep(-0.03, 0.06, along)))
    return out


def rotate_z(p, c, angle):
    x, y = p[0] - c[0], p[1] - c[1]
    ca, sa = math.cos(angle), math.sin(angle)
    return (c[0] + ca * x - sa * y, c[1] + sa * x + ca * y, p[2])


def turn_y(p, angle):
    """`p` turned by `angle` about the vertical axis (counter-clockwise seen from above)."""
    ct, st = math.cos(angle), math.sin(angle)
    return (ct * p[0] + st * p[2], p[1], -st * p[0] + ct * p[2])


def pose(rest, weights, t):
    w = 2.0 * math.pi * t / PERIOD
    raise_by = RAISE * 0.5 * (1.0 - math.cos(w))
    turn = TURN * math.sin(w)
    out = []
    for p, (side, wt) in zip(rest, weights):
        if wt > 0.0:
            r = rotate_z(p, SHOULDER[side], side * raise_by)
            p = tuple((1.0 - wt) * p[i] + wt * r[i] for i in range(3))
        out.append(turn_y(p, turn))
    return out


def a_pose_body():
    """BODY with each arm turned A_POSE further from the body about its shoulder."""
    out = []
    for part, prim in BODY:
        if part.startswith("arm"):
            c, a = SHOULDER[1.0 if part == "arm+" else -1.0], (1.0 if part == "arm+" else -1.0)
            turn = lambda q: rotate_z(q, c, a * A_POSE)
            prim = ("s", turn(prim[1]), prim[2]) if prim[0] == "s" else \
                ("c", turn(prim[1]), turn(prim[2]), prim[3])
        out.append((part, prim))
    return out


def flex(p, pivot_y, angle):
    """`p` turned about the horizontal line z = 0, y = pivot_y (along x) by `angle`; positive
    angles swing the points below the line forward (+z)."""
    dy, dz = p[1] - pivot_y, p[2]
    ca, sa = math.cos(angle), math.sin(angle)
    return (p[0], pivot_y + ca * dy + sa * dz, -sa * dy + ca * dz)


def leg_weights(verts):
    """Per vertex: (right leg, left leg, shin) weights. A vertex follows its thigh fully below
    y = 0.80 m and not at all above the hip joints (0.95 m), blending linearly (smoothstep)
    between; the two legs share the middle (|x| < 4 cm); the A-pose hands, beyond |x| = 0.3 m,
    never follow a leg. The shin's weight blends from 0 to 1 over the knee, y = 0.56 to 0.44 m."""
    out = []
    for x, y, _ in verts:
        leg = smoothstep(0.95, 0.80, y) * smoothstep(0.40, 0.30, abs(x))
        right = smoothstep(-0.04, 0.04, x)
        out.append((leg * right, leg * (1.0 - right), smoothstep(0.56, 0.44, y)))
    return out


def walk_angles(t):
    """(hip flexion of the right and left thighs, knee bend of the right and left shins, turn
    about the vertical axis), in radians, at time t."""
    ramp = smoothstep(0.0, GAIT_RAMP, t)
    phase = 2.0 * math.pi * t / STRIDE
    hip = HIP * ramp * math.sin(phase)
    knee_r = KNEE * ramp * max(0.0, math.cos(phase)) ** 2
    knee_l = KNEE * ramp * max(0.0, -math.cos(phase)) ** 2
    turn = YAW * 0.5 * (1.0 - math.cos(math.pi * min(t, YAW_TIME) / YAW_TIME))
    return (hip, -hip), (knee_r, knee_l), turn


def walk_pose(rest, weights, t, ground):
    hips, knees, turn = walk_angles(t)
    out = []
    for p, (wr, wl, wk) in zip(rest, weights):
        q = list(p)
        for w, hip, knee in ((wr, hips[0], knees[0]), (wl, hips[1], knees[1])):
            if w > 0.0:
                shin = flex(p, KNEE_Y, -knee)
                leg = flex(tuple(p[i] + wk * (shin[i] - p[i]) for i in range(3)), HIP_Y, hip)
                for i in range(3):
                    q[i] += w * (leg[i] - p[i])
        out.append(q)
    drop = ground - min(q[1] for q in out)  # the lower foot stays on the ground
    return [turn_y((q[0], q[1] + drop, q[2]), turn) for q in out]


def polygonize(body, lo, hi):
    """The closed, outward-wound surface-nets mesh of `body` in the box lo–hi."""
    for shift in ((0.0013, 0.0007, 0.0011), (0.006, 0.004, 0.009), (0.011, 0.017, 0.003),
                  (0.0021, 0.0093, 0.0057)):
        rest, tris = surface_nets(shift, body, lo, hi)
        if closed(tris):
            break
        print(f"grid shift {shift}: ambiguous faces, retrying", file=sys.stderr)
    else:
        raise SystemExit("no closed mesh")
    if volume(rest, tris) <= 0.0:
        raise SystemExit("mesh wound inward")
    return rest, tris


def write_sequence(out_dir, stem, title, frames, fps, tris, poser, digits):
    os.makedirs(out_dir, exist_ok=True)
    faces = "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in tris)
    for k in range(frames):
        t = k / fps
        verts = poser(t)
        head = [
            f"# {title} (closed, outward winding), "
            f"frame {k + 1} of {frames}, t = {t:.6f} s\n",
            "# Generated by scripts/make_mannequin.py\n",
        ]
        body = [f"v {x:.{digits}f} {y:.{digits}f} {z:.{digits}f}\n" for x, y, z in verts]
        with open(os.path.join(out_dir, f"{stem}_{k + 1:04d}.obj"), "w",
                  encoding="ascii", newline="\n") as fh:
            fh.write("".join(head + body) + faces)
    print(f"{frames} frames, {len(verts)} vertices, {len(tris)} triangles -> {out_dir}")


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    default = os.path.normpath(os.path.join(here, "..", "examples"))
    examples = sys.argv[1] if len(sys.argv) > 1 else default

    rest, tris = polygonize(BODY, (-0.45, -0.05, -0.15), (0.45, 1.80, 0.25))
    weights = arm_weights(rest)
    write_sequence(os.path.join(examples, "mannequin"), "mannequin",
                   "Mannequin turning and raising its arms", FRAMES, FPS, tris,
                   lambda t: pose(rest, weights, t), 9)

    rest, tris = polygonize(a_pose_body(), (-0.75, -0.05, -0.15), (0.75, 1.80, 0.25))
    weights = leg_weights(rest)
    ground = min(p[1] for p in rest)
    write_sequence(os.path.join(examples, "mannequin_walk"), "mannequin_walk",
                   "Mannequin in an A-pose walking in place and turning", WALK_FRAMES,
                   WALK_FPS, tris, lambda t: walk_pose(rest, weights, t, ground), 6)


if __name__ == "__main__":
    main()
