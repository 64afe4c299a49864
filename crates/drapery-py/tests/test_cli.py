"""The same bits from Python as from the drapery command."""

import numpy as np
import pytest

import drapery
from conftest import cli_run, read_ply_positions


def test_stepping_from_python_gives_the_bits_of_drapery_run(tmp_path, drape_path, drapery_bin):
    out = tmp_path / "cli"
    cli_run(drapery_bin, drape_path, out, "ply")
    scene = drapery.load_scene(drape_path)
    sim = drapery.Simulation(scene)
    moved = False
    for k in range(scene.frame_count + 1):
        if k > 0:
            sim.advance(1)
        cli = read_ply_positions(out / f"frame_{k:05d}.ply")
        assert sim.positions().tobytes() == cli.tobytes(), f"frame {k}"
        moved = moved or not np.array_equal(cli, read_ply_positions(out / "frame_00000.ply"))
    assert moved
    # the cloth reached the sphere: the run covered contact and friction
    sheet = sim.positions("sheet")
    assert np.linalg.norm(sheet - [0.0, 0.15, 0.0], axis=1).min() < 0.15 + 0.02
    assert sim.last_report["obstacle_contacts"] > 0


@pytest.mark.parametrize("formats", [["obj"], ["obj", "ply"]])
def test_drapery_run_writes_the_commands_files_byte_for_byte(tmp_path, drape_path, drapery_bin, formats):
    cli, py = tmp_path / "cli", tmp_path / "py"
    cli_run(drapery_bin, drape_path, cli, ",".join(formats))
    drapery.run(drape_path, py, formats=formats, threads=2)
    names = sorted(p.name for p in py.iterdir())
    frames = drapery.load_scene(drape_path).frame_count + 1
    assert names == sorted(f"frame_{k:05d}.{ext}" for k in range(frames) for ext in formats)
    for name in names:
        assert (py / name).read_bytes() == (cli / name).read_bytes(), name


def test_drapery_run_writes_the_commands_point_caches_byte_for_byte(tmp_path, drape_path, drapery_bin):
    cli, py = tmp_path / "cli", tmp_path / "py"
    cli_run(drapery_bin, drape_path, cli, "pc2")
    drapery.run(drape_path, py, formats="pc2")
    assert sorted(p.name for p in py.iterdir()) == ["patch.pc2", "sheet.pc2"]
    scene = drapery.load_scene(drape_path)
    sim = drapery.Simulation(scene)
    sim.advance(scene.frame_count)
    for name in ["sheet", "patch"]:
        data = (py / f"{name}.pc2").read_bytes()
        assert data == (cli / f"{name}.pc2").read_bytes(), name
        # the header counts every frame; the last sample is the f32 of the last frame
        n = len(sim.positions(name))
        assert np.frombuffer(data[16:20], "<i4")[0] == n
        assert np.frombuffer(data[28:32], "<i4")[0] == scene.frame_count + 1
        last = np.frombuffer(data[len(data) - 12 * n :], "<f4").reshape(n, 3)
        assert np.array_equal(last, sim.positions(name).astype(np.float32))


def test_drapery_run_takes_a_scene_object_and_a_comma_list(tmp_path, hang_dict):
    scene = drapery.Scene.from_dict(hang_dict)
    drapery.run(scene, tmp_path, formats="ply,obj")
    last = tmp_path / f"frame_{scene.frame_count:05d}.ply"
    sim = drapery.Simulation(scene)
    sim.advance(scene.frame_count)
    assert read_ply_positions(last).tobytes() == sim.positions().tobytes()
    assert (tmp_path / f"frame_{scene.frame_count:05d}.obj").is_file()


def test_drapery_run_refuses_formats_it_does_not_write_before_writing(tmp_path, drape_path):
    out = tmp_path / "out"
    with pytest.raises(ValueError, match="'glb'.*drapery command"):
        drapery.run(drape_path, out, formats=["obj", "glb"])
    with pytest.raises(ValueError, match="unknown format 'png'"):
        drapery.run(drape_path, out, formats="png")
    assert not out.exists()
    with pytest.raises(drapery.SceneError, match="missing.toml"):
        drapery.run(tmp_path / "missing.toml", out)


def test_a_prerolled_scene_gives_the_bits_of_drapery_run(tmp_path, drape_path, drapery_bin):
    """`[simulation] preroll`: Python's Simulation and drapery.run settle the cloth before
    frame 0 exactly as the command does."""
    text = drape_path.read_text().replace("frame_rate = 60\n", "frame_rate = 60\npreroll = 0.1\n", 1)
    scene_path = tmp_path / "preroll.toml"
    scene_path.write_text(text)
    out = tmp_path / "cli"
    cli_run(drapery_bin, scene_path, out, "ply")
    scene = drapery.load_scene(scene_path)
    sim = drapery.Simulation(scene)
    assert sim.time == 0.0
    first = read_ply_positions(out / "frame_00000.ply")
    assert sim.positions().tobytes() == first.tobytes()
    # the pre-roll moved the cloth: frame 0 is not the scene's initial grid
    plain = drapery.Simulation(drapery.load_scene(drape_path))
    assert not np.array_equal(plain.positions(), first)
    sim.advance(2)
    assert sim.positions().tobytes() == read_ply_positions(out / "frame_00002.ply").tobytes()
    py_out = tmp_path / "py"
    drapery.run(scene_path, py_out, formats=["ply"])
    assert (py_out / "frame_00000.ply").read_bytes() == (out / "frame_00000.ply").read_bytes()
