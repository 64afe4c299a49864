#!/usr/bin/env python3
"""Writes examples/mannequin/: a mannequin turning and raising its arms, as an OBJ sequence.

The body is the zero level set of the signed distance to a smooth union (polynomial smooth
minimum, blend width 4 cm) of capsules and spheres: head, neck, shoulders, chest, hips, upper
arms, forearms, hands, thighs, shins and feet; 1.74 m tall, standing on y = 0, facing +z. It
is polygonized once, in the rest pose, by surface nets on a 2.5 cm grid (one vertex per grid
cell the surface crosses, at the mean of the crossings of the cell's edges, projected onto the
surface; one quad per grid edge the surface crosses, split along its shorter diagonal): about
5 000 triangles, closed, watertight and wound counter-clockwise seen from outside. The script
checks that (and retries with a shifted grid if a grid face is ambiguous).

The animation moves those vertices (same vertices and faces in every frame): the arms turn
about the shoulders, sideways and up, by 65 (1 - cos(2 pi t / T)) / 2 degrees (from about 13
degrees away from the body to about 78, and back), and the whole body turns about the vertical axis by 0.5 sin(2 pi t / T) rad; period T = 2 s, 30
frames per second, 61 frames (t = 0 to 2 s, the last one the pose of the first):
mannequin_0001.obj ... mannequin_0061.obj. A vertex follows its arm with a weight that is 1
on the arm and blends to 0 over the shoulder (linear blend skinning), so the armpit stretches
instead of tearing.

Standard library only; run from anywhere:

    python3 scripts/make_mannequin.py [output directory]
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


def parts_distance(p):
    """Smooth-union distance of the body without the arms, and of each arm."""
    d = {"head": None, "body": None, "arm+": None, "arm-": None}
    for part, prim in BODY:
        key = "body" if part == "head" else part
        v = prim_distance(prim, p)
        d[key] = v if d[key] is None else smin(d[key], v, BLEND)
    return d["body"], d["arm+"], d["arm-"]


def sdf(p):
    body, right, left = parts_distance(p)
    return smin(smin(body, right, BLEND), left, BLEND)


def gradient(p):
    e = 1e-5
    return tuple(
        (sdf(tuple(p[j] + (e if j == i else 0.0) for j in range(3)))
         - sdf(tuple(p[j] - (e if j == i else 0.0) for j in range(3)))) / (2 * e)
        for i in range(3)
    )


def surface_nets(origin):
    lo = (-0.45, -0.05, -0.15)
    hi = (0.45, 1.80, 0.25)
    n = [int(math.ceil((hi[i] - lo[i]) / CELL)) + 1 for i in range(3)]
    o = tuple(lo[i] + origin[i] for i in range(3))
    point = lambda i, j, k: (o[0] + i * CELL, o[1] + j * CELL, o[2] + k * CELL)
    f = {}
    for i in range(n[0]):
        for j in range(n[1]):
            for k in range(n[2]):
                f[i, j, k] = sdf(point(i, j, k))
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
                g = gradient(p)
                gg = dot(g, g)
                if gg > 0:
                    step = sdf(p) / gg
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


def pose(rest, weights, t):
    w = 2.0 * math.pi * t / PERIOD
    raise_by = RAISE * 0.5 * (1.0 - math.cos(w))
    turn = TURN * math.sin(w)
    ct, st = math.cos(turn), math.sin(turn)
    out = []
    for p, (side, wt) in zip(rest, weights):
        if wt > 0.0:
            r = rotate_z(p, SHOULDER[side], side * raise_by)
            p = tuple((1.0 - wt) * p[i] + wt * r[i] for i in range(3))
        out.append((ct * p[0] + st * p[2], p[1], -st * p[0] + ct * p[2]))
    return out


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    default = os.path.normpath(os.path.join(here, "..", "examples", "mannequin"))
    out_dir = sys.argv[1] if len(sys.argv) > 1 else default
    for shift in ((0.0013, 0.0007, 0.0011), (0.006, 0.004, 0.009), (0.011, 0.017, 0.003)):
        rest, tris = surface_nets(shift)
        if closed(tris):
            break
        print(f"grid shift {shift}: ambiguous faces, retrying", file=sys.stderr)
    else:
        raise SystemExit("no closed mesh")
    if volume(rest, tris) <= 0.0:
        raise SystemExit("mesh wound inward")
    weights = arm_weights(rest)
    os.makedirs(out_dir, exist_ok=True)
    faces = "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in tris)
    for k in range(FRAMES):
        t = k / FPS
        verts = pose(rest, weights, t)
        head = [
            "# Mannequin turning and raising its arms (closed, outward winding), "
            f"frame {k + 1} of {FRAMES}, t = {t:.6f} s\n",
            "# Generated by scripts/make_mannequin.py\n",
        ]
        body = [f"v {x:.9f} {y:.9f} {z:.9f}\n" for x, y, z in verts]
        with open(os.path.join(out_dir, f"mannequin_{k + 1:04d}.obj"), "w",
                  encoding="ascii", newline="\n") as fh:
            fh.write("".join(head + body) + faces)
    print(f"{FRAMES} frames, {len(rest)} vertices, {len(tris)} triangles -> {out_dir}")


if __name__ == "__main__":
    main()
