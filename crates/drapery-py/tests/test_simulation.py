"""Stepping, numpy arrays in and out, reports, threads, the GIL and Ctrl-C."""

import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import drapery
from conftest import HANG

G = 9.81


def free_fall_scene():
    """A sheet with no pin and no air drag: its springs stay at rest while it falls."""
    d = {
        "simulation": {"duration": 0.2, "dt": 0.01, "frame_rate": 50},
        "cloth": [
            {
                "name": "sheet",
                "grid": {"size": [0.3, 0.3], "resolution": [4, 4], "center": [0.0, 2.0, 0.0]},
                "density": 0.1,
                "air_drag": 0.0,
            }
        ],
    }
    return drapery.Scene.from_dict(d)


def test_positions_velocities_and_faces_are_numpy_arrays_of_the_documented_shapes(drape_path):
    sim = drapery.Simulation(drapery.load_scene(drape_path))
    assert sim.cloths == ["sheet", "patch"]
    x = sim.positions()
    assert x.dtype == np.float64 and x.shape == (81 + 16, 3) and x.flags.c_contiguous
    assert sim.velocities().shape == (97, 3) and sim.velocities().dtype == np.float64
    sheet, patch = sim.positions("sheet"), sim.positions("patch")
    assert sheet.shape == (81, 3) and patch.shape == (16, 3)
    assert np.array_equal(np.vstack([sheet, patch]), x)
    # the generated grids: centred where the scene puts them, horizontal, 0.5 m and 0.2 m wide
    assert np.allclose(sheet.mean(axis=0), [0.0, 0.32, 0.0])
    assert np.allclose(np.ptp(sheet, axis=0), [0.5, 0.0, 0.5])
    assert np.allclose(np.ptp(patch, axis=0), [0.2, 0.0, 0.2])

    f = sim.faces("patch")
    assert f.dtype == np.int64 and f.ndim == 2 and f.shape[1] == 3
    assert f.shape[0] == 2 * 3 * 3  # 3 x 3 quads, two triangles each
    assert f.min() == 0 and f.max() == 15
    whole = sim.faces()
    assert whole.shape == (2 * 8 * 8 + 18, 3) and whole.max() == 96
    # every triangle of the patch, taken from the whole model, has the patch's positions
    tri = x[whole[-1]]
    assert np.array_equal(tri, patch[f[-1]])


def test_a_free_falling_sheet_follows_implicit_euler_exactly():
    scene = free_fall_scene()
    sim = drapery.Simulation(scene)
    y0 = sim.positions()[:, 1].copy()
    h = scene.step_size
    sim.step()
    assert sim.steps == 1 and sim.time == h and sim.frame == 0
    sim.advance(2)
    n = 1 + 2 * scene.steps_per_frame
    assert sim.steps == n and sim.frame == 2
    assert sim.time == pytest.approx(n * h, rel=1e-15)
    # v_k = -g h k, x_n = x_0 - g h² n(n+1)/2 (springs at rest, nothing else acts)
    drop = y0 - sim.positions()[:, 1]
    assert np.allclose(drop, G * h * h * n * (n + 1) / 2, rtol=1e-9, atol=0)
    assert np.allclose(sim.velocities()[:, 1], -G * h * n, rtol=1e-9)
    assert np.allclose(sim.velocities()[:, [0, 2]], 0.0, atol=1e-12)


def test_set_positions_and_velocities_move_the_cloth_between_steps():
    sim = drapery.Simulation(free_fall_scene())
    x = sim.positions()
    sim.set_positions(x + [0.0, 1.0, 0.0])
    assert np.array_equal(sim.positions(), x + [0.0, 1.0, 0.0])
    # a list of float32 rows is accepted (converted to float64)
    v = np.zeros_like(x, dtype=np.float32)
    v[:, 0] = 2.0
    sim.set_velocities(v.tolist(), cloth="sheet")
    sim.step()
    # a uniform horizontal velocity carries every particle the same way
    dx = sim.positions()[:, 0] - x[:, 0]
    assert np.allclose(dx, 2.0 * sim.time, rtol=1e-9)


def test_setting_one_cloth_leaves_the_others(drape_path):
    sim = drapery.Simulation(drapery.load_scene(drape_path))
    before = sim.positions()
    patch = sim.positions("patch") + [0.0, 0.5, 0.0]
    sim.set_positions(patch, cloth="patch")
    assert np.array_equal(sim.positions("patch"), patch)
    assert np.array_equal(sim.positions("sheet"), before[:81])


def test_bad_arrays_and_names_are_refused_and_change_nothing():
    sim = drapery.Simulation(free_fall_scene())
    x = sim.positions()
    with pytest.raises(ValueError, match=r"shape \(16, 3\), got shape \(15, 3\)"):
        sim.set_positions(x[:-1])
    with pytest.raises(ValueError, match=r"got shape \(48,\)"):
        sim.set_positions(x.ravel())
    bad = x.copy()
    bad[4, 2] = np.nan
    with pytest.raises(ValueError, match="particle 4 is not finite"):
        sim.set_positions(bad)
    with pytest.raises(ValueError, match="no cloth named 'shet'"):
        sim.positions("shet")
    with pytest.raises(ValueError, match="no cloth named"):
        sim.faces("shet")
    assert np.array_equal(sim.positions(), x)


def test_the_last_report_has_the_step_reports_fields_and_stage_times(drape_path):
    sim = drapery.Simulation(drapery.load_scene(drape_path))
    assert sim.last_report is None
    sim.advance(8)  # the sheet is on the sphere by then
    r = sim.last_report
    assert r["newton_iterations"] >= 1 and r["cg_iterations"] >= 1 and r["linear_solves"] >= 1
    assert r["obstacle_contacts"] >= 1
    assert 0 <= r["residual"] < 1e-5  # the scene's PCG tolerance is the default 1e-6
    assert r["tolerance"] == 1e-6 and r["residual"] <= r["tolerance"]
    stages = r["stages"]
    names = ["guard", "pose", "detect", "linearize", "constrain", "solve", "update", "friction", "strain", "failsafe", "commit"]
    assert list(stages) == names + ["total"]
    assert all(stages[k] >= 0 for k in names)
    assert stages["total"] == pytest.approx(sum(stages[k] for k in names))
    assert r["assembly_seconds"] == stages["linearize"]


def test_a_failed_step_raises_the_library_message_and_keeps_the_state():
    sim = drapery.Simulation(drapery.Scene.from_dict(HANG))
    sim.advance(1)
    x = sim.positions()
    v = sim.velocities()
    v[10] = [1e200, 0.0, 0.0]
    sim.set_velocities(v)
    with pytest.raises(drapery.SimulationError) as e:
        sim.step()
    m = str(e.value)
    assert m.startswith("simulation failed at step 2 (t = 0.016667 s)"), m
    assert "\n" not in m
    assert sim.steps == 2 and np.array_equal(sim.positions(), x)


def test_the_thread_count_does_not_change_the_bits(drape_path):
    scene = drapery.load_scene(drape_path)
    runs = []
    for threads in (1, 2, None):
        sim = drapery.Simulation(scene, threads=threads)
        sim.advance(8)
        runs.append(sim.positions().tobytes())
    assert runs[0] == runs[1] == runs[2]
    with pytest.raises(ValueError, match="at least 1"):
        drapery.Simulation(scene, threads=0)


def test_the_gil_is_released_while_stepping(drape_path):
    """Another Python thread keeps running while a long advance steps."""
    sim = drapery.Simulation(drapery.load_scene(drape_path), threads=1)
    # about 1 s of stepping (timed after the first frames, which also set up the multigrid and
    # the broad phase's trees and are slower)
    sim.advance(2)
    t = time.perf_counter()
    sim.advance(2)
    per_frame = (time.perf_counter() - t) / 2
    frames = max(4, int(1.0 / per_frame))
    ticks = []
    done = threading.Event()

    def work():
        sim.advance(frames)
        done.set()

    worker = threading.Thread(target=work)
    start = time.perf_counter()
    worker.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0.002)
    worker.join()
    took = time.perf_counter() - start
    gaps = np.diff([start] + ticks)
    assert took > 0.3
    # with the GIL held during the whole advance, this thread would stop for all of it
    assert len(ticks) > 20 and gaps.max() < took / 2, (len(ticks), gaps.max(), took)


def test_ctrl_c_interrupts_a_long_advance():
    code = textwrap.dedent(
        """
        import signal, sys, drapery
        # Python leaves SIGINT ignored when it starts with it ignored (a CI job started in the
        # background of a non-interactive shell): install the default handler, which raises
        # KeyboardInterrupt, so the test measures advance() and not how it was launched
        signal.signal(signal.SIGINT, signal.default_int_handler)
        scene = drapery.Scene.from_dict({
            "simulation": {"duration": 1000.0, "dt": 0.01, "frame_rate": 100},
            "cloth": [{"name": "s", "grid": {"size": [1.0, 1.0], "resolution": [30, 30]},
                       "density": 0.1, "pin": [0]}],
        })
        sim = drapery.Simulation(scene, threads=1)
        print("ready", flush=True)
        try:
            sim.advance(100000)
        except KeyboardInterrupt:
            print("interrupted at step", sim.steps, flush=True)
            sys.exit(3)
        """
    )
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "ready"
    time.sleep(0.5)
    p.send_signal(2)  # SIGINT
    try:
        out, _ = p.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        p.kill()
        pytest.fail("advance was not interrupted by SIGINT")
    assert p.returncode == 3, out
    steps = int(out.split()[-1])
    assert 0 < steps < 100000


def test_close_pairs_follow_the_thickness_against_the_grid_spacing():
    """On a grid of spacing h split into right triangles, the primitives sharing no vertex with
    a vertex are at least h / sqrt(2) from it: the same count as the library's, through Python."""
    def sim(thickness, self_collision=True):
        d = {
            "simulation": {"duration": 0.1, "dt": 0.01, "frame_rate": 10},
            "collision": {"thickness": thickness, "self_collision": self_collision},
            "cloth": [
                {
                    "name": "sheet",
                    "grid": {"size": [0.5, 0.5], "resolution": [11, 11], "normal": [0.0, 1.0, 0.0]},
                    "density": 0.1,
                }
            ],
        }
        return drapery.Simulation(drapery.Scene.from_dict(d))

    diagonal = 0.05 / np.sqrt(2.0)
    count, closest = sim(0.99 * diagonal).close_pairs
    assert count == 0 and closest == float("inf")
    count, closest = sim(1.01 * diagonal).close_pairs
    assert count > 100
    assert closest == pytest.approx(diagonal, abs=1e-12)
    assert sim(1.01 * diagonal, self_collision=False).close_pairs is None


def test_run_warns_where_the_command_warns_at_frame_0(tmp_path):
    """drapery.run raises the command's frame-0 warnings as RuntimeWarning: a thickness above
    the grid's h / sqrt(2) (the closest pair that far apart), and a pinned vertex inside a
    sphere, which the steps do not push out (the free ones inside they do: no warning)."""
    import warnings

    def scene(thickness, pin=None, sphere=False):
        cloth = {
            "name": "sheet",
            "grid": {"size": [0.5, 0.5], "resolution": [11, 11], "normal": [0.0, 1.0, 0.0]},
            "density": 0.1,
        }
        if pin is not None:
            cloth["pin"] = pin
        d = {
            "simulation": {"duration": 0.02, "dt": 0.01, "frame_rate": 100},
            "collision": {"thickness": thickness, "self_collision": True},
            "cloth": [cloth],
        }
        if sphere:
            d["collider"] = [{"shape": "sphere", "center": [0.0, 0.0, 0.0], "radius": 0.06}]
        return drapery.Scene.from_dict(d)

    def warned(s):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            drapery.run(s, tmp_path, formats=[], on_frame=lambda k, x: None)
        return [str(w.message) for w in caught if w.category is RuntimeWarning]

    diagonal = 0.05 / np.sqrt(2.0)
    assert warned(scene(0.99 * diagonal)) == []
    (thick,) = warned(scene(1.01 * diagonal))
    assert "collision.thickness: " in thick and "share no vertex" in thick
    closest = float(thick.split("the closest ")[1].split(" m apart")[0])
    assert closest == pytest.approx(diagonal, rel=1e-3)
    # the centre (vertex 60) and its 4 neighbours are within the 6 cm sphere
    assert warned(scene(0.01, sphere=True)) == []
    (inside,) = warned(scene(0.01, pin=[60], sphere=True))
    assert "frame 0 intersects (0 intersecting cloth triangle pairs, 5 vertices inside colliders)" in inside
    # the same texts from a Simulation, without the scene's name
    assert drapery.Simulation(scene(0.01, pin=[60], sphere=True)).start_warnings == [
        inside.split(": ", 1)[1]
    ]
    assert drapery.Simulation(scene(0.01, sphere=True)).start_warnings == []


def test_run_does_not_warn_of_the_contact_the_preroll_settles_into(tmp_path):
    """A second sheet 2 cm above the first falls onto it, both onto a floor, in a 0.5 s
    pre-roll: frame 0 has cloth pairs within the thickness (contact), which drapery.run does
    not warn of; a thickness beyond the grid's spacing is still one warning, found at the
    scene's start, before the pre-roll (as `drapery run` does)."""
    import warnings

    def scene(thickness):
        def sheet(name, y):
            return {
                "name": name,
                "grid": {"size": [0.4, 0.4], "resolution": [5, 5], "center": [0.0, y, 0.0],
                         "normal": [0.0, 1.0, 0.0]},
                "density": 0.1,
            }
        return drapery.Scene.from_dict({
            "simulation": {"duration": 0.02, "dt": 0.01, "frame_rate": 100, "preroll": 0.5},
            "collision": {"thickness": thickness, "self_collision": True},
            "cloth": [sheet("lower", 0.5), sheet("upper", 0.52)],
            "collider": [{"shape": "plane", "point": [0.0, 0.45, 0.0], "normal": [0.0, 1.0, 0.0]}],
        })

    def warned(s):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            drapery.run(s, tmp_path, formats=[], on_frame=lambda k, x: None)
        return [str(w.message) for w in caught if w.category is RuntimeWarning]

    # (a Simulation is built settled, after its pre-roll)
    settled = drapery.Simulation(scene(0.01))
    assert settled.close_pairs[0] > 0
    assert settled.start_warnings == []
    assert warned(scene(0.01)) == []
    (thick,) = warned(scene(0.072))
    assert "collision.thickness: " in thick
