"""The runs of the paper's study, read: convergence speeds, characteristic speeds, fits, load-only boundaries."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from dynamics.rigid_body import LoadFunction

from ... import scene_path
from ...run import CONVERGENCE_THRESHOLD, RunStore, StoredRun, attack_angle_peak, convergence_speed, prepare_projectile
from ...scene import load_scene
from ..engine.pool import Pool
from ..engine.sweep import Sweep, run_sweep
from ..reduced.turn_boundary import TurnBoundary, turn_boundary
from ..speeds.instability import is_unstable
from .plan import STUDY_NUMERICS, RunGroup

__all__ = ["PaperRun", "Study", "characteristic", "linear_fit", "interpolate", "load_boundary"]


@dataclass(frozen=True)
class PaperRun:
    """One run of the study as its tables use it (m/s, deg); ``error`` set when it failed."""

    speed: float
    key: str
    error: str | None = None
    peak: tuple[float, float] | None = None  # the largest attack angle and the speed at it
    unstable: bool = False
    convergence_speed: float | None = None
    max_attack_angle: float | None = None
    axis_angle_change: float | None = None
    end_reason: str | None = None
    path_length: float | None = None  # m

    def record(self) -> dict:
        """The run as ``results.json`` lists it."""
        if self.error is not None:
            return {"impact.speed": self.speed, "error": self.error}
        return {
            "impact.speed": self.speed,
            "peak": self.peak,
            "unstable": self.unstable,
            "convergence_speed": self.convergence_speed,
            "max_attack_angle": self.max_attack_angle,
            "axis_angle_change": self.axis_angle_change,
            "end_reason": self.end_reason,
            "key": self.key,
        }


@dataclass
class Study:
    """Runs groups of the study through one store and pool."""

    store: RunStore
    pool: Pool

    def run(self, groups: Sequence[RunGroup]) -> dict[tuple[str, float], list[PaperRun]]:
        """Every group as one parallel sweep; the runs of each group, keyed by ``(kind, ratio)``."""
        pairs = [(g.base(), v) for g in groups for v in g.variations()]
        result = run_sweep(Sweep.combined(pairs), self.store, self.pool)
        out, start = {}, 0
        for group in groups:
            runs = result.runs[start : start + len(group.speeds)]
            out[(group.kind, group.ratio)] = [self._read(speed, run) for speed, run in zip(group.speeds, runs)]
            start += len(group.speeds)
        return out

    def _read(self, speed: float, run: StoredRun) -> PaperRun:
        if run.failed:
            return PaperRun(speed, run.key, error=run.error)
        history = self.history(run.key)
        peak = attack_angle_peak(history)
        s = run.summary
        assert s is not None  # not failed
        return PaperRun(
            speed,
            run.key,
            None,
            (float(history["total_attack_angle"].iloc[peak]), float(history["speed"].iloc[peak])),
            is_unstable(s.axis_angle_change),
            convergence_speed(history, CONVERGENCE_THRESHOLD),
            s.max_attack_angle,
            s.axis_angle_change,
            s.end_reason,
            s.path_length,
        )

    def history(self, key: str) -> pd.DataFrame:
        return self.store.history(key)


def characteristic(runs: list[PaperRun]) -> float | None:
    """Median convergence speed of the unstable runs that converged inside the target."""
    values = [r.convergence_speed for r in runs if r.unstable and r.convergence_speed]
    return float(np.median(values)) if values else None


def linear_fit(x: Sequence[float], y: Sequence[float | None]) -> dict:
    """Least-squares line ``y = slope x + intercept`` and its R^2; a None in ``y`` (a speed not found) is NaN, and
    makes every number NaN."""
    xs, ys = np.asarray(x, float), np.asarray(y, float)
    slope, intercept = np.polyfit(xs, ys, 1)
    residual = ys - (slope * xs + intercept)
    r2 = 1 - residual @ residual / ((ys - ys.mean()) @ (ys - ys.mean()))
    return {"slope": float(slope), "intercept": float(intercept), "r2": float(r2)}


def interpolate(xs: Sequence[float], ys: Sequence[float | None], x: float) -> float | None:
    """Linear interpolation through the known points; None outside them."""
    points = [(a, v) for a, v in zip(xs, ys) if v is not None]
    if not points or not points[0][0] <= x <= points[-1][0]:
        return None
    return float(np.interp(x, [a for a, _ in points], [v for _, v in points]))


def load_boundary(ratio: float) -> TurnBoundary:
    """The load-only boundaries (:mod:`~cases.studies.reduced.turn_boundary`) of the projectile at ``ratio``: the
    load on the kernel a study's worker would run it on (the compiled one for the paper's law, 4-5 times faster
    here)."""
    scene = load_scene(scene_path("paper_p3"), {**STUDY_NUMERICS, "projectile.centre_of_mass_ratio": ratio})
    prepared = prepare_projectile(scene)
    loads = scene.loads(prepared.quadrature)
    function: LoadFunction = loads
    if scene.with_kernel(many_runs=True).numerics.kernel == "compiled":
        from ...run.compiled import compiled_load_function

        function = compiled_load_function(loads)
    return turn_boundary(function, prepared.mass.mass, attack_angles=tuple(range(1, 31)))
