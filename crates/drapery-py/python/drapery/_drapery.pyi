"""Type stubs of the native module drapery._drapery (re-exported by drapery)."""

import os
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt

__all__ = [
    "DraperyError",
    "Scene",
    "SceneError",
    "Simulation",
    "SimulationError",
    "StateError",
    "load_scene",
    "run",
    "scene_toml",
    "__version__",
]

__version__: str

_StrPath = Union[str, "os.PathLike[str]"]
# A collider: its index in the scene or its ``name``.
_Collider = Union[int, str]
# A handle: its index in ``Simulation.handles`` or ``(cloth name, k)``, the cloth's k-th handle.
_Handle = Union[int, Tuple[str, int]]
# A pose: translation (3,) and rotation, a unit quaternion [x, y, z, w] (4,).
_Pose = Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]

class DraperyError(Exception):
    """Base class of drapery's errors."""

class SceneError(DraperyError):
    """A scene (file, dict, mesh) that cannot be loaded; the message names the file and the field."""

class SimulationError(DraperyError):
    """A step that failed (non-finite state, solver failure, blow-up); the simulation is left as it was before that step."""

class StateError(DraperyError):
    """Saved state bytes that are damaged or belong to another scene."""

@final
class Scene:
    """A loaded and validated scene: its time span, step and cloths. Immutable."""

    @staticmethod
    def from_dict(d: Mapping[str, Any]) -> "Scene":
        """A scene from a dict with the scene file's keys (checked as a file is, errors naming
        ``<dict>``); mesh paths are relative to the current directory."""
    @property
    def path(self) -> str:
        """The scene file as given, or ``<dict>``."""
    @property
    def duration(self) -> float:
        """Simulated time span, s."""
    @property
    def frame_rate(self) -> float:
        """Output frames per simulated second."""
    @property
    def step_size(self) -> float:
        """The step actually taken, s: 1/(frame_rate · steps_per_frame)."""
    @property
    def steps_per_frame(self) -> int:
        """Steps per output frame."""
    @property
    def frame_count(self) -> int:
        """Frames after frame 0 (a run writes frame_count + 1 frames)."""
    @property
    def cloths(self) -> list[str]:
        """The cloths' names, in scene order."""
    @property
    def fingerprint(self) -> int:
        """A 64-bit hash of the scene text and meshes (as ``drapery run`` computes it)."""

def load_scene(path: _StrPath) -> Scene:
    """Reads and checks a scene file (TOML) and its meshes; raises SceneError."""

@final
class Simulation:
    """A simulation of a scene, at its initial state.

    ``threads``: the size of a thread pool of this simulation's own that every step runs in
    (default: rayon's global pool, one thread per core). Same bits whatever the thread count.
    """

    def __new__(cls, scene: Scene, threads: Optional[int] = None) -> "Simulation": ...
    @staticmethod
    def from_state(scene: Scene, state: bytes, threads: Optional[int] = None) -> "Simulation":
        """Continues from ``save_state()`` bytes (or a ``drapery run`` folder's state.bin) to the
        same bits as the run that saved them; raises StateError."""
    def step(self) -> None:
        """One step of ``scene.step_size`` seconds; raises SimulationError."""
    def advance(self, frames: int = 1) -> None:
        """``frames`` frames of ``scene.steps_per_frame`` steps; Ctrl-C interrupts it between steps."""
    @property
    def time(self) -> float:
        """Simulated time, s."""
    @property
    def steps(self) -> int:
        """Steps taken since the initial state."""
    @property
    def tangled(self) -> tuple[int, int]:
        """What is still tangled: (vertices inside colliders, crossed cloth triangle pairs)."""
    @property
    def close_pairs(self) -> Optional[tuple[int, float]]:
        """Cloth pairs closer than collision.thickness now: (count, distance of the closest), or None without self-collision."""
    @property
    def start_warnings(self) -> list[str]:
        """What ``drapery run`` would warn of, were a run to start from the current state: intersections the steps will not untangle, cloth pairs closer than collision.thickness (``[]`` for a clean start)."""
    @property
    def frame(self) -> int:
        """Whole frames of steps taken: steps // scene.steps_per_frame."""
    @property
    def scene(self) -> Scene:
        """The scene simulated."""
    @property
    def cloths(self) -> list[str]:
        """The cloths' names, in particle order."""
    @property
    def last_report(self) -> Optional[Dict[str, Any]]:
        """The last step's report (iterations, contacts, ``stages``: seconds per stage), or None."""
    def positions(self, cloth: Optional[str] = None) -> npt.NDArray[np.float64]:
        """Positions, m, shape (n, 3): every particle, or those of the cloth named."""
    def velocities(self, cloth: Optional[str] = None) -> npt.NDArray[np.float64]:
        """Velocities, m/s, shape (n, 3)."""
    def set_positions(self, positions: npt.ArrayLike, cloth: Optional[str] = None) -> None:
        """Sets positions (shape (n, 3)); ValueError on a wrong shape or a non-finite value."""
    def set_velocities(self, velocities: npt.ArrayLike, cloth: Optional[str] = None) -> None:
        """Sets velocities (shape (n, 3)); as set_positions."""
    def faces(self, cloth: Optional[str] = None) -> npt.NDArray[np.int64]:
        """Triangles, shape (m, 3): of the cloth named (indexing positions(cloth)) or of all."""
    @property
    def colliders(self) -> List[Optional[str]]:
        """The colliders' names (None where a collider has none), in scene order."""
    @property
    def handles(self) -> List[Tuple[str, int]]:
        """Every handle as ``(cloth name, k)``, in the order of the handle indices."""
    def set_collider_pose(
        self,
        collider: _Collider,
        translation: npt.ArrayLike,
        rotation: npt.ArrayLike = (0.0, 0.0, 0.0, 1.0),
        time: Optional[float] = None,
    ) -> None:
        """Moves a collider linearly from its pose at ``sim.time`` to ``translation``,
        ``rotation`` (quaternion [x, y, z, w]: x = c + T + R (x0 - c), c its center), reached at
        ``time`` (default: the end of the next step) and held; IndexError, ValueError or
        TypeError naming the argument. ``save_state()`` keeps the motions set this way."""
    def set_handle_pose(
        self,
        handle: _Handle,
        translation: npt.ArrayLike,
        rotation: npt.ArrayLike = (0.0, 0.0, 0.0, 1.0),
        time: Optional[float] = None,
    ) -> None:
        """Moves a handle's vertices as ``set_collider_pose`` a collider (about its pivot);
        ValueError too for a handle already released."""
    def collider_pose(self, collider: _Collider) -> _Pose:
        """``(translation, rotation)`` of a collider at ``sim.time``."""
    def handle_pose(self, handle: _Handle) -> _Pose:
        """``(translation, rotation)`` of a handle at ``sim.time``."""
    def handle_vertices(self, handle: _Handle) -> npt.NDArray[np.int64]:
        """The handle's vertices: rows of ``positions(cloth)``, cloth ``handles[i][0]``."""
    def save_state(self) -> bytes:
        """The whole state, exact to the bit, with the scene's fingerprint (and the collider
        and handle motions set from Python, if any)."""

def run(
    scene: Union[Scene, _StrPath],
    output: _StrPath,
    formats: Union[Sequence[str], str, None] = None,
    threads: Optional[int] = None,
    on_frame: Optional[Callable[[int, npt.NDArray[np.float64]], object]] = None,
) -> None:
    """Simulates ``scene`` and writes frame_00000.obj … into ``output`` as ``drapery run`` does
    (byte for byte); formats "obj" (default), "ply" and/or "pc2" (``<cloth name>.pc2`` caches). ``on_frame(k, positions)`` is called
    after frame k is written, with every particle's positions (float64, (n, 3)); with
    ``formats=[]`` and ``on_frame`` no file is written. Warns (RuntimeWarning) where the command
    warns at frame 0: intersections the steps will not untangle, cloth pairs closer than
    ``collision.thickness``."""

def scene_toml(d: Mapping[str, Any]) -> str:
    """The TOML text of a scene dict, as ``Scene.from_dict`` reads it (not checked as a scene);
    mesh paths are written as given."""
