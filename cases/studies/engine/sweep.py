"""Sweeps: many variations of a scene, run in parallel, stored run by run, resumable.

Every run is stored in a :class:`~cases.run.persistence.RunStore` under the key
of its fully resolved scene (and the code of runs): the record (its summary, or
the error of a failed run) and the thinned time history.  Files are written
atomically by the process that drives the sweep, so a sweep killed at any
moment leaves each run either complete or absent, and running it again skips
what is done.  Failed runs are recorded with their error, do not stop the
others, and are tried again by the next run of the sweep.

A variation's values are typed (``{"impact.speed": 1120}``) and applied to the
scene's dictionaries as they are; a sweep never passes a value through text.
"""

from __future__ import annotations

import itertools
import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ...run import RunStore, RunSummary, StoredRun
from ...scene import (
    InputError,
    Overrides,
    Scene,
    apply_overrides,
    dotted_key,
    parse_override,
    read_scene_data,
    read_toml,
    scene_from_dict,
    scene_key,
)
from .pool import Pool, run_missing

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "Variation",
    "grid",
    "parse_grid",
    "read_variations",
    "Sweep",
    "SweepResult",
    "run_sweep",
    "end_cells",
    "MAX_GRID_VALUES",
]

MAX_GRID_VALUES = 100_000  # values of one START:STOP:STEP range


@dataclass(frozen=True)
class Variation:
    """One run of a sweep: the base scene with ``values`` set (dotted key -> value)."""

    values: dict[str, Any]


def grid(parameters: Mapping[str, Sequence[Any]]) -> list[Variation]:
    """The cartesian product of value lists, the last key varying fastest."""
    keys = list(parameters)
    return [Variation(dict(zip(keys, combo))) for combo in itertools.product(*parameters.values())]


def parse_grid(text: str, option: str = "--grid") -> tuple[str, list[Any]]:
    """``key=v1,v2,...`` or ``key=start:stop:step`` (inclusive stop) -> (key, values); errors name ``option``."""
    key, raw = text.split("=", 1) if "=" in text else (text, "")
    if not raw.strip():
        raise InputError(f"{option} {text!r}: expected KEY=V1,V2,... or KEY=START:STOP:STEP")
    key = ".".join(dotted_key(key, f"{option} {text!r}"))
    parts = raw.split(":")
    if len(parts) == 3:
        try:
            start, stop, step = (float(p) for p in parts)
        except ValueError:
            raise InputError(f"{option} {text!r}: START:STOP:STEP must be numbers") from None
        if not all(math.isfinite(v) for v in (start, stop, step)):
            raise InputError(f"{option} {text!r}: START:STOP:STEP must be finite numbers")
        if not step > 0 or stop < start:
            raise InputError(f"{option} {text!r}: need STEP > 0 and STOP >= START")
        if (stop - start) / step >= MAX_GRID_VALUES:
            raise InputError(
                f"{option} {text!r}: more than {MAX_GRID_VALUES} values (allowed: (STOP - START) / STEP"
                f" < {MAX_GRID_VALUES})"
            )
        count = int(round((stop - start) / step)) + 1
        values = [start + i * step for i in range(count)]
        if all(float(v).is_integer() for v in (start, step)):
            values = [int(round(v)) for v in values]
        return key, values
    return key, [parse_override(f"{key}={item}")[1] for item in raw.split(",")]


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
        raise InputError(f'{path}: expected only [[run]] tables of dotted keys, e.g. [[run]] "impact.speed" = 1100')
    return [Variation(dict(run)) for run in runs]


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
        # validate everything before anything runs: a typo fails the sweep at once; the runs of a study
        # share warm workers, so numerics.kernel = "auto" is the compiled step (Scene.with_kernel)
        self.scenes = [
            scene_from_dict(apply_overrides(self.base, v.values, self.source), self.source).with_kernel(many_runs=True)
            for v in self.variations
        ]

    @classmethod
    def from_file(
        cls, path: str | os.PathLike, overrides: Overrides | None = None, variations: Sequence[Variation] = ()
    ) -> Sweep:
        base = apply_overrides(read_scene_data(path), overrides, str(path))
        return cls(base, list(variations) or [Variation({})], str(path))

    @classmethod
    def combined(cls, parts: Sequence[tuple[Sweep, Variation]]) -> Sweep:
        """Variations of several base scenes as one sweep, each variation on its own base."""
        return cls.from_bases([(base.base, base.source, variation) for base, variation in parts])

    @classmethod
    def from_bases(cls, parts: Sequence[tuple[dict, str, Variation]]) -> Sweep:
        """One sweep of ``(base scene, its source, variation)`` parts, each variation on its own base (nested
        dictionaries, before validation: each combined scene is validated once, here)."""
        sweep = cls.__new__(cls)
        sweep.base, sweep.source = {}, "scenes"
        sweep.variations = [variation for _, _, variation in parts]
        sweep.scenes = [
            scene_from_dict(apply_overrides(base, variation.values, source), source).with_kernel(many_runs=True)
            for base, source, variation in parts
        ]
        return sweep

    def keys(self) -> list[str]:
        return [scene_key(s) for s in self.scenes]


@dataclass
class SweepResult:
    """The stored runs of a sweep, in the order of its variations."""

    sweep: Sweep
    runs: list[StoredRun]
    store: RunStore

    def __len__(self) -> int:
        return len(self.runs)

    def history(self, index: int) -> pd.DataFrame:
        """The stored (thinned) time history of run ``index``."""
        return self.store.history(self.runs[index].key)

    def summaries(self, labels: Sequence[str]) -> list[RunSummary]:
        """Every run's summary, for a study that cannot go on without one: the first failed run raises a
        ``RuntimeError`` naming its ``labels`` entry (e.g. ``at 910 m/s``) and its error."""
        for label, run in zip(labels, self.runs):
            if run.failed:
                raise RuntimeError(f"the run {label} failed: {run.error}")
        return [run.summary for run in self.runs if run.summary is not None]

    def table(self) -> pd.DataFrame:
        """One row per variation: the varied keys, the run key and the summary (or the error); timings last."""
        rows = []
        for variation, run in zip(self.sweep.variations, self.runs):
            row = dict(variation.values)
            row["key"] = run.key
            record = run.summary.record() if run.summary is not None else {"error": run.error}
            for name, value in record.items():
                # a number the record holds as null (NaN: not defined for this run) is NaN in the table, as read back
                row[name] = (
                    json.dumps(value) if isinstance(value, (list, dict)) else math.nan if value is None else value
                )
            rows.append(row)
        import pandas as pd  # here: a search or a sweep without a table does not pay its import (0.25 s)

        table = pd.DataFrame(rows)
        volatile = [c for c in ("wall_time", "integration_time") if c in table]
        return table[[c for c in table.columns if c not in volatile] + volatile]


def end_cells(runs: Sequence[tuple[str, Sequence[str]]]) -> tuple[list[str], list[str]]:
    """How a study table shows each run's end: ``(cells, notes)`` for ``(end_reason, warnings)`` pairs.

    A cell is the end reason, with ``[k]`` pointing to note ``k`` when the run carries warnings; the notes
    are the distinct warning texts, numbered once each, so that no row hides a run the numerics doubt.
    """
    notes: list[str] = []
    cells = []
    for end_reason, warnings in runs:
        marks = []
        for warning in (w for w in warnings if w):
            if warning not in notes:
                notes.append(warning)
            marks.append(str(notes.index(warning) + 1))
        cells.append(end_reason + (f" [{', '.join(dict.fromkeys(marks))}]" if marks else ""))
    return cells, notes


def run_sweep(sweep: Sweep, store: RunStore, pool: Pool | None = None) -> SweepResult:
    """Run every variation not yet in ``store`` on ``pool`` (default: every local core); all of them, typed."""
    keys = sweep.keys()
    todo = {key: scene for key, scene in zip(keys, sweep.scenes) if not store.finished(key)}
    # called with nothing to run too: a study's progress bar counts the runs its rounds find in the store
    run_missing(todo, store, pool or Pool(), keys)
    return SweepResult(sweep, [StoredRun.from_record(key, store.load(key)) for key in keys], store)
