#!/usr/bin/env python3
"""Writes examples/balloon.obj, the closed cloth of examples/balloon.toml.

An icosahedron subdivided LEVELS times (each triangle into four), its vertices pushed onto the
sphere of radius RADIUS around CENTER, every face wound counter-clockwise seen from outside
(outward normals, so that a positive pressure inflates it). The icosphere is the one of
scripts/make_breathing.py.

    python3 scripts/make_balloon.py [OUT.obj]
"""
import sys

from make_breathing import icosphere

LEVELS = 2
RADIUS = 0.2                # m
CENTER = (0.0, 0.4, 0.0)    # m


def main(out):
    x, tris = icosphere(LEVELS)
    # outward faces: each normal points away from the centre
    for a, b, c in tris:
        u = [x[b][k] - x[a][k] for k in range(3)]
        v = [x[c][k] - x[a][k] for k in range(3)]
        n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
        assert sum(n[k] * x[a][k] for k in range(3)) > 0.0
    lines = [f"# icosphere: {LEVELS} subdivisions, {len(x)} vertices, {len(tris)} triangles, "
             f"radius {RADIUS} m, outward faces"]
    for p in x:
        lines.append("v " + " ".join(f"{CENTER[k] + RADIUS * p[k]:.9f}" for k in range(3)))
    for a, b, c in tris:
        lines.append(f"f {a + 1} {b + 1} {c + 1}")
    with open(out, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "examples/balloon.obj")
