"""drapery: cloth simulation (linearized implicit Euler, Baraff & Witkin 1998) from Python.

Load a scene, step it, read and write numpy arrays::

    import drapery
    scene = drapery.load_scene("examples/hang.toml")
    sim = drapery.Simulation(scene)
    sim.advance(frames=30)
    x = sim.positions("sheet")        # float64, shape (n, 3)

Stepping from Python gives the same bits as ``drapery run`` of the same scene.
``drapery.sweep(scene, params, output)`` runs a scene once per parameter sample (a data set),
on a process pool or on Ray; see drapery/sweep.py and the command ``drapery-sweep``.
"""

from . import _drapery
from ._drapery import *  # noqa: F401,F403 (the names of _drapery.__all__, typed in _drapery.pyi)

from .sweep import sweep  # the function (the module stays importable as drapery.sweep)

__all__ = list(_drapery.__all__) + ["sweep"]
