"""Scenes from files and dicts: properties, the same scene either way, the library's errors."""

import subprocess

import numpy as np
import pytest

import drapery
from conftest import EXAMPLES, HANG


def test_a_dict_scene_has_the_timing_and_cloths_it_was_given(hang_dict):
    s = drapery.Scene.from_dict(hang_dict)
    assert s.path == "<dict>"
    assert s.cloths == ["sheet"]
    assert s.steps_per_frame == 2
    assert s.frame_count == 6
    assert s.step_size == 1.0 / (60 * 2)
    assert s.duration == 0.1 and s.frame_rate == 60


def test_a_dict_steps_to_the_same_bits_as_the_same_scene_from_a_file(tmp_path, hang_dict):
    toml = """\
[simulation]
duration = 0.1
dt = 0.008333333333333333
frame_rate = 60

[[cloth]]
name = "sheet"
grid = { size = [0.4, 0.4], resolution = [7, 7], center = [0.0, 1.0, 0.0] }
density = 0.1
bend_stiffness = 0.5
pin = [0, 6]
initial_velocity = [0.0, 0.0, 0.5]
"""
    path = tmp_path / "hang.toml"
    path.write_text(toml)
    from_file = drapery.Simulation(drapery.load_scene(path))
    from_dict = drapery.Simulation(drapery.Scene.from_dict(hang_dict))
    for sim in (from_file, from_dict):
        sim.advance(3)
    a, b = from_file.positions(), from_dict.positions()
    assert not np.array_equal(a, drapery.Simulation(drapery.load_scene(path)).positions())
    assert a.tobytes() == b.tobytes()


def test_numpy_values_and_tuples_are_accepted_in_a_dict(hang_dict):
    c = hang_dict["cloth"][0]
    c["grid"]["center"] = np.array([0.0, 1.0, 0.0])
    c["grid"]["resolution"] = (np.int64(7), np.int32(7))
    c["density"] = np.float32(0.1)
    s = drapery.Scene.from_dict(hang_dict)
    x = drapery.Simulation(s).positions()
    assert x.shape == (49, 3)
    assert np.allclose(x.mean(axis=0), [0.0, 1.0, 0.0])


def test_mesh_paths_in_a_dict_are_relative_to_the_current_directory(monkeypatch):
    monkeypatch.chdir(EXAMPLES)
    s = drapery.Scene.from_dict(
        {
            "simulation": {"duration": 0.05, "dt": 0.01, "frame_rate": 20},
            "cloth": [{"name": "rope", "mesh": "chain.obj", "vertex_mass": 0.01, "pin": [0]}],
        }
    )
    obj_vertices = sum(1 for l in (EXAMPLES / "chain.obj").read_text().splitlines() if l.startswith("v "))
    assert drapery.Simulation(s).positions().shape == (obj_vertices, 3)


def test_dict_errors_are_the_loaders_one_line_messages_naming_the_field(hang_dict):
    hang_dict["cloth"][0]["density"] = -1.0
    with pytest.raises(drapery.SceneError) as e:
        drapery.Scene.from_dict(hang_dict)
    m = str(e.value)
    assert m.startswith("<dict>: ") and "density" in m and "\n" not in m
    assert "line " not in m, "line numbers of the generated TOML mean nothing to a dict's user"


def test_a_misspelt_key_in_a_dict_is_refused_by_name(hang_dict):
    hang_dict["cloth"][0]["bend_stifness"] = 1.0
    with pytest.raises(drapery.SceneError, match="bend_stifness"):
        drapery.Scene.from_dict(hang_dict)


def test_values_a_scene_cannot_hold_are_refused_naming_the_key(hang_dict):
    hang_dict["cloth"][0]["damping"] = None
    with pytest.raises(drapery.SceneError, match=r"cloth\[0\]\.damping: None"):
        drapery.Scene.from_dict(hang_dict)
    hang_dict["cloth"][0]["damping"] = object()
    with pytest.raises(drapery.SceneError, match=r"cloth\[0\]\.damping: a value of type object"):
        drapery.Scene.from_dict(hang_dict)
    with pytest.raises(TypeError):
        drapery.Scene.from_dict([HANG])


def test_file_errors_are_the_same_messages_as_the_commands(tmp_path, drapery_bin):
    bad = tmp_path / "bad.toml"
    bad.write_text((EXAMPLES / "hang.toml").read_text().replace("density = 0.1", "density = -0.1"))
    with pytest.raises(drapery.SceneError) as e:
        drapery.load_scene(bad)
    cli = subprocess.run([str(drapery_bin), "validate", str(bad)], capture_output=True, text=True)
    assert cli.returncode != 0
    assert cli.stderr.strip() == f"error: {e.value}"
    assert str(bad) in str(e.value) and "density" in str(e.value)


def test_a_missing_scene_file_is_a_scene_error_naming_it(tmp_path):
    with pytest.raises(drapery.SceneError, match="nowhere.toml"):
        drapery.load_scene(tmp_path / "nowhere.toml")
    assert issubclass(drapery.SceneError, drapery.DraperyError)
