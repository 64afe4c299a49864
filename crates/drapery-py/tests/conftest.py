"""Shared fixtures: small scenes, the drapery command, a PLY reader."""

import copy
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[3]
EXAMPLES = REPO / "examples"

# A 0.4 m sheet (7 x 7) pinned at its two top corners, swinging: 2 steps per frame, 6 frames.
HANG = {
    "simulation": {"duration": 0.1, "dt": 1.0 / 120.0, "frame_rate": 60},
    "cloth": [
        {
            "name": "sheet",
            "grid": {"size": [0.4, 0.4], "resolution": [7, 7], "center": [0.0, 1.0, 0.0]},
            "density": 0.1,
            "bend_stiffness": 0.5,
            "pin": [0, 6],
            "initial_velocity": [0.0, 0.0, 0.5],
        }
    ],
}

# A 0.5 m sheet (9 x 9) falling onto a sphere (collisions, friction, self-collision), with a
# second small cloth above it: 2 steps per frame, 15 frames; contact from about frame 6.
DRAPE_TOML = """\
[simulation]
duration = 0.25
dt = 0.008333333333333333
frame_rate = 60

[collision]
thickness = 0.005
friction = 0.3

[[cloth]]
name = "sheet"
grid = { size = [0.5, 0.5], resolution = [9, 9], center = [0.0, 0.32, 0.0], normal = [0.0, 1.0, 0.0] }
density = 0.1
bend_stiffness = 0.5

[[cloth]]
name = "patch"
grid = { size = [0.2, 0.2], resolution = [4, 4], center = [0.05, 0.4, 0.0], normal = [0.0, 1.0, 0.0] }
density = 0.1

[[collider]]
shape = "sphere"
center = [0.0, 0.15, 0.0]
radius = 0.15
"""


@pytest.fixture
def hang_dict():
    """A fresh copy of HANG (tests may edit it)."""
    return copy.deepcopy(HANG)


@pytest.fixture
def drape_path(tmp_path):
    """The drape scene as a file."""
    p = tmp_path / "drape.toml"
    p.write_text(DRAPE_TOML)
    return p


@pytest.fixture(scope="session")
def drapery_bin():
    """The drapery command (scripts/python-tests.sh builds it and sets DRAPERY_BIN)."""
    path = Path(os.environ.get("DRAPERY_BIN", REPO / "target" / "release" / "drapery"))
    if not path.is_file():
        pytest.fail(f"{path}: no drapery command; build it with cargo build --release -p drapery-cli")
    return path


def cli_run(drapery_bin, scene, out, fmt, *extra):
    """`drapery run SCENE --output OUT --format FMT --quiet`; its stderr on failure."""
    r = subprocess.run(
        [str(drapery_bin), "run", str(scene), "--output", str(out), "--format", fmt, "--quiet", *extra],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr
    return r


def read_ply_positions(path):
    """The f64 positions of a binary little-endian PLY frame (as drapery writes them)."""
    data = Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    assert header[1] == "format binary_little_endian 1.0"
    n = next(int(l.split()[2]) for l in header if l.startswith("element vertex"))
    i = header.index(f"element vertex {n}")
    assert header[i + 1 : i + 4] == [f"property double {c}" for c in "xyz"]
    return np.frombuffer(data, dtype="<f8", count=3 * n, offset=end).reshape(n, 3)
