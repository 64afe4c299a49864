"""Data-set sweeps: ``drapery.sweep`` (documented there: ``help(drapery.sweep)``) and the
console command ``drapery-sweep`` (``main``; ``drapery-sweep --help``)."""

from __future__ import annotations

import argparse
import copy
import hashlib
import itertools
import json
import math
import multiprocessing
import operator
import os
import random
import re
import shutil
import sys
import time
import zipfile
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _drapery

__all__ = ["sweep", "main"]

MANIFEST = "manifest.jsonl"
DONE = "done.json"
SCENE = "scene.toml"
NPZ = "frames.npz"
# The time every member of frames.npz is stamped with (zip's earliest), so that the file's
# bytes depend on its arrays only.
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)
# The scene keys that name files, relative to the scene file's folder.
_MESH_TABLES = ("cloth", "collider")

PathLike = Union[str, "os.PathLike[str]"]


# ---------------------------------------------------------------------------------------------
# The base scene and key paths


def _read_toml(path: Path) -> Dict[str, Any]:
    if sys.version_info >= (3, 11):
        import tomllib
    else:
        try:
            import tomli as tomllib
        except ImportError as e:
            raise ImportError(
                "reading a scene file for a sweep needs tomli on Python < 3.11: "
                "pip install 'drapery[sweep]' (or pass the scene as a dict)"
            ) from e
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except OSError:
        _drapery.load_scene(path)  # raises the library's message naming the file
        raise
    except tomllib.TOMLDecodeError:
        _drapery.load_scene(path)
        raise


def _base_scene(scene: Union[Mapping[str, Any], PathLike]) -> Dict[str, Any]:
    """The scene as a dict, its mesh paths made absolute (relative to the scene file's folder,
    or to the current directory for a dict)."""
    if isinstance(scene, _drapery.Scene):
        if scene.path == "<dict>":
            raise TypeError("sweep: a Scene made from a dict cannot be swept; pass the dict itself")
        scene = scene.path
    if isinstance(scene, Mapping):
        base, folder = copy.deepcopy(dict(scene)), Path.cwd()
    elif isinstance(scene, (str, os.PathLike)):
        path = Path(scene)
        base, folder = _read_toml(path), path.resolve().parent
    else:
        raise TypeError(f"sweep: scene must be a path or a dict, not {type(scene).__name__}")
    for table in _MESH_TABLES:
        items = base.get(table)
        if isinstance(items, list):
            for item in items:
                if isinstance(item, dict) and isinstance(item.get("mesh"), str):
                    item["mesh"] = os.path.join(folder, item["mesh"])
    return base


def _segments(path: str) -> List[str]:
    if not isinstance(path, str) or not path or any(not s for s in path.split(".")):
        raise ValueError(f"parameter {path!r}: a key path is dot-separated names, e.g. cloth.sheet.bend_stiffness")
    return path.split(".")


def _element(items: List[Any], seg: str, at: str) -> int:
    """The index in an array that `seg` selects: the table named `seg`, else index `seg`."""
    for i, item in enumerate(items):
        if isinstance(item, dict) and item.get("name") == seg:
            return i
    if seg.isdigit() and int(seg) < len(items):
        return int(seg)
    names = [str(it["name"]) for it in items if isinstance(it, dict) and "name" in it]
    known = f"names {', '.join(names)}; " if names else ""
    raise ValueError(f"{at}: no element '{seg}' ({known}indices 0 to {len(items) - 1})" if items else f"{at}: no element '{seg}' (the array is empty)")


def _assign(scene: Dict[str, Any], path: str, value: Any) -> None:
    """Sets the key `path` of `scene` to `value`, creating missing tables and the last key."""
    segs = _segments(path)
    node: Any = scene
    for depth, seg in enumerate(segs):
        at = f"parameter {path}: " + ".".join(segs[:depth]) if depth else f"parameter {path}"
        last = depth == len(segs) - 1
        if isinstance(node, dict):
            if last:
                node[seg] = value
            else:
                node = node.setdefault(seg, {})
        elif isinstance(node, list):
            i = _element(node, seg, at)
            if last:
                node[i] = value
            else:
                node = node[i]
        else:
            raise ValueError(f"{at}: is a value ({node!r}), not a table or array")


def _unknown_key(message: str, path: str) -> bool:
    """Whether the loader's message refuses a key of `path` as unknown."""
    # serde's wording (most tables) or the typed key reader's (cloth, collider, garment, ...)
    m = re.search(r"unknown field `([^`]*)`", message) or re.search(
        r"\.([A-Za-z0-9_]+): unknown key of", message
    )
    return m is not None and m.group(1) in path.split(".")


def _check_paths(base: Dict[str, Any], params: "List[_Param]", first: Dict[str, Any]) -> None:
    """One clear error for a parameter path the scene cannot take, before anything runs."""
    for p in params:
        probe = copy.deepcopy(base)
        _assign(probe, p.path, first[p.path])
        try:
            _drapery.Scene.from_dict(probe)
        except _drapery.SceneError as e:
            if _unknown_key(str(e), p.path):
                raise ValueError(f"parameter {p.path}: not a key of the scene format ({e})") from None


# ---------------------------------------------------------------------------------------------
# Parameters and samples


def _plain(v: Any) -> Any:
    """numpy scalars and arrays, tuples: as JSON and TOML values."""
    if hasattr(v, "tolist") and not isinstance(v, (str, bytes)):
        v = v.tolist()
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    return v


class _Param:
    def __init__(self, path: str, spec: Any):
        _segments(path)
        self.path = path
        self.values: Optional[List[Any]] = None
        self.low = self.high = 0.0
        self.log = False
        if isinstance(spec, Mapping):
            extra = set(spec) - {"low", "high", "log"}
            if extra or not {"low", "high"} <= set(spec):
                raise ValueError(f"parameter {path}: a range is {{'low': a, 'high': b, 'log': bool}}, got keys {sorted(spec)}")
            try:
                self.low, self.high = float(spec["low"]), float(spec["high"])
            except (TypeError, ValueError):
                raise ValueError(f"parameter {path}: low and high must be numbers") from None
            self.log = bool(spec.get("log", False))
            if not (math.isfinite(self.low) and math.isfinite(self.high) and self.low <= self.high):
                raise ValueError(f"parameter {path}: a range needs finite low <= high, got {self.low}, {self.high}")
            if self.log and self.low <= 0:
                raise ValueError(f"parameter {path}: a log range needs low > 0, got {self.low}")
        else:
            values = _plain(spec)
            if isinstance(values, (str, bytes)) or not isinstance(values, list) or not values:
                raise ValueError(f"parameter {path}: give a non-empty list of values or a range dict, got {spec!r}")
            self.values = values

    def draw(self, rng: random.Random) -> float:
        u = rng.random()
        if self.log:
            lo, hi = math.log(self.low), math.log(self.high)
            return min(max(math.exp(lo + u * (hi - lo)), self.low), self.high)
        return self.low + u * (self.high - self.low)


def _plan(params: Mapping[str, Any], samples: Optional[int], seed: int) -> Tuple[List[_Param], List[Dict[str, Any]]]:
    """The parameters and every sample's values, in sweep order."""
    if not isinstance(params, Mapping) or not params:
        raise ValueError("sweep: params must be a non-empty dict of key path -> list or range")
    ps = [_Param(k, v) for k, v in params.items()]
    grid = [p for p in ps if p.values is not None]
    ranges = [p for p in ps if p.values is None]
    if ranges:
        if _count(samples) is None:
            raise ValueError(f"sweep: range parameters need samples (a count >= 1), got {samples!r}")
        samples = _count(samples)
        assert samples is not None
        rng = random.Random(seed)
        draws = [[p.draw(rng) for p in ranges] for _ in range(samples)]
    else:
        if samples is not None:
            raise ValueError("sweep: samples is the number of random draws of range parameters; these params are all lists (a grid)")
        draws = [[]]
    plan = []
    for point in itertools.product(*(p.values or [] for p in grid)):
        for draw in draws:
            values = dict(zip((p.path for p in grid), point))
            values.update(zip((p.path for p in ranges), draw))
            plan.append({p.path: values[p.path] for p in ps})
    return ps, plan


def _count(n: Any) -> Optional[int]:
    """`n` as a whole number >= 1 (int or numpy integer), or None."""
    if isinstance(n, bool):
        return None
    try:
        n = operator.index(n)
    except TypeError:
        return None
    return n if n >= 1 else None


def _hash(obj: Any) -> str:
    text = json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _formats(frames: Union[Sequence[str], str, None]) -> List[str]:
    if frames is None:
        return ["obj"]
    if isinstance(frames, str):
        frames = [] if frames.strip() in ("", "none") else [f.strip() for f in frames.split(",")]
    out = list(frames)
    for f in out:
        if f not in ("obj", "ply"):
            raise ValueError(f"sweep: frames: unknown format {f!r} (obj, ply, or none)")
    return out


# ---------------------------------------------------------------------------------------------
# One sample (in a worker process or Ray task)


def _save_npz(path: Path, arrays: Mapping[str, np.ndarray]) -> None:
    """An .npz whose bytes depend only on the arrays (np.savez stamps the current time)."""
    tmp = path.with_name(path.name + ".tmp")
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_STORED) as z:
        for name, a in arrays.items():
            info = zipfile.ZipInfo(name + ".npy", date_time=_ZIP_TIME)
            with z.open(info, "w", force_zip64=True) as f:
                np.lib.format.write_array(f, np.ascontiguousarray(a), allow_pickle=False)
    os.replace(tmp, path)


def _write_json(path: Path, obj: Any) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(obj, indent=1) + "\n")
    os.replace(tmp, path)


def _run_sample(job: Dict[str, Any]) -> Dict[str, Any]:
    """Runs one sample into its folder; its manifest record (never raises for the sample's own
    failures)."""
    start = time.perf_counter()
    folder = Path(job["dir"])
    try:
        if folder.exists():
            shutil.rmtree(folder)
        folder.mkdir(parents=True)
        (folder / SCENE).write_text(_drapery.scene_toml(job["scene"]))
        scene = _drapery.load_scene(folder / SCENE)
        frames: List[np.ndarray] = []
        _drapery.run(
            scene,
            folder,
            formats=job["formats"],
            threads=job["threads"],
            on_frame=lambda k, x: frames.append(x.astype(np.float32)),
        )
        sim = _drapery.Simulation(scene, threads=job["threads"])
        sizes = [sim.positions(c).shape[0] for c in sim.cloths]
        _save_npz(
            folder / NPZ,
            {
                "positions": np.stack(frames),
                "faces": sim.faces(),
                "cloths": np.array(sim.cloths, dtype=str),
                "offsets": np.cumsum([0] + sizes, dtype=np.int64),
                "times": np.arange(len(frames), dtype=np.float64) / scene.frame_rate,
            },
        )
        record = _record(job, time.perf_counter() - start)
        _write_json(folder / DONE, {"id": job["id"], "scene_hash": job["scene_hash"], "params_hash": job["params_hash"], "frames": len(frames)})
        return record
    except Exception as e:  # a failed sample is recorded; the sweep goes on
        return _record(job, time.perf_counter() - start, e)


def _record(job: Dict[str, Any], wall_time: float, error: Optional[BaseException] = None) -> Dict[str, Any]:
    """A sample's manifest line: ok, or failed with `error`."""
    record: Dict[str, Any] = {
        "id": job["id"],
        "params": job["params"],
        "params_hash": job["params_hash"],
        "status": "ok" if error is None else "failed",
        "wall_time": wall_time,
    }
    if error is not None:
        record["error"] = str(error)
        record["error_type"] = type(error).__name__
    return record


# ---------------------------------------------------------------------------------------------
# Backends: each calls done(job, record) as samples finish, in any order


def _local(jobs: List[Dict[str, Any]], workers: int, done: Callable[[Dict[str, Any], Dict[str, Any]], None]) -> None:
    # spawn: a forked child would inherit a rayon pool whose threads it does not have
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=min(workers, len(jobs)), mp_context=ctx) as pool:
        futures = {pool.submit(_run_sample, job): job for job in jobs}
        try:
            while futures:
                finished, _ = wait(futures, return_when=FIRST_COMPLETED)
                for f in finished:
                    job = futures.pop(f)
                    try:
                        record = f.result()
                    except Exception as e:  # the worker process died
                        record = _record(job, 0.0, e)
                    done(job, record)
        except BaseException:
            for f in futures:
                f.cancel()
            raise


def _import_ray() -> Any:
    try:
        import ray
    except ImportError as e:
        raise ImportError("backend='ray' needs Ray: pip install 'drapery[ray]' (or pip install ray)") from e
    return ray


def _ray(
    ray: Any,
    jobs: List[Dict[str, Any]],
    workers: Optional[int],
    cpus_per_task: int,
    address: Optional[str],
    done: Callable[[Dict[str, Any], Dict[str, Any]], None],
) -> None:
    started = not ray.is_initialized()
    if started:
        ray.init(address=address)
    try:
        task = ray.remote(num_cpus=cpus_per_task, max_retries=0)(_run_sample)
        queue = iter(jobs)
        limit = workers or len(jobs)
        running: Dict[Any, Dict[str, Any]] = {}
        for job in itertools.islice(queue, limit):
            running[task.remote(job)] = job
        while running:
            ready, _ = ray.wait(list(running), num_returns=1)
            for ref in ready:
                job = running.pop(ref)
                try:
                    record = ray.get(ref)
                except Exception as e:  # the task or its worker died
                    record = _record(job, 0.0, e)
                done(job, record)
                for nxt in itertools.islice(queue, 1):
                    running[task.remote(nxt)] = nxt
    finally:
        if started:
            ray.shutdown()


# ---------------------------------------------------------------------------------------------
# The manifest


def _read_manifest(path: Path) -> Dict[str, Dict[str, Any]]:
    out: Dict[str, Dict[str, Any]] = {}
    if path.is_file():
        for line in path.read_text().splitlines():
            try:
                rec = json.loads(line)
            except ValueError:
                continue  # a line cut short by a killed run
            if isinstance(rec, dict) and isinstance(rec.get("id"), str):
                out[rec["id"]] = rec
    return out


def _write_manifest(path: Path, records: Iterable[Dict[str, Any]]) -> None:
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "w") as f:
        for rec in records:
            f.write(json.dumps(rec) + "\n")
    os.replace(tmp, path)


def _complete(folder: Path, job: Dict[str, Any], old: Optional[Dict[str, Any]]) -> bool:
    """Whether the sample is already done: its marker matches its scene and its line says ok."""
    if not old or old.get("status") != "ok" or old.get("params_hash") != job["params_hash"]:
        return False
    try:
        marker = json.loads((folder / DONE).read_text())
    except (OSError, ValueError):
        return False
    return isinstance(marker, dict) and marker.get("scene_hash") == job["scene_hash"]


def _progress(total: int, initial: int) -> Any:
    if not sys.stderr.isatty():
        return None
    try:
        from tqdm import tqdm  # type: ignore[import-not-found,import-untyped,unused-ignore]
    except ImportError:
        return None
    return tqdm(total=total, initial=initial, unit="sample", desc="drapery sweep")


# ---------------------------------------------------------------------------------------------
# The sweep


def sweep(
    scene: Union[Mapping[str, Any], PathLike],
    params: Mapping[str, Any],
    output: PathLike,
    samples: Optional[int] = None,
    seed: int = 0,
    backend: str = "local",
    workers: Optional[int] = None,
    cpus_per_task: int = 1,
    frames: Union[Sequence[str], str, None] = None,
    ray_address: Optional[str] = None,
) -> List[Dict[str, Any]]:
    """Runs ``scene`` (a scene file's path or a scene dict) once per sample of ``params`` into
    ``output`` and returns the manifest's records, in sample order.

    ``params``: key path -> list of values (grid) or ``{"low", "high", "log"}`` range (random,
    ``samples`` draws with ``seed``); paths, sample order, files and resuming below.
    ``backend``: ``"local"`` (a process pool of ``workers``) or ``"ray"`` (``ray_address``;
    ``workers`` limits the tasks in flight). ``cpus_per_task``: threads per sample. ``frames``: the frame files, ``["obj"]`` (default), ``["ply"]``,
    both, or ``[]`` / ``"none"`` for frames.npz alone.

    Raises ValueError for a bad parameter (unknown key path, empty list, bad range) and
    SceneError for a base scene that cannot be read, before anything runs; a sample that fails
    is a ``"failed"`` record.

    Files, for sample ``sNNNN`` (the command ``drapery-sweep`` writes the same)::

        output/manifest.jsonl           one JSON line per sample, in sample order
        output/sNNNN/scene.toml         the sample's scene (mesh paths absolute: `drapery run` runs it)
        output/sNNNN/frame_00000.obj …  its frames, as `drapery run` writes them (``frames=``)
        output/sNNNN/frames.npz         positions float32 [frames, vertices, 3] and faces
        output/sNNNN/done.json          written last: the sample is complete

    Key paths: a parameter is a key path into the scene, its segments separated by dots: table names
    (``collision.friction``, ``solver.tolerance``), and in an array of tables (``[[cloth]]``,
    ``[[collider]]``) the element whose ``name`` is the segment, else the element at that index
    (``cloth.sheet.bend_stiffness``, ``collider.0.friction``); an index also selects an array's
    component (``cloth.sheet.grid.center.1``). A missing table or key is created (a default can be
    swept); a path into a table that does not exist (no such cloth, index out of range) or a key
    that the scene format does not know is a ``ValueError`` before anything runs.

    Each parameter's value is a list (grid) or a range ``{"low": a, "high": b, "log": False}``
    (random). The samples are the Cartesian product of the lists (in ``params`` order, the last one
    varying fastest); ranges are drawn ``samples`` times (``random.Random(seed)``, uniform, or
    log-uniform when ``log``), and when both are given every grid point is combined with the same
    ``samples`` draws (``grid × samples`` samples, the draws varying fastest). ``samples`` is
    required with ranges and refused without.

    Sample ids are ``s0000``, ``s0001``, … in that order (wider past 10000 samples), so the same
    ``params``, ``samples`` and ``seed`` give the same ids and values; the manifest also carries a
    hash of the parameter values.

    ``frames.npz``: ``positions`` (float32 [frames, vertices, 3], frame 0 the initial state, every
    cloth's vertices concatenated in scene order), ``faces`` (int64 [m, 3], triangles indexing
    those rows), ``cloths`` (the names) and ``offsets`` (int64 [cloths + 1]: cloth i is rows
    ``offsets[i]:offsets[i+1]``), ``times`` (float64 [frames], s). Written with fixed zip
    timestamps, so the same sample gives the same bytes on any backend.

    Manifest lines: ``{"id", "params", "params_hash", "status": "ok" | "failed", "wall_time" (s),
    "error" and "error_type" when failed}``.

    Resume: running the same sweep into the same folder again skips every sample whose ``done.json``
    matches its scene and whose manifest line says ``ok``; failed and incomplete samples run again
    (their folder is emptied first). A failing sample (a scene the library refuses, a step that
    fails) is recorded as failed and the others go on.

    Backends: ``"local"``, a process pool of ``workers`` processes (default
    ``os.cpu_count() // cpus_per_task``); ``"ray"``, one Ray task per sample with ``num_cpus =
    cpus_per_task`` (``ray.init(address=ray_address)``, a local instance when None; an instance
    already initialised is used as it is), at most ``workers`` in flight when given; on a cluster,
    ``output`` and the scene's meshes must be on a file system every node sees, and drapery
    installed on every node. Each sample's steps run on ``cpus_per_task`` threads (the bits are the
    same whatever that number). Only this process writes the manifest, in sample order.
    """
    if backend not in ("local", "ray"):
        raise ValueError(f"sweep: backend must be 'local' or 'ray', got {backend!r}")
    cpus = _count(cpus_per_task)
    if cpus is None:
        raise ValueError(f"sweep: cpus_per_task must be a whole number >= 1, got {cpus_per_task!r}")
    cpus_per_task = cpus
    if workers is not None:
        if _count(workers) is None:
            raise ValueError(f"sweep: workers must be a whole number >= 1 or None, got {workers!r}")
        workers = _count(workers)
    formats = _formats(frames)
    base = _base_scene(scene)
    ps, plan = _plan(params, samples, seed)
    _check_paths(base, ps, plan[0])
    ray = _import_ray() if backend == "ray" else None

    out = Path(output)
    out.mkdir(parents=True, exist_ok=True)
    width = max(4, len(str(len(plan) - 1)))
    jobs: List[Dict[str, Any]] = []
    for i, values in enumerate(plan):
        s = copy.deepcopy(base)
        for path, v in values.items():
            _assign(s, path, v)
        sid = f"s{i:0{width}d}"
        jobs.append(
            {
                "id": sid,
                "dir": str(out / sid),
                "scene": s,
                "params": values,
                "params_hash": _hash(values),
                "scene_hash": _hash(s),
                "formats": formats,
                "threads": cpus_per_task,
            }
        )

    manifest = out / MANIFEST
    old = _read_manifest(manifest)
    records: List[Optional[Dict[str, Any]]] = []
    pending = []
    for job in jobs:
        prev = old.get(job["id"])
        if _complete(Path(job["dir"]), job, prev):
            records.append(prev)
        else:
            records.append(None)
            pending.append(job)
    index = {job["id"]: i for i, job in enumerate(jobs)}

    def current() -> List[Dict[str, Any]]:
        # new records, else the previous run's line for the same values (until replaced)
        kept = []
        for job, rec in zip(jobs, records):
            prev = old.get(job["id"])
            if rec is None and prev is not None and prev.get("params_hash") == job["params_hash"]:
                rec = prev
            if rec is not None:
                kept.append(rec)
        return kept

    bar = _progress(len(jobs), len(jobs) - len(pending))
    last_write = [time.monotonic()]

    def done(job: Dict[str, Any], record: Dict[str, Any]) -> None:
        records[index[job["id"]]] = record
        if bar is not None:
            bar.update(1)
        if time.monotonic() - last_write[0] > 1.0:
            _write_manifest(manifest, current())
            last_write[0] = time.monotonic()

    try:
        if pending:
            if backend == "ray":
                _ray(ray, pending, workers, cpus_per_task, ray_address, done)
            else:
                _local(pending, workers or max(1, (os.cpu_count() or 1) // cpus_per_task), done)
    finally:
        _write_manifest(manifest, current())
        if bar is not None:
            bar.close()
    return [r for r in records if r is not None]


# ---------------------------------------------------------------------------------------------
# The command drapery-sweep


def _split_top(text: str) -> List[str]:
    """`text` split at the commas outside brackets and quotes."""
    parts, depth, quote, cur = [], 0, False, ""
    for ch in text:
        if ch == '"':
            quote = not quote
        elif not quote and ch == "[":
            depth += 1
        elif not quote and ch == "]":
            depth -= 1
        if ch == "," and depth == 0 and not quote:
            parts.append(cur)
            cur = ""
        else:
            cur += ch
    parts.append(cur)
    return parts


def _value(text: str) -> Any:
    """A value on the command line: JSON (numbers, true/false, "text", [lists]) or bare text."""
    try:
        return json.loads(text)
    except ValueError:
        return text


def parse_param(arg: str) -> Tuple[str, Any]:
    """``PATH=V1,V2,...`` (a grid) or ``PATH=LOW:HIGH`` / ``PATH=LOW:HIGH:log`` (a range)."""
    path, eq, spec = arg.partition("=")
    path, spec = path.strip(), spec.strip()
    if not eq or not path or not spec:
        raise ValueError(f"--param {arg!r}: expected PATH=V1,V2,... or PATH=LOW:HIGH[:log]")
    if ":" in spec and not spec.startswith(("[", '"')):
        bits = spec.split(":")
        if len(bits) not in (2, 3) or (len(bits) == 3 and bits[2] not in ("log", "lin")):
            raise ValueError(f"--param {arg!r}: a range is LOW:HIGH or LOW:HIGH:log")
        try:
            low, high = float(bits[0]), float(bits[1])
        except ValueError:
            raise ValueError(f"--param {arg!r}: LOW and HIGH must be numbers") from None
        return path, {"low": low, "high": high, "log": len(bits) == 3 and bits[2] == "log"}
    return path, [_value(v.strip()) for v in _split_top(spec)]


_EPILOG = """\
parameters (--param, repeatable):
  PATH=V1,V2,...     a grid: every combination of the listed values of all grid parameters;
                     values are JSON (1e3, true, "text", [5, 5]) or bare text
  PATH=LOW:HIGH      a range, drawn uniformly --samples times with --seed
  PATH=LOW:HIGH:log  a range drawn log-uniformly (LOW > 0)
  Grid and ranges together: each grid point with the same --samples draws.
  PATH: dot-separated keys of the scene; in [[cloth]] / [[collider]] an element by its name
  or index: cloth.sheet.bend_stiffness, collider.0.friction, collision.friction,
  cloth.sheet.grid.center.1

output: DIR/manifest.jsonl (one line per sample: id, params, status ok/failed, wall_time,
error) and DIR/sNNNN/ (scene.toml, frames, frames.npz, done.json). Running again skips the
samples already complete. Exit status 0 when every sample is ok, 1 when some failed, 2 for
bad arguments.

example:
  drapery-sweep examples/drape_sphere.toml --output out/sweep \\
      --param cloth.sheet.bend_stiffness=0.1,1,10 --param collider.0.friction=0.1:0.9:log \\
      --samples 4 --seed 0 --workers 2
"""


def main(argv: Optional[Sequence[str]] = None) -> int:
    """The console command ``drapery-sweep``."""
    ap = argparse.ArgumentParser(
        prog="drapery-sweep",
        description="Runs a drapery scene once per sample of its parameters, one folder per sample.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("scene", help="the scene file (TOML)")
    ap.add_argument("--param", "-p", action="append", default=[], metavar="PATH=SPEC", help="a swept key (see below); repeatable")
    ap.add_argument("--output", "-o", required=True, metavar="DIR", help="the sweep's folder")
    ap.add_argument("--samples", "-n", type=int, default=None, help="random draws of the range parameters")
    ap.add_argument("--seed", type=int, default=0, help="seed of the random draws (default 0)")
    ap.add_argument("--backend", choices=["local", "ray"], default="local", help="process pool (default) or Ray tasks")
    ap.add_argument("--workers", "-j", type=int, default=None, help="parallel samples (default: cores / cpus-per-task; ray: no limit)")
    ap.add_argument("--cpus-per-task", type=int, default=1, help="threads per sample (default 1)")
    ap.add_argument("--format", default="obj", help="frame files: obj (default), ply, obj,ply or none")
    ap.add_argument("--ray-address", default=None, help="the Ray cluster to join (default: a local instance)")
    args = ap.parse_args(argv)
    try:
        params = dict(parse_param(p) for p in args.param)
        if not params:
            ap.error("give at least one --param")
        records = sweep(
            args.scene,
            params,
            args.output,
            samples=args.samples,
            seed=args.seed,
            backend=args.backend,
            workers=args.workers,
            cpus_per_task=args.cpus_per_task,
            frames=args.format,
            ray_address=args.ray_address,
        )
    except (ValueError, TypeError, ImportError, _drapery.DraperyError) as e:
        print(f"drapery-sweep: error: {e}", file=sys.stderr)
        return 2
    failed = [r for r in records if r.get("status") != "ok"]
    for r in failed:
        print(f"drapery-sweep: {r['id']} failed: {r.get('error')}", file=sys.stderr)
    print(
        f"drapery-sweep: {len(records) - len(failed)} ok, {len(failed)} failed; {Path(args.output) / MANIFEST}",
        file=sys.stderr,
    )
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
