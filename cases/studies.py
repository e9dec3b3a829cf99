"""The paper's characteristic speeds, measured on trajectories.

Definitions (docs/studies.md):

* **Instability indicator** of a run: ``|axis_angle_change|``, how far the
  projectile axis turns in the vertical plane over the run (deg).  Below the
  critical impact velocity the axis turns by a few degrees; above it the
  path turns strongly and the axis by 50 to 180 degrees.  The change is
  abrupt for a 1-degree attack angle (the largest attack angle jumps too, from
  about 2 to 15 degrees) and still a factor of four for 5 degrees, where the
  largest attack angle grows smoothly with speed and would not show it.
* **Critical impact velocity**: a coarse scan of impact speeds brackets the
  largest jump of ``log(indicator)`` between neighbouring speeds; bisection
  then halves the bracket, classing the middle speed with whichever end its
  ``log(indicator)`` lies closer to, until the bracket is no wider than the
  resolution.  The critical velocity is the middle of the final bracket.
* **Unstable run** (to decide whether a single run can give the convergent
  velocity): ``|axis_angle_change| >= UNSTABLE_TURN`` (30 degrees; in every
  run of docs/paper stable runs turn by at most 13 degrees and unstable
  ones by at least 50).
* **Convergence speed** of a run: the speed at which the total attack angle,
  after its peak, first falls below ``threshold`` (default 0.1 degree),
  interpolated linearly between steps.  In an unstable run this is the
  characteristic convergent velocity of the projectile and target.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .results import attack_angle_peak
from .sweep import RunStore, Sweep, Variation, run_sweep

__all__ = ["convergence_speed", "CriticalSearch", "find_critical_velocity", "find_critical_velocities",
           "is_unstable",
           "ConvergentResult", "measure_convergent_velocity",
           "CONVERGENCE_THRESHOLD", "UNSTABLE_TURN", "indicator"]

CONVERGENCE_THRESHOLD = 0.1  # deg
UNSTABLE_TURN = 30.0  # deg of axis turn that marks an unstable run


def convergence_speed(history: pd.DataFrame, threshold: float = CONVERGENCE_THRESHOLD) -> float | None:
    """Speed (m/s) at which the attack angle, after its peak, first falls below ``threshold`` (deg).

    The peak is :func:`~cases.results.attack_angle_peak` (sought while the speed is
    at least 10 % of the impact speed).  None if the angle never falls below the threshold.
    """
    speed = history["speed"].to_numpy()
    angle = history["total_attack_angle"].to_numpy()
    peak = attack_angle_peak(history)
    below = np.flatnonzero(angle[peak:] < threshold)
    if len(below) == 0:
        return None
    i = peak + int(below[0])
    if i == 0 or angle[i - 1] == angle[i]:
        return float(speed[i])
    # linear interpolation of the crossing between the two steps
    w = (angle[i - 1] - threshold) / (angle[i - 1] - angle[i])
    return float(speed[i - 1] + w * (speed[i] - speed[i - 1]))


def indicator(axis_angle_change: float) -> float:
    """The instability indicator of a run: how far its axis turned (deg)."""
    return abs(axis_angle_change)


def is_unstable(axis_angle_change: float) -> bool:
    """Whether a run went unstable: its axis turned by at least :data:`UNSTABLE_TURN` degrees."""
    return indicator(axis_angle_change) >= UNSTABLE_TURN


@dataclass
class CriticalSearch:
    """Result of :func:`find_critical_velocity`."""

    critical_velocity: float | None
    bracket: list[float] | None
    indicator: list[dict] = field(default_factory=list)
    message: str = ""

    def as_dict(self) -> dict:
        return {"critical_velocity": self.critical_velocity, "bracket": self.bracket,
                "indicator": self.indicator, "message": self.message}


def find_critical_velocity(sweep_base: Sweep, store: RunStore, speeds: Sequence[float],
                           resolution: float = 5.0, workers: int | None = None,
                           scheduler: str | None = None, progress: bool = False) -> CriticalSearch:
    """Bracket the critical impact velocity by a scan over ``speeds``, then bisect.

    Parameters
    ----------
    sweep_base : Sweep
        The scene (its first variation's overrides apply to every run).
    store : RunStore
        Run store; runs done before are reused.
    speeds : sequence of float
        The coarse scan (m/s).
    resolution : float
        Width (m/s) at which bisection stops.
    """
    return find_critical_velocities([sweep_base], store, speeds, resolution, workers, scheduler, progress)[0]


def find_critical_velocities(bases: Sequence[Sweep], store: RunStore, speeds: Sequence[float],
                             resolution: float = 5.0, workers: int | None = None,
                             scheduler: str | None = None, progress: bool = False) -> list[CriticalSearch]:
    """:func:`find_critical_velocity` for several scenes at once.

    The searches advance in lockstep (the scans together, then one bisection
    round for all), so every round is one parallel sweep.
    """
    speeds = sorted(float(v) for v in speeds)
    seen: list[dict[float, dict]] = [{} for _ in bases]

    def measure(wanted: list[list[float]]) -> None:
        jobs = [(i, v) for i, values in enumerate(wanted) for v in values if v not in seen[i]]
        if not jobs:
            return
        # one sweep over every base: each variation on its own base
        parts = [(bases[i], Variation({**bases[i].variations[0].values, "impact.speed": v})) for i, v in jobs]
        table = run_sweep(Sweep.combined(parts), store, workers=workers, scheduler=scheduler, progress=progress)
        for (i, v), (_, row) in zip(jobs, table.iterrows()):
            if isinstance(row.get("error"), str):
                raise RuntimeError(f"the run at {v:g} m/s failed: {row['error']}")
            seen[i][v] = {"speed": v, "max_attack_angle": float(row["max_attack_angle"]),
                          "axis_angle_change": float(row["axis_angle_change"]),
                          "end_reason": row["end_reason"], "key": row["key"]}

    def log_indicator(i: int, v: float) -> float:
        return math.log(max(indicator(seen[i][v]["axis_angle_change"]), 1e-6))

    measure([speeds for _ in bases])
    brackets: list[list[float] | None] = []
    for i in range(len(bases)):
        jumps = np.diff([log_indicator(i, v) for v in speeds])
        if len(jumps) == 0 or jumps.max() < math.log(2.0):
            brackets.append(None)
        else:
            k = int(np.argmax(jumps))
            brackets.append([speeds[k], speeds[k + 1]])
    grid_step = 0.5 * resolution  # bisect on a grid, so that runs are shared between searches

    def middle(bracket: list[float]) -> float | None:
        low, high = bracket
        mid = round(0.5 * (low + high) / grid_step) * grid_step
        return mid if high - low > resolution and low < mid < high else None

    while True:
        wanted = [[m] if b is not None and (m := middle(b)) is not None else [] for b in brackets]
        if not any(wanted):
            break
        measure(wanted)
        for i, values in enumerate(wanted):
            if not values:
                continue
            mid = values[0]
            low, high = brackets[i]
            if abs(log_indicator(i, mid) - log_indicator(i, low)) <= abs(log_indicator(i, mid) - log_indicator(i, high)):
                brackets[i] = [mid, high]
            else:
                brackets[i] = [low, mid]
    results = []
    for i, bracket in enumerate(brackets):
        rows = sorted(seen[i].values(), key=lambda r: r["speed"])
        if bracket is None:
            message = f"no abrupt change of the axis turn between {speeds[0]:g} and {speeds[-1]:g} m/s"
            results.append(CriticalSearch(None, None, rows, message))
        else:
            results.append(CriticalSearch(0.5 * sum(bracket), bracket, rows, ""))
    return results


@dataclass
class ConvergentResult:
    """Result of :func:`measure_convergent_velocity`."""

    characteristic_convergent_velocity: float | None
    runs: list[dict]
    message: str

    def as_dict(self) -> dict:
        return {"characteristic_convergent_velocity": self.characteristic_convergent_velocity,
                "runs": self.runs, "message": self.message}


def measure_convergent_velocity(sweep_base: Sweep, store: RunStore, threshold: float = CONVERGENCE_THRESHOLD,
                                raise_factor: float = 1.15, max_speed: float = 4000.0,
                                workers: int | None = None, scheduler: str | None = None,
                                progress: bool = False) -> ConvergentResult:
    """The characteristic convergent velocity from an unstable run of the scene.

    The scene runs at its own impact speed; if that run is stable (see
    :func:`is_unstable`), the speed is raised by ``raise_factor`` until a run
    is unstable, and the message says so.
    """
    base_values = dict(sweep_base.variations[0].values)
    scene = sweep_base.scenes[0]
    speed = scene.impact.speed
    runs: list[dict] = []
    while True:
        variation = Variation({**base_values, "impact.speed": round(speed, 6)})
        sweep = Sweep(sweep_base.base, [variation], sweep_base.source)
        row = run_sweep(sweep, store, workers=workers, scheduler=scheduler, progress=progress).iloc[0]
        if isinstance(row.get("error"), str):
            raise RuntimeError(f"the run at {speed:g} m/s failed: {row['error']}")
        history = store.history(row["key"])
        unstable = is_unstable(float(row["axis_angle_change"]))
        runs.append({"speed": round(speed, 6), "max_attack_angle": float(row["max_attack_angle"]),
                     "axis_angle_change": float(row["axis_angle_change"]),
                     "convergence_speed": convergence_speed(history, threshold), "unstable": unstable,
                     "end_reason": row["end_reason"]})
        if unstable:
            break
        if speed * raise_factor > max_speed:
            return ConvergentResult(None, runs, f"no unstable run up to {max_speed:g} m/s")
        speed *= raise_factor
    value = runs[-1]["convergence_speed"]
    message = ""
    if len(runs) > 1:
        message = (f"the run at {scene.impact.speed:g} m/s is stable; raised the impact speed to"
                   f" {speed:.6g} m/s to get an unstable run")
    if value is None:
        message += ("; " if message else "") + f"the attack angle never fell below {threshold} deg"
    return ConvergentResult(value, runs, message)
