"""The paper's characteristic speeds, measured on trajectories.

Definitions (docs/studies.md):

* **Instability indicator** of a run: ``max_attack_angle``, the largest total
  attack angle while the speed is at least 10 % of the impact speed.  Below
  the critical impact velocity it stays near the initial disturbance; above
  it the attack angle grows to many degrees.  The change is abrupt.
* **Critical impact velocity**: a coarse scan of impact speeds brackets the
  largest jump of ``log(indicator)`` between neighbouring speeds; bisection
  then halves the bracket, classing the middle speed with whichever end its
  ``log(indicator)`` lies closer to, until the bracket is no wider than the
  resolution.  The critical velocity is the middle of the final bracket.
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

from .sweep import RunStore, Sweep, Variation, run_sweep

__all__ = ["convergence_speed", "CriticalSearch", "find_critical_velocity", "is_unstable",
           "ConvergentResult", "measure_convergent_velocity",
           "CONVERGENCE_THRESHOLD", "UNSTABLE_GROWTH"]

CONVERGENCE_THRESHOLD = 0.1  # deg
UNSTABLE_GROWTH = 4.0  # a run is unstable when its attack angle grows to this multiple of the start


def convergence_speed(history: pd.DataFrame, threshold: float = CONVERGENCE_THRESHOLD,
                      moving_fraction: float = 0.1) -> float | None:
    """Speed (m/s) at which the attack angle, after its peak, first falls below ``threshold`` (deg).

    The peak is sought while the speed is at least ``moving_fraction`` of the
    impact speed.  None if the angle never falls below the threshold.
    """
    speed = history["speed"].to_numpy()
    angle = history["total_attack_angle"].to_numpy()
    moving = np.flatnonzero(speed >= moving_fraction * speed[0])
    peak = int(moving[np.argmax(angle[moving])])
    below = np.flatnonzero(angle[peak:] < threshold)
    if len(below) == 0:
        return None
    i = peak + int(below[0])
    if i == 0 or angle[i - 1] == angle[i]:
        return float(speed[i])
    # linear interpolation of the crossing between the two steps
    w = (angle[i - 1] - threshold) / (angle[i - 1] - angle[i])
    return float(speed[i - 1] + w * (speed[i] - speed[i - 1]))


def is_unstable(max_attack_angle: float, initial_attack_angle: float) -> bool:
    """Whether a run went unstable: its attack angle grew past ``UNSTABLE_GROWTH`` times the start.

    Used only to decide whether a single run can give the convergent velocity;
    the critical velocity itself is found from the jump between speeds.
    """
    return max_attack_angle > UNSTABLE_GROWTH * max(abs(initial_attack_angle), 0.25)


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
        The coarse scan (m/s), ascending.
    resolution : float
        Width (m/s) at which bisection stops.
    """
    base_values = dict(sweep_base.variations[0].values)
    seen: dict[float, dict] = {}

    def measure(values: Sequence[float]) -> None:
        fresh = [v for v in values if v not in seen]
        if not fresh:
            return
        variations = [Variation({**base_values, "impact.speed": float(v)}) for v in fresh]
        table = run_sweep(Sweep(sweep_base.base, variations, sweep_base.source), store,
                          workers=workers, scheduler=scheduler, progress=progress)
        for v, (_, row) in zip(fresh, table.iterrows()):
            if isinstance(row.get("error"), str):
                raise RuntimeError(f"the run at {v} m/s failed: {row['error']}")
            seen[v] = {"speed": float(v), "max_attack_angle": float(row["max_attack_angle"]),
                       "axis_angle_change": float(row["axis_angle_change"]),
                       "end_reason": row["end_reason"]}

    speeds = sorted(float(v) for v in speeds)
    measure(speeds)
    logs = [math.log(max(seen[v]["max_attack_angle"], 1e-6)) for v in speeds]
    jumps = np.diff(logs)
    if len(jumps) == 0 or jumps.max() < math.log(2.0):
        return CriticalSearch(None, None, sorted(seen.values(), key=lambda r: r["speed"]),
                              f"no abrupt growth of the attack angle between {speeds[0]:g} and {speeds[-1]:g} m/s")
    k = int(np.argmax(jumps))
    low, high = speeds[k], speeds[k + 1]
    while high - low > resolution:
        # bisect on a grid of the resolution, so runs are reused between searches
        middle = round(0.5 * (low + high) / (0.5 * resolution)) * 0.5 * resolution
        if not low < middle < high:
            break
        measure([middle])
        log_mid = math.log(max(seen[middle]["max_attack_angle"], 1e-6))
        log_low = math.log(max(seen[low]["max_attack_angle"], 1e-6))
        log_high = math.log(max(seen[high]["max_attack_angle"], 1e-6))
        if abs(log_mid - log_low) <= abs(log_mid - log_high):
            low = middle
        else:
            high = middle
    return CriticalSearch(0.5 * (low + high), [low, high], sorted(seen.values(), key=lambda r: r["speed"]),
                          "")


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

    The scene runs at its own impact speed; if that run is stable (its attack
    angle does not grow past :data:`UNSTABLE_GROWTH` times the start), the
    speed is raised by ``raise_factor`` until a run is unstable, and the
    message says so.
    """
    base_values = dict(sweep_base.variations[0].values)
    scene = sweep_base.scenes[0]
    initial = math.hypot(scene.impact.attack_angle, scene.impact.yaw_angle)
    speed = scene.impact.speed
    runs: list[dict] = []
    while True:
        variation = Variation({**base_values, "impact.speed": round(speed, 6)})
        sweep = Sweep(sweep_base.base, [variation], sweep_base.source)
        row = run_sweep(sweep, store, workers=workers, scheduler=scheduler, progress=progress).iloc[0]
        if isinstance(row.get("error"), str):
            raise RuntimeError(f"the run at {speed:g} m/s failed: {row['error']}")
        history = store.history(row["key"])
        unstable = is_unstable(float(row["max_attack_angle"]), initial)
        runs.append({"speed": round(speed, 6), "max_attack_angle": float(row["max_attack_angle"]),
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
