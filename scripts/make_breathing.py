#!/usr/bin/env python3
"""Writes examples/breathing/: a breathing, swaying torso as an OBJ sequence.

The torso is an ellipsoid (semi-axes 0.30 m across x, 0.40 m tall along y, 0.20 m deep along
z, centred 0.5 m above the ground y = 0) made from an icosahedron subdivided three times and
pushed onto the ellipsoid: 642 vertices and 1280 triangles, closed, watertight and wound
counter-clockwise seen from outside (outward normals).

The animation has period T = 2 s (one breath) and is sampled at 30 frames per second from
t = 0 to t = 2 s inclusive: 61 frames, breathing_0001.obj (t = 0) to breathing_0061.obj
(t = 2 s, the same pose as the first, so the sequence loops). At time t a rest point x goes to

    P + Ry(yaw(t)) Rz(tilt(t)) (C - P + s(t) (x - C))

with C the torso's centre, P = (0, 0.1, 0) the pivot at its base, and

    s(t)    = 1 + 0.10 sin(2 pi t / T)        breathing: +-10 % about the centre
    tilt(t) = 0.12 sin(2 pi t / T + pi / 2)   sway side to side about z (rad)
    yaw(t)  = 0.20 sin(2 pi t / T + pi / 4)   turning about the vertical (rad)

Every file has the same vertices (in the same order) and the same faces; positions are
printed with 9 decimals (1 nm). Standard library only; run from anywhere:

    python3 scripts/make_breathing.py [output directory]
"""

import math
import os
import sys

PERIOD = 2.0  # s, one breath
FPS = 30
FRAMES = 61
RADII = (0.30, 0.40, 0.20)  # m: semi-axes along x, y, z
CENTER = (0.0, 0.5, 0.0)
PIVOT = (0.0, 0.1, 0.0)
BREATH = 0.10  # relative amplitude of the scaling
TILT = 0.12  # rad
YAW = 0.20  # rad
SUBDIVISIONS = 3


def icosphere(levels):
    """Unit sphere: (vertices, triangles), triangles counter-clockwise seen from outside."""
    g = (1.0 + math.sqrt(5.0)) / 2.0
    verts = [
        (-1, g, 0), (1, g, 0), (-1, -g, 0), (1, -g, 0),
        (0, -1, g), (0, 1, g), (0, -1, -g), (0, 1, -g),
        (g, 0, -1), (g, 0, 1), (-g, 0, -1), (-g, 0, 1),
    ]
    verts = [normalize(v) for v in verts]
    tris = [
        (0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11),
        (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8),
        (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9),
        (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1),
    ]
    for _ in range(levels):
        midpoint = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in midpoint:
                pa, pb = verts[a], verts[b]
                verts.append(normalize(tuple((pa[i] + pb[i]) / 2.0 for i in range(3))))
                midpoint[key] = len(verts) - 1
            return midpoint[key]

        new = []
        for a, b, c in tris:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        tris = new
    return verts, tris


def normalize(v):
    n = math.sqrt(sum(x * x for x in v))
    return tuple(x / n for x in v)


def sub(a, b):
    return tuple(a[i] - b[i] for i in range(3))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def volume(verts, tris):
    """Enclosed volume by the divergence theorem (positive for outward winding)."""
    return sum(dot(verts[a], cross(verts[b], verts[c])) for a, b, c in tris) / 6.0


def check_closed(tris):
    """Every edge shared by exactly two triangles, traversed in opposite directions."""
    directed = {}
    for a, b, c in tris:
        for e in ((a, b), (b, c), (c, a)):
            directed[e] = directed.get(e, 0) + 1
    for (a, b), n in directed.items():
        if n != 1 or directed.get((b, a)) != 1:
            raise SystemExit(f"mesh not closed and consistently wound at edge {a}-{b}")


def pose(rest, t):
    w = 2.0 * math.pi * t / PERIOD
    s = 1.0 + BREATH * math.sin(w)
    tilt = TILT * math.sin(w + math.pi / 2.0)
    yaw = YAW * math.sin(w + math.pi / 4.0)
    ct, st = math.cos(tilt), math.sin(tilt)
    cy, sy = math.cos(yaw), math.sin(yaw)
    out = []
    for x in rest:
        # relative to the pivot, after breathing about the centre
        r = tuple(CENTER[i] - PIVOT[i] + s * (x[i] - CENTER[i]) for i in range(3))
        # tilt about z, then yaw about y
        r = (ct * r[0] - st * r[1], st * r[0] + ct * r[1], r[2])
        r = (cy * r[0] + sy * r[2], r[1], -sy * r[0] + cy * r[2])
        out.append(tuple(PIVOT[i] + r[i] for i in range(3)))
    return out


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    default = os.path.normpath(os.path.join(here, "..", "examples", "breathing"))
    out_dir = sys.argv[1] if len(sys.argv) > 1 else default
    os.makedirs(out_dir, exist_ok=True)
    unit, tris = icosphere(SUBDIVISIONS)
    rest = [tuple(CENTER[i] + RADII[i] * v[i] for i in range(3)) for v in unit]
    check_closed(tris)
    if volume(rest, tris) <= 0.0:
        raise SystemExit("mesh wound inward")
    faces = "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in tris)
    for k in range(FRAMES):
        t = k / FPS
        verts = pose(rest, t)
        lines = [
            "# Breathing, swaying torso (closed ellipsoid, outward winding), "
            f"frame {k + 1} of {FRAMES}, t = {t:.6f} s\n",
            "# Generated by scripts/make_breathing.py\n",
        ]
        lines += [f"v {x:.9f} {y:.9f} {z:.9f}\n" for x, y, z in verts]
        path = os.path.join(out_dir, f"breathing_{k + 1:04d}.obj")
        with open(path, "w", encoding="ascii", newline="\n") as f:
            f.write("".join(lines) + faces)
    print(f"{FRAMES} frames, {len(rest)} vertices, {len(tris)} triangles -> {out_dir}")


if __name__ == "__main__":
    main()
