"""The paper's characteristic speeds, measured on trajectories: ``penetrate critical`` and ``convergent``.

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
from dataclasses import asdict, dataclass, field

import numpy as np

from ..run import CONVERGENCE_THRESHOLD, RunStore, convergence_speed
from .pool import Pool
from .sweep import Sweep, Variation, run_sweep

__all__ = ["CriticalSearch", "find_critical_velocity", "find_critical_velocities", "is_unstable", "indicator",
           "ConvergentResult", "measure_convergent_velocity", "UNSTABLE_TURN", "ScanRun"]

UNSTABLE_TURN = 30.0  # deg of axis turn that marks an unstable run


def indicator(axis_angle_change: float) -> float:
    """The instability indicator of a run: how far its axis turned (deg)."""
    return abs(axis_angle_change)


def is_unstable(axis_angle_change: float) -> bool:
    """Whether a run went unstable: its axis turned by at least :data:`UNSTABLE_TURN` degrees."""
    return indicator(axis_angle_change) >= UNSTABLE_TURN


@dataclass(frozen=True)
class ScanRun:
    """One run of a critical-speed search (m/s, deg)."""

    speed: float
    max_attack_angle: float
    axis_angle_change: float
    end_reason: str
    key: str


@dataclass
class CriticalSearch:
    """Result of :func:`find_critical_velocity` (m/s)."""

    critical_velocity: float | None
    bracket: list[float] | None
    indicator: list[ScanRun] = field(default_factory=list)
    message: str = ""

    def as_dict(self) -> dict:
        return {"critical_velocity": self.critical_velocity, "bracket": self.bracket,
                "indicator": [asdict(run) for run in self.indicator], "message": self.message}


def find_critical_velocity(sweep_base: Sweep, store: RunStore, speeds: Sequence[float], resolution: float = 5.0,
                           pool: Pool | None = None) -> CriticalSearch:
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
    pool : Pool, optional
        Where the runs go.
    """
    return find_critical_velocities([sweep_base], store, speeds, resolution, pool)[0]


def _scan(bases: Sequence[Sweep], store: RunStore, pool: Pool | None, seen: list[dict[float, ScanRun]],
          wanted: list[list[float]]) -> None:
    """Run the wanted speeds of every base not seen yet, as one parallel sweep; record them in ``seen``."""
    jobs = [(i, v) for i, values in enumerate(wanted) for v in values if v not in seen[i]]
    if not jobs:
        return
    parts = [(bases[i], Variation({**bases[i].variations[0].values, "impact.speed": v})) for i, v in jobs]
    result = run_sweep(Sweep.combined(parts), store, pool)
    for (i, v), run in zip(jobs, result.runs):
        if run.failed:
            raise RuntimeError(f"the run at {v:g} m/s failed: {run.error}")
        s = run.summary
        seen[i][v] = ScanRun(v, s.max_attack_angle, s.axis_angle_change, s.end_reason, run.key)


def find_critical_velocities(bases: Sequence[Sweep], store: RunStore, speeds: Sequence[float],
                             resolution: float = 5.0, pool: Pool | None = None) -> list[CriticalSearch]:
    """:func:`find_critical_velocity` for several scenes at once.

    The searches advance in lockstep (the scans together, then one bisection
    round for all), so every round is one parallel sweep.
    """
    speeds = sorted(float(v) for v in speeds)
    seen: list[dict[float, ScanRun]] = [{} for _ in bases]

    def log_indicator(i: int, v: float) -> float:
        return math.log(max(indicator(seen[i][v].axis_angle_change), 1e-6))

    _scan(bases, store, pool, seen, [speeds for _ in bases])
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
        _scan(bases, store, pool, seen, wanted)
        for i, values in enumerate(wanted):
            if not values:
                continue
            mid = values[0]
            low, high = brackets[i]
            to_low = abs(log_indicator(i, mid) - log_indicator(i, low))
            if to_low <= abs(log_indicator(i, mid) - log_indicator(i, high)):
                brackets[i] = [mid, high]
            else:
                brackets[i] = [low, mid]
    results = []
    for i, bracket in enumerate(brackets):
        rows = sorted(seen[i].values(), key=lambda r: r.speed)
        if bracket is None:
            message = f"no abrupt change of the axis turn between {speeds[0]:g} and {speeds[-1]:g} m/s"
            results.append(CriticalSearch(None, None, rows, message))
        else:
            results.append(CriticalSearch(0.5 * sum(bracket), bracket, rows, ""))
    return results


@dataclass(frozen=True)
class ConvergentRun:
    """One run of :func:`measure_convergent_velocity` (m/s, deg)."""

    speed: float
    max_attack_angle: float
    axis_angle_change: float
    convergence_speed: float | None
    unstable: bool
    end_reason: str


@dataclass
class ConvergentResult:
    """Result of :func:`measure_convergent_velocity` (m/s)."""

    characteristic_convergent_velocity: float | None
    runs: list[ConvergentRun]
    message: str

    def as_dict(self) -> dict:
        return {"characteristic_convergent_velocity": self.characteristic_convergent_velocity,
                "runs": [asdict(run) for run in self.runs], "message": self.message}


def measure_convergent_velocity(sweep_base: Sweep, store: RunStore, threshold: float = CONVERGENCE_THRESHOLD,
                                raise_factor: float = 1.15, max_speed: float = 4000.0,
                                pool: Pool | None = None) -> ConvergentResult:
    """The characteristic convergent velocity from an unstable run of the scene.

    The scene runs at its own impact speed; if that run is stable (see
    :func:`is_unstable`), the speed is raised by ``raise_factor`` until a run
    is unstable, and the message says so.
    """
    base_values = dict(sweep_base.variations[0].values)
    scene = sweep_base.scenes[0]
    speed = scene.impact.speed
    runs: list[ConvergentRun] = []
    while True:
        variation = Variation({**base_values, "impact.speed": round(speed, 6)})
        result = run_sweep(Sweep(sweep_base.base, [variation], sweep_base.source), store, pool)
        run = result.runs[0]
        if run.failed:
            raise RuntimeError(f"the run at {speed:g} m/s failed: {run.error}")
        s = run.summary
        runs.append(ConvergentRun(round(speed, 6), s.max_attack_angle, s.axis_angle_change,
                                  convergence_speed(result.history(0), threshold), is_unstable(s.axis_angle_change),
                                  s.end_reason))
        if runs[-1].unstable:
            break
        if speed * raise_factor > max_speed:
            return ConvergentResult(None, runs, f"no unstable run up to {max_speed:g} m/s")
        speed *= raise_factor
    value = runs[-1].convergence_speed
    message = ""
    if len(runs) > 1:
        message = (f"the run at {scene.impact.speed:g} m/s is stable; raised the impact speed to"
                   f" {speed:.6g} m/s to get an unstable run")
    if value is None:
        message += ("; " if message else "") + f"the attack angle never fell below {threshold} deg"
    return ConvergentResult(value, runs, message)
