"""Handles and colliders driven from Python between steps: set_handle_pose, set_collider_pose,
their readers, and their errors."""

import math

import numpy as np
import pytest

import drapery

H = 1.0 / 120.0


def control_scene(friction=0.8):
    """A sheet hanging from a handle (its first grid row), a mat resting on a named box table,
    a flag with two one-vertex handles (the second released at 0.02 s), and an unnamed sphere
    far away (so that the table is collider 1)."""
    return {
        "simulation": {"duration": 1.0, "dt": H, "frame_rate": 60},
        "collision": {"thickness": 0.005, "friction": friction},
        "cloth": [
            {
                "name": "sheet",
                "grid": {"size": [0.3, 0.3], "resolution": [5, 5], "center": [0.0, 1.0, 0.0]},
                "density": 0.1,
                "handle": [{"vertices": [0, 1, 2, 3, 4]}],
            },
            {
                "name": "mat",
                "grid": {"size": [0.2, 0.2], "resolution": [4, 4], "center": [0.0, 0.306, 0.0],
                         "normal": [0.0, 1.0, 0.0]},
                "density": 0.1,
            },
            {
                "name": "flag",
                "grid": {"size": [0.1, 0.1], "resolution": [3, 3], "center": [1.0, 1.0, 0.0]},
                "density": 0.1,
                "handle": [{"vertices": [0]}, {"vertices": [2], "release": 0.02}],
            },
        ],
        "collider": [
            {"shape": "sphere", "center": [5.0, 0.0, 0.0], "radius": 0.1},
            {
                "name": "table",
                "shape": "box",
                "center": [0.0, 0.25, 0.0],
                "half_extents": [0.4, 0.05, 0.4],
            },
        ],
    }


def simulation(friction=0.8):
    return drapery.Simulation(drapery.Scene.from_dict(control_scene(friction)))


def rotation_matrix(q):
    """The rotation of the quaternion q = [x, y, z, w] (normalized here)."""
    x, y, z, w = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def about_y(angle):
    """The quaternion of a turn by `angle` about +y."""
    return [0.0, math.sin(angle / 2), 0.0, math.cos(angle / 2)]


def assert_close(x, expected, rel=1e-12):
    scale = np.abs(expected).max()
    err = np.abs(x - expected).max()
    assert err <= rel * scale, f"off by {err} (scale {scale})"


def test_handles_and_colliders_are_listed_and_named_by_index_or_name():
    sim = simulation()
    assert sim.handles == [("sheet", 0), ("flag", 0), ("flag", 1)]
    assert sim.colliders == [None, "table"]
    # cloth-local rows, in the scene's order
    assert sim.handle_vertices(0).tolist() == [0, 1, 2, 3, 4]
    assert sim.handle_vertices(0).dtype == np.int64
    assert sim.handle_vertices(("flag", 1)).tolist() == [2]
    assert sim.handle_vertices(2).tolist() == [2]
    assert sim.handle_vertices(("flag", 0)).tolist() == [0]
    # a fixed motion is the identity pose
    t, r = sim.collider_pose("table")
    assert t.tolist() == [0.0, 0.0, 0.0] and r.tolist() == [0.0, 0.0, 0.0, 1.0]
    # the same collider by index and by name; the same handle by index and by (cloth, k)
    sim.set_collider_pose(1, [0.0, 0.0, 0.01])
    sim.set_handle_pose(("flag", 0), [0.0, 0.02, 0.0])
    sim.step()
    assert sim.collider_pose("table")[0].tolist() == [0.0, 0.0, 0.01]
    assert sim.collider_pose(1)[0].tolist() == [0.0, 0.0, 0.01]
    assert sim.handle_pose(1)[0].tolist() == [0.0, 0.02, 0.0]
    assert sim.handle_pose(("flag", 0))[0].tolist() == [0.0, 0.02, 0.0]
    # the other handles did not move
    assert sim.handle_pose(0)[0].tolist() == [0.0, 0.0, 0.0]
    x0 = drapery.Simulation(sim.scene).positions("flag")
    assert_close(sim.positions("flag")[0], x0[0] + [0.0, 0.02, 0.0])


def test_handle_vertices_are_exactly_at_the_pose_set_after_the_step():
    sim = simulation()
    x0 = sim.positions("sheet")
    rows = sim.handle_vertices(0)
    c = x0[rows].mean(axis=0)  # the default pivot: the centroid at t = 0
    T = np.array([0.02, 0.05, -0.01])
    q = 2.0 * np.array(about_y(0.3))  # not normalized: set_handle_pose normalizes it
    sim.set_handle_pose(0, T, q, time=sim.time + H)
    sim.step()
    R = rotation_matrix(q)
    assert_close(sim.positions("sheet")[rows], c + T + (x0[rows] - c) @ R.T)
    t, r = sim.handle_pose(0)
    assert_close(t, T, 1e-15)
    assert_close(r, q / np.linalg.norm(q), 1e-15)

    # a pose three steps ahead: reached linearly (lerp, slerp about the same axis), then held
    T2, a2 = np.array([-0.03, 0.1, 0.02]), -0.4
    sim.set_handle_pose(0, T2, about_y(a2), time=sim.time + 3 * H)
    for k in range(1, 6):
        sim.step()
        s = min(k / 3, 1.0)
        Tk = T + s * (T2 - T)
        Rk = rotation_matrix(about_y(0.3 + s * (a2 - 0.3)))
        assert_close(sim.positions("sheet")[rows], c + Tk + (x0[rows] - c) @ Rk.T)
    # the other vertices hang below: they are free
    assert sim.positions("sheet")[5:, 1].max() < sim.positions("sheet")[rows, 1].min()


def test_a_control_loop_lifts_a_handle_step_by_step():
    sim = simulation()
    x0 = sim.positions("sheet")
    rows = sim.handle_vertices(("sheet", 0))
    for k in range(1, 11):
        t, r = sim.handle_pose(0)
        sim.set_handle_pose(0, t + [0.0, 0.01, 0.0], r)
        sim.step()
        assert_close(sim.positions("sheet")[rows], x0[rows] + [0.0, 0.01 * k, 0.0])


def test_a_moving_table_carries_the_mat_on_it_by_friction():
    def moved(friction):
        """The mat's mean displacement after it settles and the table slides 0.1 m along +x
        in 0.5 s, one set_collider_pose a step."""
        sim = simulation(friction)
        for _ in range(12):
            sim.step()
        start = sim.positions("mat").mean(axis=0)
        steps = 60
        for k in range(1, steps + 1):
            target = [0.1 * k / steps, 0.0, 0.0]
            sim.set_collider_pose("table", target)
            sim.step()
            assert sim.collider_pose("table")[0].tolist() == target
        for _ in range(12):
            sim.step()
        return sim.positions("mat").mean(axis=0) - start, sim.positions("mat")

    d, x = moved(0.8)
    # carried along +x the whole way (friction 0.8 · g could give it the table's 0.2 m/s in
    # 0.025 s: it sticks), never farther than the table went, not sideways, still on the table
    # top (y = 0.3)
    assert 0.095 < d[0] < 0.1 + 1e-9, d
    assert abs(d[2]) < 1e-3 and abs(d[1]) < 1e-3, d
    assert x[:, 1].min() > 0.3
    # without friction the table slides out from under it
    d0, _ = moved(0.0)
    assert abs(d0[0]) < 0.01, d0


def test_a_collider_pose_rotates_about_its_center():
    sim = simulation()
    q = about_y(0.2)
    sim.set_collider_pose("table", [0.0, 0.0, 0.0], q, time=sim.time + 2 * H)
    sim.step()
    t, r = sim.collider_pose("table")
    # half way: half the angle
    assert_close(r, np.array(about_y(0.1)), 1e-14)
    sim.step()
    assert_close(sim.collider_pose("table")[1], np.array(q), 1e-15)


def run_sequence():
    sim = simulation()
    for k in range(8):
        sim.set_handle_pose(0, [0.01 * k, 0.02 * k, 0.0], about_y(0.05 * k))
        sim.set_collider_pose("table", [0.0, 0.0, 0.005 * k], about_y(-0.02 * k), time=sim.time + 2 * H)
        sim.set_handle_pose(("flag", 0), [0.0, 0.0, 0.01 * k])
        sim.step()
    return sim.positions(), sim.velocities()


def test_the_same_calls_give_the_same_bits():
    (x1, v1), (x2, v2) = run_sequence(), run_sequence()
    assert x1.tobytes() == x2.tobytes() and v1.tobytes() == v2.tobytes()


def test_a_saved_state_keeps_the_poses_set_and_continues_to_the_same_bits():
    def controlled():
        sim = simulation()
        for k in range(4):
            sim.set_handle_pose(0, [0.01 * k, 0.02 * k, 0.0], about_y(0.05 * k))
            sim.step()
        # motions that end after the state is saved
        sim.set_collider_pose("table", [0.05, 0.0, 0.0], about_y(-0.1), time=sim.time + 10 * H)
        sim.set_handle_pose(("flag", 0), [0.0, 0.0, 0.03], time=sim.time + 10 * H)
        for _ in range(3):
            sim.step()
        return sim

    whole = controlled()
    state = whole.save_state()
    poses = [whole.collider_pose("table"), whole.handle_pose(0), whole.handle_pose(1)]
    for _ in range(9):
        whole.step()
    resumed = drapery.Simulation.from_state(drapery.Scene.from_dict(control_scene()), state)
    again = [resumed.collider_pose("table"), resumed.handle_pose(0), resumed.handle_pose(1)]
    for (t, r), (u, w) in zip(poses, again):
        assert t.tobytes() == u.tobytes() and r.tobytes() == w.tobytes()
    for _ in range(9):
        resumed.step()
    assert resumed.positions().tobytes() == whole.positions().tobytes()
    assert resumed.velocities().tobytes() == whole.velocities().tobytes()
    # the scene's own motions would have left the table where it was
    assert resumed.collider_pose("table")[0].tolist() == [0.05, 0.0, 0.0]


@pytest.mark.parametrize(
    "call, error, message",
    [
        (lambda s: s.set_collider_pose("chair", [0, 0, 0]), ValueError, "collider: no collider named 'chair'"),
        (lambda s: s.set_collider_pose(2, [0, 0, 0]), IndexError, "collider: 2 is out of range"),
        (lambda s: s.set_collider_pose(-1, [0, 0, 0]), IndexError, "collider: -1 is out of range"),
        (lambda s: s.set_collider_pose(1.0, [0, 0, 0]), TypeError, "collider: expected"),
        (lambda s: s.collider_pose("chair"), ValueError, "collider: no collider named"),
        (lambda s: s.set_handle_pose(3, [0, 0, 0]), IndexError, "handle: 3 is out of range: the scene has 3 handles"),
        (lambda s: s.set_handle_pose(("sheet", 1), [0, 0, 0]), IndexError, "handle: 1 is out of range: cloth 'sheet' has 1 handle"),
        (lambda s: s.set_handle_pose(("mat", 0), [0, 0, 0]), IndexError, "cloth 'mat' has 0 handles"),
        (lambda s: s.set_handle_pose(("cape", 0), [0, 0, 0]), ValueError, "handle: no cloth named 'cape'"),
        (lambda s: s.set_handle_pose(("sheet",), [0, 0, 0]), TypeError, "handle: expected"),
        (lambda s: s.handle_vertices("sheet"), TypeError, "handle: expected"),
        (lambda s: s.set_handle_pose(0, [0, math.nan, 0]), ValueError, "translation: must be finite"),
        (lambda s: s.set_handle_pose(0, [0, 0]), ValueError, r"translation: expected an array of shape \(3,\)"),
        (lambda s: s.set_handle_pose(0, "up"), ValueError, "translation: expected"),
        (lambda s: s.set_collider_pose(1, [0, 0, 0], [0, 0, 0, 0]), ValueError, "rotation: the zero quaternion"),
        (lambda s: s.set_collider_pose(1, [0, 0, 0], [0, math.inf, 0, 1]), ValueError, "rotation: must be finite"),
        (lambda s: s.set_collider_pose(1, [0, 0, 0], [0, 0, 1]), ValueError, r"rotation: expected an array of shape \(4,\)"),
        (lambda s: s.set_collider_pose(1, [0, 0, 0], time=s.time), ValueError, "time: must be a finite time later than sim.time"),
        (lambda s: s.set_handle_pose(0, [0, 0, 0], time=math.nan), ValueError, "time:"),
    ],
)
def test_bad_arguments_raise_naming_the_argument_and_change_nothing(call, error, message):
    sim, untouched = simulation(), simulation()
    sim.step()
    untouched.step()
    with pytest.raises(error, match=message):
        call(sim)
    sim.step()
    untouched.step()
    assert sim.positions().tobytes() == untouched.positions().tobytes()


def test_a_released_handle_cannot_be_driven():
    sim = simulation()
    sim.set_handle_pose(("flag", 1), [0.0, 0.01, 0.0])  # before its release: allowed
    for _ in range(3):
        sim.step()
    assert sim.time > 0.02
    with pytest.raises(ValueError, match="handle: handle 2 was released at 0.02 s"):
        sim.set_handle_pose(("flag", 1), [0.0, 0.0, 0.0])
