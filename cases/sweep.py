"""Sweeps: many variations of a scene, run in parallel, stored run by run, resumable.

Every run is stored under :func:`~cases.scene.scene_key` of its fully resolved
scene: ``<store>/<key>.json`` (the summary, the scene and the varied keys, or
the error of a failed run) and ``<store>/<key>.csv.gz`` (the thinned time
history).  Files are written atomically by the process that drives the sweep,
so a sweep killed at any moment leaves each run either complete or absent,
and running it again skips what is done.  Failed runs are recorded with their
error, do not stop the others, and are tried again by the next run of the sweep.

Workers are a local process pool (every core by default) or, with
``scheduler``, an existing Dask distributed cluster; both return the same
table, ordered as the variations were given.
"""

from __future__ import annotations

import gzip
import io
import itertools
import json
import math
import os
import re
from collections.abc import Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from .results import atomic_write_bytes, json_safe
from .scene import SceneError, apply_overrides, parse_override, read_toml, scene_from_dict, scene_key
from .schema import Scene

__all__ = ["Variation", "grid", "parse_grid", "read_variations", "RunStore", "Sweep", "run_sweep", "MAX_HISTORY_ROWS"]

MAX_HISTORY_ROWS = 4000  # stored histories are thinned to about this many rows
MAX_GRID_VALUES = 100_000  # values of one START:STOP:STEP range


@dataclass(frozen=True)
class Variation:
    """One run of a sweep: the base scene with ``values`` set (dotted key -> value)."""

    values: dict[str, Any]

    def overrides(self) -> list[str]:
        return [f"{key}={_toml_value(value)}" for key, value in self.values.items()]


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return repr(value)


def grid(parameters: dict[str, Sequence[Any]]) -> list[Variation]:
    """The cartesian product of value lists, the last key varying fastest."""
    keys = list(parameters)
    return [Variation(dict(zip(keys, combo))) for combo in itertools.product(*parameters.values())]


def parse_grid(text: str) -> tuple[str, list[Any]]:
    """``key=v1,v2,...`` or ``key=start:stop:step`` (inclusive stop) -> (key, values)."""
    key, raw = text.split("=", 1) if "=" in text else (text, "")
    if not raw.strip():
        raise SceneError(f"--grid {text!r}: expected KEY=V1,V2,... or KEY=START:STOP:STEP")
    parts = raw.split(":")
    if len(parts) == 3:
        try:
            start, stop, step = (float(p) for p in parts)
        except ValueError:
            raise SceneError(f"--grid {text!r}: START:STOP:STEP must be numbers") from None
        if not all(math.isfinite(v) for v in (start, stop, step)):
            raise SceneError(f"--grid {text!r}: START:STOP:STEP must be finite numbers")
        if not step > 0 or stop < start:
            raise SceneError(f"--grid {text!r}: need STEP > 0 and STOP >= START")
        if (stop - start) / step >= MAX_GRID_VALUES:
            raise SceneError(f"--grid {text!r}: more than {MAX_GRID_VALUES} values (allowed: (STOP - START) / STEP"
                             f" < {MAX_GRID_VALUES})")
        count = int(round((stop - start) / step)) + 1
        values = [start + i * step for i in range(count)]
        if all(float(v).is_integer() for v in (start, step)):
            values = [int(round(v)) for v in values]
        return key.strip(), values
    return key.strip(), [parse_override(f"{key}={item}")[1] for item in raw.split(",")]


def read_variations(path: str | os.PathLike) -> list[Variation]:
    """Variations listed in a TOML file, one ``[[run]]`` table of dotted keys each.

    Example::

        [[run]]
        "impact.speed" = 1100
        "impact.attack_angle" = 5
    """
    data = read_toml(path)
    runs = data.get("run")
    unknown = set(data) - {"run"}
    if unknown or not isinstance(runs, list) or not all(isinstance(r, dict) and r for r in runs):
        raise SceneError(f"{path}: expected only [[run]] tables of dotted keys, e.g."
                         ' [[run]] "impact.speed" = 1100')
    return [Variation(dict(run)) for run in runs]


def _file_name(key: str) -> str:
    """A run key as a file name inside the store: never a path (keys are scene digests, see scene_key)."""
    if not key or key.startswith(".") or any(c in key for c in "/\\\0") or not key.isprintable():
        raise ValueError(f"run key {key!r}: must be a plain file name inside the store")
    return key


class RunStore:
    """A folder of finished runs keyed by their resolved scene."""

    def __init__(self, root: str | os.PathLike) -> None:
        # made when the first run is saved: a command that fails on bad input leaves nothing behind
        self.root = Path(root)
        if self.root.exists() and not self.root.is_dir():
            raise SceneError(f"{self.root}: the run store must be a folder, and this is a file")

    def record_path(self, key: str) -> Path:
        return self.root / f"{_file_name(key)}.json"

    def history_path(self, key: str) -> Path:
        return self.root / f"{_file_name(key)}.csv.gz"

    def load(self, key: str) -> dict | None:
        """The stored record of a run, or None."""
        try:
            return json.loads(self.record_path(key).read_text())
        except (OSError, ValueError):
            return None

    def finished(self, key: str) -> bool:
        record = self.load(key)
        return record is not None and "error" not in record

    def history(self, key: str) -> pd.DataFrame:
        """The stored (thinned) time history of a finished run."""
        return pd.read_csv(self.history_path(key))

    def save(self, key: str, record: dict, history_csv: bytes | None) -> None:
        """Store a run: the history first, then the record that marks it finished."""
        if history_csv is not None:
            atomic_write_bytes(self.history_path(key), history_csv)
        text = json.dumps(json_safe(record), indent=1, allow_nan=False) + "\n"  # null, never NaN
        atomic_write_bytes(self.record_path(key), text.encode())


def simulate_record(scene_json: str) -> tuple[dict, bytes | None]:
    """Run one resolved scene (a worker's job): its summary and gzipped CSV history, or the error."""
    from .results import json_safe, history_table, summary
    from .runner import run_scene

    scene = Scene.model_validate_json(scene_json)
    try:
        result = run_scene(scene)
        history = history_table(result)
        record = json_safe(summary(result, history))
        record["scene_resolved"] = scene.model_dump(mode="json")
    except Exception as exc:  # recorded, so that one failure does not stop the sweep
        return {"error": f"{type(exc).__name__}: {exc}"}, None
    every = max(1, len(history) // MAX_HISTORY_ROWS)
    kept = history.iloc[::every]
    if kept.index[-1] != history.index[-1]:
        kept = pd.concat([kept, history.iloc[[-1]]])
    buffer = io.BytesIO()
    with gzip.GzipFile(fileobj=buffer, mode="wb", mtime=0) as gz:
        gz.write(_csv_bytes(kept))
    return record, buffer.getvalue()


def _csv_bytes(table: pd.DataFrame) -> bytes:
    """A numeric table as CSV, ten significant digits (numpy's writer: 4x faster than pandas' here)."""
    buffer = io.StringIO()
    np.savetxt(buffer, table.to_numpy(dtype=float), fmt="%.10g", delimiter=",", header=",".join(table.columns),
               comments="")
    # undefined cells (e.g. resistance_centre_from_tip) empty, as pandas writes them: never "nan" in an output
    return _NON_FINITE_CELL.sub("", buffer.getvalue()).encode()


_NON_FINITE_CELL = re.compile(r"(?m)(?<![^,\n])-?(?:nan|inf)(?=,|$)")


@dataclass
class Sweep:
    """Variations of a base scene.

    Parameters
    ----------
    base : dict
        The base scene as nested dictionaries (before validation).
    variations : list of Variation
        What each run changes.
    source : str
        Where the base came from, for error messages.
    """

    base: dict
    variations: list[Variation]
    source: str = "scene"
    scenes: list[Scene] = field(init=False)

    def __post_init__(self) -> None:
        # validate everything before anything runs: a typo fails the sweep at once
        self.scenes = [scene_from_dict(apply_overrides(self.base, v.overrides()), self.source)
                       for v in self.variations]

    @classmethod
    def from_file(cls, path: str | os.PathLike, overrides: Iterable[str] = (),
                  variations: Sequence[Variation] = ()) -> Sweep:
        base = apply_overrides(read_toml(path), list(overrides))
        return cls(base, list(variations) or [Variation({})], str(path))

    @classmethod
    def combined(cls, parts: Sequence[tuple[Sweep, Variation]]) -> Sweep:
        """Variations of several base scenes as one sweep, each variation on its own base."""
        sweep = cls.__new__(cls)
        sweep.base, sweep.source = {}, "scenes"
        sweep.variations = [variation for _, variation in parts]
        sweep.scenes = [scene_from_dict(apply_overrides(base.base, variation.overrides()), base.source)
                        for base, variation in parts]
        return sweep

    def keys(self) -> list[str]:
        return [scene_key(s) for s in self.scenes]


def prepare_record(scene_json: str) -> None:
    """Prepare a scene's projectile into the disk cache (a worker's job); errors surface in its runs."""
    from .runner import prepare_projectile

    try:
        prepare_projectile(Scene.model_validate_json(scene_json))
    except Exception:  # noqa: BLE001 - the runs of this projectile will fail and record why
        pass


def _distinct_projectiles(scenes: Sequence[Scene]) -> list[str]:
    """One scene (as JSON) per distinct projectile and mesh setting."""
    from .runner import preparation_key

    seen: dict[tuple, str] = {}
    for scene in scenes:
        seen.setdefault(preparation_key(scene), scene.model_dump_json())
    return list(seen.values())


def run_sweep(sweep: Sweep, store: RunStore, *, workers: int | None = None, scheduler: str | None = None,
              progress: bool = True) -> pd.DataFrame:
    """Run every variation not yet in ``store``; return the table of all of them.

    Parameters
    ----------
    sweep : Sweep
        The runs.
    store : RunStore
        Where finished runs are kept (and found again).
    workers : int, optional
        Local processes (default: every core).
    scheduler : str, optional
        Address of a Dask distributed scheduler to run on instead.
    progress : bool
        Show a progress bar (runs done, failed, time left) on stderr.
    """
    keys = sweep.keys()
    todo: dict[str, Scene] = {}
    for key, scene in zip(keys, sweep.scenes):
        if not store.finished(key):
            todo[key] = scene
    if todo:
        _run_missing(todo, store, workers, scheduler, progress, total=len(set(keys)))
    return results_table(sweep, store)


def _run_missing(todo: dict[str, Scene], store: RunStore, workers: int | None, scheduler: str | None,
                 progress: bool, total: int) -> None:
    from tqdm import tqdm

    jobs = {key: scene.model_dump_json() for key, scene in todo.items()}
    bar = tqdm(total=total, initial=total - len(jobs), disable=not progress, unit="run",
               desc="sweep", dynamic_ncols=True)
    failed = 0

    def finish(key: str, record: dict, history: bytes | None) -> None:
        nonlocal failed
        store.save(key, record, history)
        failed += "error" in record
        bar.set_postfix(failed=failed, refresh=False)
        bar.update(1)

    try:
        if scheduler:
            from distributed import Client
            from distributed import as_completed as dask_completed

            with Client(scheduler) as client:
                futures = {client.submit(simulate_record, text, pure=False): key for key, text in jobs.items()}
                for future in dask_completed(futures):
                    finish(futures[future], *future.result())
        else:
            count = workers or os.cpu_count() or 1
            if count == 1:
                for key, text in jobs.items():
                    finish(key, *simulate_record(text))
            else:
                with ProcessPoolExecutor(count, mp_context=get_context("spawn")) as pool:
                    # mesh and prepare each projectile once, in parallel, into the disk cache,
                    # before the runs that read it
                    for done in [pool.submit(prepare_record, text)
                                 for text in _distinct_projectiles(list(todo.values()))]:
                        done.result()
                    futures = {pool.submit(simulate_record, text): key for key, text in jobs.items()}
                    for future in as_completed(futures):
                        finish(futures[future], *future.result())
    finally:
        bar.close()


def results_table(sweep: Sweep, store: RunStore) -> pd.DataFrame:
    """One row per variation: the varied keys, the run key and the stored summary (or error)."""
    rows = []
    for variation, key in zip(sweep.variations, sweep.keys()):
        record = store.load(key) or {"error": "not run"}
        row = dict(variation.values)
        row["key"] = key
        for name, value in record.items():
            if name not in ("scene_resolved", "history_units"):
                row[name] = json.dumps(value) if isinstance(value, (list, dict)) else value
        rows.append(row)
    table = pd.DataFrame(rows)
    volatile = [c for c in ("wall_time", "integration_time") if c in table]
    return table[[c for c in table.columns if c not in volatile] + volatile]

