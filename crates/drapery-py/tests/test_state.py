"""Saved states: a run continued from its bytes gives the bits of an uninterrupted one."""

import numpy as np
import pytest

import drapery
from conftest import cli_run, read_ply_positions


def test_continuing_from_a_saved_state_gives_the_bits_of_an_uninterrupted_run(drape_path):
    scene = drapery.load_scene(drape_path)
    whole = drapery.Simulation(scene)
    whole.advance(12)

    first = drapery.Simulation(scene)
    first.advance(5)  # contact with the sphere starts later: the rest is in contact
    state = first.save_state()
    assert isinstance(state, bytes)
    second = drapery.Simulation.from_state(scene, state, threads=1)
    assert second.steps == first.steps and second.frame == 5 and second.time == first.time
    assert second.positions().tobytes() == first.positions().tobytes()
    assert second.velocities().tobytes() == first.velocities().tobytes()
    second.advance(7)
    assert not np.array_equal(second.positions(), first.positions())
    assert second.positions().tobytes() == whole.positions().tobytes()
    assert second.velocities().tobytes() == whole.velocities().tobytes()
    assert second.time == whole.time


def test_a_state_of_another_scene_is_refused(drape_path, hang_dict):
    drape = drapery.Simulation(drapery.load_scene(drape_path))
    drape.step()
    state = drape.save_state()
    with pytest.raises(drapery.StateError, match="another scene"):
        drapery.Simulation.from_state(drapery.Scene.from_dict(hang_dict), state)
    # the same particle count but another scene (a different stiffness) is refused too
    other = drape_path.read_text().replace("bend_stiffness = 0.5", "bend_stiffness = 0.6")
    other_path = drape_path.with_name("other.toml")
    other_path.write_text(other)
    with pytest.raises(drapery.StateError, match="another scene"):
        drapery.Simulation.from_state(drapery.load_scene(other_path), state)


def test_damaged_state_bytes_are_refused_with_the_librarys_reason(drape_path):
    scene = drapery.load_scene(drape_path)
    sim = drapery.Simulation(scene)
    sim.step()
    state = bytearray(sim.save_state())
    state[len(state) // 2] ^= 1
    with pytest.raises(drapery.StateError, match="checksum"):
        drapery.Simulation.from_state(scene, bytes(state))
    with pytest.raises(drapery.StateError, match="damaged"):
        drapery.Simulation.from_state(scene, b"not a state")


def test_the_commands_state_file_continues_to_the_commands_frames(tmp_path, drape_path, drapery_bin):
    """A run stopped by the CLI after frame 6, continued in Python, reaches the CLI's last frame."""
    scene = drapery.load_scene(drape_path)
    full, part = tmp_path / "full", tmp_path / "part"
    cli_run(drapery_bin, drape_path, full, "ply")
    import subprocess

    r = subprocess.run(
        [str(drapery_bin), "run", str(drape_path), "--output", str(part), "--format", "ply",
         "--quiet", "--stop-after-frames", "6"],
        capture_output=True, text=True,
    )
    assert r.returncode != 0 and "stopped after frame 6" in r.stderr
    sim = drapery.Simulation.from_state(scene, (part / "state.bin").read_bytes())
    assert sim.frame == 6
    sim.advance(scene.frame_count - 6)
    last = read_ply_positions(full / f"frame_{scene.frame_count:05d}.ply")
    assert sim.positions().tobytes() == last.tobytes()


def test_a_dict_scenes_state_loads_into_the_same_dict_written_in_another_key_order(hang_dict):
    sim = drapery.Simulation(drapery.Scene.from_dict(hang_dict))
    sim.advance(2)
    reordered = {k: hang_dict[k] for k in reversed(list(hang_dict))}
    reordered["cloth"] = [{k: v for k, v in reversed(list(hang_dict["cloth"][0].items()))}]
    again = drapery.Simulation.from_state(drapery.Scene.from_dict(reordered), sim.save_state())
    assert again.positions().tobytes() == sim.positions().tobytes()
    hang_dict["cloth"][0]["density"] = 0.2
    with pytest.raises(drapery.StateError, match="another scene"):
        drapery.Simulation.from_state(drapery.Scene.from_dict(hang_dict), sim.save_state())
