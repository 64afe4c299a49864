#!/usr/bin/env python3
"""Writes examples/balloon.obj, the closed cloth of examples/balloon.toml.

An icosahedron subdivided LEVELS times (each triangle into four), its vertices pushed onto the
sphere of radius RADIUS around CENTER, every face wound counter-clockwise seen from outside
(outward normals, so that a positive pressure inflates it).

    python3 scripts/make_balloon.py [OUT.obj]
"""
import math
import sys

LEVELS = 2
RADIUS = 0.2                # m
CENTER = (0.0, 0.4, 0.0)    # m


def normalize(p):
    n = math.sqrt(sum(c * c for c in p))
    return tuple(c / n for c in p)


def main(out):
    phi = (1.0 + math.sqrt(5.0)) / 2.0
    x = []
    for a, b in [(1.0, phi), (-1.0, phi), (1.0, -phi), (-1.0, -phi)]:
        x += [normalize((0.0, a, b)), normalize((a, b, 0.0)), normalize((b, 0.0, a))]
    dist = lambda i, j: math.dist(x[i], x[j])
    edge = min(dist(0, j) for j in range(1, 12))
    near = lambda i, j: abs(dist(i, j) - edge) < 1e-9
    tris = []
    for i in range(12):
        for j in range(i + 1, 12):
            for k in range(j + 1, 12):
                if near(i, j) and near(j, k) and near(i, k):
                    u = [x[j][c] - x[i][c] for c in range(3)]
                    v = [x[k][c] - x[i][c] for c in range(3)]
                    n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
                    out_ = sum(n[c] * x[i][c] for c in range(3)) > 0.0
                    tris.append((i, j, k) if out_ else (i, k, j))
    assert len(tris) == 20
    for _ in range(LEVELS):
        mid = {}

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                x.append(normalize(tuple(x[a][c] + x[b][c] for c in range(3))))
                mid[key] = len(x) - 1
            return mid[key]

        nxt = []
        for a, b, c in tris:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            nxt += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
        tris = nxt
    lines = [f"# icosphere: {LEVELS} subdivisions, {len(x)} vertices, {len(tris)} triangles, "
             f"radius {RADIUS} m, outward faces"]
    for p in x:
        lines.append("v " + " ".join(f"{CENTER[c] + RADIUS * p[c]:.9f}" for c in range(3)))
    for a, b, c in tris:
        lines.append(f"f {a + 1} {b + 1} {c + 1}")
    with open(out, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "examples/balloon.obj")
