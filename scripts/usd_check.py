"""Open a .usda written by drapery with Pixar's USD library and read every frame back.

Usage: python3 usd_check.py FILE.usda
Checks: the stage opens, has a default prim, y up, metres, start/end time codes and
timeCodesPerSecond are set, and every Mesh has `points` at every integer time code from
start to end with the same point count at each (time-sampled at every time code, or constant:
a fixed or rigidly moving collider), faceVertexIndices in range, and faceVertexCounts summing
to the number of indices; every time-sampled xform op (a moving collider) has a sample at every
time code, and the prim's transform evaluates to finite values at each. Prints nothing and exits 0 on success;
prints the problems and exits 1 otherwise.
"""

import math
import sys

from pxr import Usd, UsdGeom


def check(path):
    problems = []
    stage = Usd.Stage.Open(path)
    if stage is None:
        return [f"{path}: Usd.Stage.Open failed"]
    if not stage.GetDefaultPrim():
        problems.append("no default prim")
    if UsdGeom.GetStageUpAxis(stage) != UsdGeom.Tokens.y:
        problems.append(f"up axis is {UsdGeom.GetStageUpAxis(stage)}, not Y")
    if UsdGeom.GetStageMetersPerUnit(stage) != 1.0:
        problems.append(f"metersPerUnit is {UsdGeom.GetStageMetersPerUnit(stage)}, not 1")
    if not (stage.HasAuthoredTimeCodeRange() and stage.GetTimeCodesPerSecond() > 0):
        problems.append("no authored time code range or timeCodesPerSecond")
    start, end = int(stage.GetStartTimeCode()), int(stage.GetEndTimeCode())
    meshes = [UsdGeom.Mesh(p) for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    if not meshes:
        problems.append("no Mesh prims")
    for mesh in meshes:
        name = mesh.GetPath()
        points_attr = mesh.GetPointsAttr()
        samples = points_attr.GetTimeSamples()
        if samples and [int(t) for t in samples] != list(range(start, end + 1)):
            problems.append(f"{name}: points time samples {samples[:5]}... do not cover {start}..{end}")
        if not samples and points_attr.Get() is None:
            problems.append(f"{name}: points are neither time-sampled nor set")
        xformable = UsdGeom.Xformable(mesh.GetPrim())
        ops = xformable.GetOrderedXformOps()
        for op in ops:
            op_samples = op.GetTimeSamples()
            if op_samples and [int(t) for t in op_samples] != list(range(start, end + 1)):
                problems.append(f"{name}: {op.GetOpName()} time samples do not cover {start}..{end}")
        if ops:
            for t in range(start, end + 1):
                m = xformable.ComputeLocalToWorldTransform(Usd.TimeCode(t))
                if not all(math.isfinite(m[i][j]) for i in range(4) for j in range(4)):
                    problems.append(f"{name}: transform at time code {t} is not finite")
        counts = list(mesh.GetFaceVertexCountsAttr().Get() or [])
        indices = list(mesh.GetFaceVertexIndicesAttr().Get() or [])
        if sum(counts) != len(indices):
            problems.append(f"{name}: faceVertexCounts sum {sum(counts)} != {len(indices)} indices")
        n = None
        for t in range(start, end + 1):
            pts = points_attr.Get(Usd.TimeCode(t))
            if pts is None:
                problems.append(f"{name}: no points at time code {t}")
                continue
            if n is None:
                n = len(pts)
            elif len(pts) != n:
                problems.append(f"{name}: {len(pts)} points at time code {t}, {n} at {start}")
        if n is not None and indices and max(indices) >= n:
            problems.append(f"{name}: face index {max(indices)} >= point count {n}")
    return [f"{path}: {p}" for p in problems]


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print("usage: usd_check.py FILE.usda", file=sys.stderr)
        sys.exit(2)
    errs = check(sys.argv[1])
    for e in errs:
        print(e, file=sys.stderr)
    sys.exit(1 if errs else 0)
