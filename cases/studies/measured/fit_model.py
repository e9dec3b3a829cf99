"""The model a fit inverts: observed quantities as a function of the fitted parameters, through the run store.

A point of the model is the parameters' values (each as a fraction of its range); evaluating points runs the
observations' scenes with those values set, all points in one batch of runs
(:func:`~cases.studies.engine.sweep.run_sweep`), and measures the characteristic speeds by their searches.  Every
point is cached, and every run is kept in the run store, so the fit's iterations and a fit run again make no run
twice.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ...run import CONVERGENCE_THRESHOLD, RunStore
from ...scene import apply_overrides
from ..engine.pool import Pool
from ..engine.sweep import Sweep, Variation, run_sweep
from ..speeds.characteristic import find_critical_velocity, measure_convergent_velocity
from ..speeds.instability import disturbance_fix, undisturbed
from .series import RUN_QUANTITIES, run_value

__all__ = ["Parameter", "Observation", "FitModel", "STUDY_QUANTITIES", "DIGITS"]

#: quantities of a study of the scene (penetrate critical, penetrate convergent)
STUDY_QUANTITIES = ("critical_velocity", "characteristic_convergent_velocity")
#: values set in a scene keep this many significant digits, so a point reached twice is the same run
DIGITS = 12


@dataclass(frozen=True)
class Parameter:
    """A numeric scene key fitted within ``[low, high]``; ``start`` is the scene's own value."""

    key: str
    low: float
    high: float
    start: float

    def value(self, unit: float) -> float:
        """The value at ``unit`` in [0, 1] of the range, to :data:`DIGITS` significant digits."""
        return float(f"{self.low + unit * (self.high - self.low):.{DIGITS}g}")


@dataclass(frozen=True)
class Observation:
    """``quantity`` of ``scene`` observed as ``value`` with standard deviation ``sigma`` (None: not given)."""

    scene: str
    quantity: str
    value: float
    sigma: float | None


class FitModel:
    """The observations as a function of the parameters' unit values, through the run store (cached)."""

    def __init__(
        self,
        bases: dict[str, dict],
        parameters: Sequence[Parameter],
        observations: Sequence[Observation],
        store: RunStore,
        pool: Pool | None,
        resolution: float,
    ) -> None:
        self.bases, self.parameters, self.observations = bases, list(parameters), list(observations)
        self.store, self.pool, self.resolution = store, pool, resolution
        self.cache: dict[tuple[float, ...], np.ndarray] = {}
        self.keys: set[str] = set()
        self.new_runs = 0

    def _values(self, unit: np.ndarray) -> dict[str, float]:
        return {p.key: p.value(float(u)) for p, u in zip(self.parameters, unit)}

    @staticmethod
    def _key(point: np.ndarray) -> tuple[float, ...]:
        return tuple(np.round(np.asarray(point, float), DIGITS))

    def __call__(self, points: Sequence[np.ndarray]) -> list[np.ndarray]:
        """The observed quantities at each point (unit values), runs of all points in one batch."""
        wanted = [self._key(p) for p in points]
        missing = list(dict.fromkeys(w for w in wanted if w not in self.cache))
        if missing:
            before = self.store.records()
            self._evaluate([np.array(m) for m in missing])
            self.new_runs += len(self.store.records() - before)  # the records this batch added
        return [self.cache[w] for w in wanted]

    def _evaluate(self, points: list[np.ndarray]) -> None:
        run_observations = [(i, o) for i, o in enumerate(self.observations) if o.quantity in RUN_QUANTITIES]
        scenes = list(dict.fromkeys(o.scene for _, o in run_observations))
        parts = [
            (Sweep(self.bases[scene], [Variation({})], scene), Variation(self._values(point)))
            for point in points
            for scene in scenes
        ]
        results = np.full((len(points), len(self.observations)), np.nan)
        if parts:
            sweep = Sweep.combined(parts)
            result = run_sweep(sweep, self.store, self.pool)
            self.keys.update(sweep.keys())
            for index, run in enumerate(result.runs):
                if run.failed:
                    raise RuntimeError(f"a run of the fit failed ({parts[index][1].values}): {run.error}")
                point_index, scene = divmod(index, len(scenes))
                for i, o in run_observations:
                    if o.scene != scenes[scene]:
                        continue
                    value = run_value(result, index, o.quantity)
                    results[point_index, i] = np.nan if value is None else value
        for i, o in enumerate(self.observations):
            if o.quantity not in STUDY_QUANTITIES:
                continue
            for point_index, point in enumerate(points):
                values = self._values(point)
                base = Sweep(apply_overrides(self.bases[o.scene], values, o.scene), [Variation({})], o.scene)
                results[point_index, i] = self._study(o.quantity, base)
        for point, row in zip(points, results):
            self.cache[self._key(point)] = row

    def _study(self, quantity: str, base: Sweep) -> float:
        if quantity == "critical_velocity":
            speed = base.scenes[0].impact.speed
            searched = (200.0, max(2000.0, 2 * speed))
            search = find_critical_velocity(base, self.store, searched, self.resolution, self.pool)
            value, why = search.critical_velocity, search.message
            where = f" between {searched[0]:g} and {searched[1]:g} m/s"  # the search's range, fixed by the fit
            used = {run.key for run in search.indicator}
        else:
            measured = measure_convergent_velocity(base, self.store, pool=self.pool)
            value, where = measured.characteristic_convergent_velocity, ""
            why = (
                f"its attack angle never fell below {CONVERGENCE_THRESHOLD} deg"
                if measured.runs[-1].unstable
                else f"no unstable run up to {measured.runs[-1].speed:.6g} m/s"
            )
            start = base.variations[0].values
            used = {
                Sweep(base.base, [Variation({**start, "impact.speed": run.speed})], base.source).keys()[0]
                for run in measured.runs
            }
        self.keys.update(used)
        if value is None:
            # the fit's own search range is fixed: what the user can change is the parameters' ranges or the scene
            scene = base.scenes[0]
            fixes = [f"keep the --param ranges where the scene has one{where}"] + (
                [disturbance_fix(scene)] if undisturbed(scene) else []
            )
            raise RuntimeError(
                f"{quantity} of {base.source} not found at {base.variations[0].values or 'the start'}"
                f" ({why}): {', or '.join(fixes)}"
            )
        return float(value)
