#!/usr/bin/env python3
"""Writes examples/stitched_tube.obj, the open sleeve of examples/stitched_tube.toml.

A sheet of COLS columns around and ROWS rows along x, bent into a C: column c lies at angle
2*pi*c/COLS on a circle whose chords between neighbouring columns are CHORD long, so the gap
between the last column and the first is one chord too (about the +z side). Vertex (row r,
column c) is number r*COLS + c (0-based); the example stitches column COLS-1 to column 0.

    python3 scripts/make_stitched_tube.py [OUT.obj]
"""
import math
import sys

COLS, ROWS = 24, 21
CHORD = 0.026          # m, between neighbouring columns
SPACING = 0.03         # m, between rows (along x)
CENTER_Y = 1.0         # m, height of the tube's axis

def main(out):
    radius = CHORD / (2.0 * math.sin(math.pi / COLS))
    lines = [f"# open tube: {COLS} columns x {ROWS} rows, radius {radius:.6f} m; "
             f"stitch column {COLS - 1} to column 0 to close it"]
    for r in range(ROWS):
        x = (r - (ROWS - 1) / 2) * SPACING
        for c in range(COLS):
            a = 2.0 * math.pi * c / COLS
            lines.append(f"v {x:.9f} {CENTER_Y + radius * math.sin(a):.9f} {radius * math.cos(a):.9f}")
    for r in range(ROWS - 1):
        for c in range(COLS - 1):
            i = r * COLS + c + 1  # OBJ is 1-based
            lines.append(f"f {i} {i + COLS} {i + COLS + 1} {i + 1}")
    with open(out, "w") as f:
        f.write("\n".join(lines) + "\n")
    last = [r * COLS + COLS - 1 for r in range(ROWS)]
    first = [r * COLS for r in range(ROWS)]
    print(f"a vertices = {last}\nb vertices = {first}")

if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "examples/stitched_tube.obj")
