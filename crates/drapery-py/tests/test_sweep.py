"""drapery.sweep and drapery-sweep: samples, files, failures, resume, Ray, the command."""

import copy
import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import drapery
from conftest import EXAMPLES, cli_run
from drapery.sweep import _plan, parse_param

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

# A 0.3 m sheet (4 x 4) falling onto a sphere: 2 steps per frame, 3 frames.
TINY = {
    "simulation": {"duration": 0.05, "dt": 1.0 / 120.0, "frame_rate": 60},
    "collision": {"thickness": 0.005},
    "cloth": [
        {
            "name": "sheet",
            "grid": {"size": [0.3, 0.3], "resolution": [4, 4], "center": [0.0, 0.21, 0.0], "normal": [0.0, 1.0, 0.0]},
            "density": 0.1,
            "bend_stiffness": 0.5,
            "initial_velocity": [0.3, -1.0, 0.0],
        }
    ],
    "collider": [{"shape": "sphere", "center": [0.0, 0.1, 0.0], "radius": 0.1, "friction": 0.3}],
}
FRAMES = 4  # frame 0 and 3 more
VERTICES = 16
TRIANGLES = 2 * 3 * 3
GRID = {"cloth.sheet.bend_stiffness": [0.01, 10.0], "collider.0.friction": [0.0, 0.9]}


def manifest(out):
    return [json.loads(l) for l in (Path(out) / "manifest.jsonl").read_text().splitlines()]


def npz(path):
    with np.load(path) as z:
        return {k: z[k] for k in z.files}


def frames_of(scene):
    """Every frame's positions (f64), stepping a Simulation of `scene` frame by frame."""
    sim = drapery.Simulation(scene)
    out = [sim.positions()]
    for _ in range(scene.frame_count):
        sim.advance(1)
        out.append(sim.positions())
    return np.stack(out)


@pytest.fixture(scope="module")
def grid_sweep(tmp_path_factory):
    """The 4-sample grid sweep of TINY on the local backend (shared: it is only read)."""
    out = tmp_path_factory.mktemp("grid") / "out"
    records = drapery.sweep(copy.deepcopy(TINY), GRID, out, workers=2)
    return out, records


def test_a_grid_sweep_runs_every_combination_into_its_own_folder(grid_sweep):
    out, records = grid_sweep
    lines = manifest(out)
    assert lines == records
    assert [r["id"] for r in lines] == ["s0000", "s0001", "s0002", "s0003"]
    assert sorted(p.name for p in out.iterdir() if p.is_dir()) == ["s0000", "s0001", "s0002", "s0003"]
    assert [r["status"] for r in lines] == ["ok"] * 4
    # the Cartesian product, the last parameter varying fastest
    assert [tuple(r["params"].values()) for r in lines] == [(0.01, 0.0), (0.01, 0.9), (10.0, 0.0), (10.0, 0.9)]
    assert len({r["params_hash"] for r in lines}) == 4
    assert all(r["wall_time"] > 0 and "error" not in r for r in lines)
    for r in lines:
        scene = tomllib.loads((out / r["id"] / "scene.toml").read_text())
        assert scene["cloth"][0]["bend_stiffness"] == r["params"]["cloth.sheet.bend_stiffness"]
        assert scene["collider"][0]["friction"] == r["params"]["collider.0.friction"]
        assert scene["cloth"][0]["density"] == 0.1  # the rest of the scene is the base's
        assert sorted(p.name for p in (out / r["id"]).glob("frame_*.obj")) == [f"frame_{k:05d}.obj" for k in range(FRAMES)]
        assert json.loads((out / r["id"] / "done.json").read_text())["frames"] == FRAMES


def test_the_npz_holds_float32_positions_equal_to_running_the_samples_scene_file(grid_sweep):
    out, records = grid_sweep
    finals = []
    for r in records:
        z = npz(out / r["id"] / "frames.npz")
        assert z["positions"].dtype == np.float32 and z["positions"].shape == (FRAMES, VERTICES, 3)
        assert z["faces"].dtype == np.int64 and z["faces"].shape == (TRIANGLES, 3)
        assert z["faces"].min() == 0 and z["faces"].max() == VERTICES - 1
        assert list(z["cloths"]) == ["sheet"] and list(z["offsets"]) == [0, VERTICES]
        assert np.array_equal(z["times"], np.arange(FRAMES) / 60.0)
        scene = drapery.load_scene(out / r["id"] / "scene.toml")
        want = frames_of(scene)
        assert z["positions"].tobytes() == want.astype(np.float32).tobytes()
        assert np.array_equal(z["faces"], drapery.Simulation(scene).faces())
        finals.append(want[-1])
    # the parameters change the motion (the comparisons above are not all of one run)
    assert len({f.tobytes() for f in finals}) == 4


def test_a_samples_scene_file_runs_on_its_own_with_the_drapery_command(tmp_path, drapery_bin):
    # a scene file with a mesh relative to its folder, swept from another folder
    scene = tmp_path / "scenes" / "cloth.toml"
    scene.parent.mkdir()
    shutil.copy(EXAMPLES / "sheet.obj", scene.parent / "sheet.obj")
    scene.write_text((EXAMPLES / "obj_cloth.toml").read_text().replace("duration = 1.5", "duration = 0.05"))
    out = tmp_path / "out"
    records = drapery.sweep(scene, {"cloth.sheet.damping": [0.0, 0.05]}, out, workers=1, frames=["obj", "ply"])
    assert [r["status"] for r in records] == ["ok", "ok"]
    sample = out / "s0001"
    mesh = tomllib.loads((sample / "scene.toml").read_text())["cloth"][0]["mesh"]
    assert Path(mesh).is_absolute() and Path(mesh).samefile(scene.parent / "sheet.obj")
    moved = tmp_path / "elsewhere"
    shutil.copytree(sample, moved)
    cli_run(drapery_bin, moved / "scene.toml", tmp_path / "cli", "obj")
    frames = sorted((tmp_path / "cli").glob("frame_*.obj"))
    assert len(frames) == 3  # 0.05 s at 40 frames/s: frames 0, 1, 2
    for f in frames:
        assert f.read_bytes() == (sample / f.name).read_bytes(), f.name


def test_random_draws_are_reproducible_and_inside_their_ranges():
    params = {
        "cloth.sheet.damping": {"low": 0.001, "high": 0.1, "log": True},
        "cloth.sheet.bend_stiffness": {"low": 0.5, "high": 2.0},
    }
    _, a = _plan(params, 4000, seed=7)
    _, b = _plan(params, 4000, seed=7)
    _, c = _plan(params, 4000, seed=8)
    assert a == b and a != c and len(a) == 4000
    d = np.array([s["cloth.sheet.damping"] for s in a])
    k = np.array([s["cloth.sheet.bend_stiffness"] for s in a])
    assert d.min() >= 0.001 and d.max() <= 0.1 and k.min() >= 0.5 and k.max() <= 2.0
    # uniform: half below the middle; log-uniform: half below the geometric mean and
    # ln(50.5)/ln(100) = 85 % below the arithmetic mean (a uniform draw would put 50 % there).
    # n = 4000: one standard deviation of a fraction is at most 0.008.
    assert abs(np.mean(k < 1.25) - 0.5) < 0.04
    assert abs(np.mean(d < 0.01) - 0.5) < 0.04
    assert abs(np.mean(d < 0.0505) - math.log(50.5) / math.log(100)) < 0.04
    # log10 of a log-uniform draw is uniform on [-3, -1]: its quartiles
    q = np.quantile(np.log10(d), [0.25, 0.5, 0.75])
    assert np.allclose(q, [-2.5, -2.0, -1.5], atol=0.06)


def test_grid_and_ranges_together_combine_every_grid_point_with_the_same_draws(tmp_path):
    params = {"cloth.sheet.bend_stiffness": [0.1, 1.0], "collider.0.friction": {"low": 0.1, "high": 0.9}}
    _, plan = _plan(params, 2, seed=3)
    assert [s["cloth.sheet.bend_stiffness"] for s in plan] == [0.1, 0.1, 1.0, 1.0]
    draws = [s["collider.0.friction"] for s in plan]
    assert draws[:2] == draws[2:] and draws[0] != draws[1]
    with pytest.raises(ValueError, match="samples"):
        _plan(params, None, seed=0)
    with pytest.raises(ValueError, match="samples"):
        _plan({"cloth.sheet.bend_stiffness": [1.0]}, 3, seed=0)
    # the same seed through sweep writes the same values again
    one = drapery.sweep(copy.deepcopy(TINY), params, tmp_path / "a", samples=2, seed=3, workers=2)
    assert [r["params"] for r in one] == plan
    assert all(r["status"] == "ok" for r in one)


def test_a_sample_the_library_refuses_fails_with_its_message_and_the_others_run(tmp_path):
    out = tmp_path / "out"
    params = {"cloth.sheet.bend_stiffness": [0.5, -1.0, 2.0]}
    records = drapery.sweep(copy.deepcopy(TINY), params, out, workers=2)
    assert [r["status"] for r in records] == ["ok", "failed", "ok"]
    assert manifest(out) == records
    bad = records[1]
    with pytest.raises(drapery.SceneError) as e:
        drapery.load_scene(out / "s0001" / "scene.toml")
    assert bad["error"] == str(e.value) and "bend_stiffness" in bad["error"]
    assert bad["error_type"] == "SceneError"
    assert not (out / "s0001" / "done.json").exists() and not (out / "s0001" / "frames.npz").exists()
    assert (out / "s0002" / "frames.npz").is_file()
    # running again retries the failed sample only
    before = {s: (out / s / "scene.toml").stat().st_mtime_ns for s in ("s0000", "s0001", "s0002")}
    again = drapery.sweep(copy.deepcopy(TINY), params, out, workers=2)
    after = {s: (out / s / "scene.toml").stat().st_mtime_ns for s in ("s0000", "s0001", "s0002")}
    assert [r["status"] for r in again] == ["ok", "failed", "ok"]
    assert after["s0000"] == before["s0000"] and after["s0002"] == before["s0002"]
    assert after["s0001"] != before["s0001"]


def test_resume_after_deleting_a_sample_reruns_only_that_sample(tmp_path, grid_sweep):
    out = tmp_path / "out"
    first = drapery.sweep(copy.deepcopy(TINY), GRID, out, workers=2)
    files = {r["id"]: out / r["id"] / "frames.npz" for r in first}
    stamps = {i: f.stat().st_mtime_ns for i, f in files.items()}
    data = {i: f.read_bytes() for i, f in files.items()}
    shutil.rmtree(out / "s0002")
    second = drapery.sweep(copy.deepcopy(TINY), GRID, out, workers=2)
    assert [r["status"] for r in second] == ["ok"] * 4
    for i, f in files.items():
        assert f.read_bytes() == data[i]
        if i == "s0002":
            assert f.stat().st_mtime_ns != stamps[i]
        else:
            assert f.stat().st_mtime_ns == stamps[i], i
    # the manifest keeps the skipped samples' lines as they were
    assert [r for r in second if r["id"] != "s0002"] == [r for r in first if r["id"] != "s0002"]
    assert manifest(out) == second
    # the same bytes as the shared sweep of the same parameters
    shared, _ = grid_sweep
    assert all(data[i] == (shared / i / "frames.npz").read_bytes() for i in data)
    # an interrupted sample (no done.json) runs again; so do the samples whose values changed
    (out / "s0000" / "done.json").unlink()
    changed = dict(GRID, **{"collider.0.friction": [0.0, 0.8]})
    stamps = {i: f.stat().st_mtime_ns for i, f in files.items()}
    third = drapery.sweep(copy.deepcopy(TINY), changed, out, workers=2)
    rerun = {i for i, f in files.items() if f.stat().st_mtime_ns != stamps[i]}
    assert rerun == {"s0000", "s0001", "s0003"}
    assert [r["params"]["collider.0.friction"] for r in third] == [0.0, 0.8, 0.0, 0.8]
    assert manifest(out) == third and all(r["status"] == "ok" for r in third)


def test_an_unknown_key_path_is_one_error_before_anything_runs(tmp_path):
    out = tmp_path / "out"
    cases = {
        "cloth.shirt.bend_stiffness": "shirt",
        "collider.3.friction": "collider",
        "cloth.sheet.bend_stifness": "bend_stifness",
        "cloth.sheet.density.x": "density",
        "simulaton.duration": "simulaton",
    }
    for path, named in cases.items():
        with pytest.raises(ValueError, match=named):
            drapery.sweep(copy.deepcopy(TINY), {path: [1.0]}, out)
    with pytest.raises(ValueError, match="non-empty list"):
        drapery.sweep(copy.deepcopy(TINY), {"cloth.sheet.bend_stiffness": []}, out)
    with pytest.raises(ValueError, match="low > 0"):
        drapery.sweep(copy.deepcopy(TINY), {"cloth.sheet.damping": {"low": 0.0, "high": 1.0, "log": True}}, out, samples=2)
    assert not out.exists()


def test_a_key_absent_from_the_base_scene_can_be_swept(tmp_path):
    params = {"solver.tolerance": [1e-4], "cloth.sheet.damping": [0.02], "cloth.sheet.grid.center.1": [0.25]}
    records = drapery.sweep(copy.deepcopy(TINY), params, tmp_path, workers=1)
    assert records[0]["status"] == "ok", records[0]
    scene = tomllib.loads((tmp_path / "s0000" / "scene.toml").read_text())
    assert scene["solver"]["tolerance"] == 1e-4 and scene["cloth"][0]["damping"] == 0.02
    assert scene["cloth"][0]["grid"]["center"] == [0.0, 0.25, 0.0]  # an array's component
    with np.load(tmp_path / "s0000" / "frames.npz") as z:
        assert abs(z["positions"][0, :, 1].mean() - 0.25) < 1e-6  # the sheet starts there


def test_command_line_parameters():
    assert parse_param("cloth.sheet.bend_stiffness=10,100,1e3") == ("cloth.sheet.bend_stiffness", [10, 100, 1000.0])
    assert parse_param("collider.0.friction=0.1:0.9:log") == ("collider.0.friction", {"low": 0.1, "high": 0.9, "log": True})
    assert parse_param("collision.friction=0:1") == ("collision.friction", {"low": 0.0, "high": 1.0, "log": False})
    assert parse_param("cloth.sheet.grid.resolution=[5,5],[9, 9]") == ("cloth.sheet.grid.resolution", [[5, 5], [9, 9]])
    assert parse_param("solver.linear_solver=pcg,direct") == ("solver.linear_solver", ["pcg", "direct"])
    for bad in ("nothing", "a=", "a=1:2:3:4", "a=x:y"):
        with pytest.raises(ValueError):
            parse_param(bad)


def test_drapery_sweep_command_runs_a_two_sample_sweep(tmp_path):
    scene = tmp_path / "tiny.toml"
    scene.write_text(drapery.scene_toml(TINY))
    exe = Path(sys.executable).with_name("drapery-sweep")
    assert exe.is_file(), "the console script is installed beside python"
    out = tmp_path / "out"
    r = subprocess.run(
        [str(exe), str(scene), "--param", "cloth.sheet.bend_stiffness=0.1,10", "--output", str(out), "--workers", "2", "--format", "ply"],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr
    assert "2 ok, 0 failed" in r.stderr
    lines = manifest(out)
    assert [(l["id"], l["status"], l["params"]) for l in lines] == [
        ("s0000", "ok", {"cloth.sheet.bend_stiffness": 0.1}),
        ("s0001", "ok", {"cloth.sheet.bend_stiffness": 10}),
    ]
    assert len(list((out / "s0001").glob("frame_*.ply"))) == FRAMES and not list((out / "s0001").glob("*.obj"))
    bad = subprocess.run([str(exe), str(scene), "--param", "cloth.nope.x=1", "--output", str(out)], capture_output=True, text=True)
    assert bad.returncode == 2 and "nope" in bad.stderr
    helped = subprocess.run([str(exe), "--help"], capture_output=True, text=True)
    assert helped.returncode == 0 and "PATH=LOW:HIGH:log" in helped.stdout


def test_run_reports_every_frame_to_on_frame_without_files(tmp_path):
    scene = drapery.Scene.from_dict(TINY)
    seen = []
    drapery.run(scene, tmp_path / "none", formats=[], on_frame=lambda k, x: seen.append((k, x)))
    assert [k for k, _ in seen] == list(range(FRAMES))
    assert np.stack([x for _, x in seen]).tobytes() == frames_of(scene).tobytes()
    assert not list((tmp_path / "none").glob("frame_*"))
    with pytest.raises(ValueError, match="no output format"):
        drapery.run(scene, tmp_path / "x", formats=[])


def test_scene_toml_reads_back_to_the_same_dict():
    assert tomllib.loads(drapery.scene_toml(TINY)) == TINY


# ---------------------------------------------------------------------------------------------
# Ray: required where DRAPERY_REQUIRE_RAY is set (CI), else skipped when ray is not installed


def _ray():
    try:
        import ray
    except ImportError:
        if os.environ.get("DRAPERY_REQUIRE_RAY"):
            raise
        pytest.skip("ray is not installed (pip install ray; DRAPERY_REQUIRE_RAY=1 makes this a failure)")
    return ray


def test_the_ray_backend_without_ray_is_one_clear_error(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray fails
    with pytest.raises(ImportError, match=r"drapery\[ray\]"):
        drapery.sweep(copy.deepcopy(TINY), {"cloth.sheet.damping": [0.1]}, tmp_path, backend="ray")
    assert not list(tmp_path.iterdir()), "nothing is written"


@pytest.fixture(scope="module")
def ray_instance():
    ray = _ray()
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield ray
    ray.shutdown()


def test_the_ray_backend_writes_the_same_bytes_as_the_local_one(tmp_path, grid_sweep, ray_instance):
    local, local_records = grid_sweep
    out = tmp_path / "ray"
    records = drapery.sweep(copy.deepcopy(TINY), GRID, out, backend="ray", cpus_per_task=1)
    assert ray_instance.is_initialized(), "an instance the caller started is left running"
    strip = lambda rs: [{k: v for k, v in r.items() if k != "wall_time"} for r in rs]
    assert strip(records) == strip(local_records) and manifest(out) == records
    for r in records:
        for name in ("frames.npz", "scene.toml", "frame_00003.obj"):
            assert (out / r["id"] / name).read_bytes() == (local / r["id"] / name).read_bytes(), (r["id"], name)


def test_a_scene_loaded_from_a_file_is_swept_from_that_file(tmp_path):
    from drapery.sweep import _base_scene

    path = tmp_path / "tiny.toml"
    path.write_text(drapery.scene_toml(TINY))
    assert _base_scene(drapery.load_scene(path)) == _base_scene(path) == TINY
    with pytest.raises(TypeError, match="pass the dict"):
        drapery.sweep(drapery.Scene.from_dict(TINY), {"cloth.sheet.damping": [0.1]}, tmp_path / "out")


def test_the_sweep_module_type_checks_strictly(tmp_path):
    r = subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--no-incremental", "-m", "drapery.sweep"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stdout + r.stderr
