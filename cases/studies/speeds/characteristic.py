"""The paper's characteristic speeds, measured on trajectories: ``penetrate critical`` and ``convergent``.

Definitions (docs/studies.md):

* **Instability indicator** of a run: ``|axis_angle_change|``, how far the
  projectile axis turns in the vertical plane over the run (deg).  Below the
  critical impact velocity the axis turns by a few degrees; above it the
  path turns strongly and the axis by 50 to 180 degrees.  The change is
  abrupt for a 1-degree attack angle (the largest attack angle jumps too, from
  about 2 to 15 degrees) and still a factor of four for 5 degrees, where the
  largest attack angle grows smoothly with speed and would not show it.
* **Critical impact velocity**: the speed at which runs change from stable
  to unstable (:func:`is_unstable`), found to ``resolution``: the lowest
  unstable run with a stable run at most ``resolution`` below it, in a range
  of speeds.  Each round splits the bracket into equal parts with as many runs
  as the pool has workers (k-section); the range's ends, or a guessed
  bracket's, count only once runs confirm them.  The critical velocity is the
  middle of the final bracket (the one threshold search, :mod:`..engine.search`).
* **Guided search** (the default where it applies, :mod:`.guide`): the reduced
  pitch-plane model's prediction gives a first bracket one resolution wide; full
  runs confirm its ends, and an end its run contradicts gallops out, one
  resolution and then doubling (spare workers run the next speeds beyond it).
* **Unstable run** (the critical speed's two sides, and whether a single run
  can give the convergent velocity): ``|axis_angle_change| >= UNSTABLE_TURN``
  (30 degrees).  In the paper's critical-speed searches the runs just below
  the jump turn by up to 18 degrees and most just above it by 50 or more;
  projectile #1 turns by 20 degrees 2.5 m/s above its jump and reaches 30
  degrees about 7 m/s higher, so its critical speed lies there.
* **Convergence speed** of a run: the speed at which the total attack angle,
  after its peak, first falls below ``threshold`` (default 0.1 degree),
  interpolated linearly between steps.  In an unstable run this is the
  characteristic convergent velocity of the projectile and target.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ...run import CONVERGENCE_THRESHOLD, RunStore, convergence_speed
from ...run.history import attack_angle_peak
from ...scene import InputError
from ..engine.pool import Pool, study_progress
from ..engine.search import Bracket, search
from ..engine.sweep import Sweep, Variation, run_sweep
from .guide import Guide, convergent_guide, critical_guide
from .instability import (
    MAX_SPEED,
    RAISE_FACTOR,
    disturbance_fix,
    is_unstable,
    raised_speeds,
    range_fix,
    typed_number,
)

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "CriticalSearch",
    "find_critical_velocity",
    "find_critical_velocities",
    "ConvergentResult",
    "measure_convergent_velocity",
    "ScanRun",
]


#: a range without the change, by side ({speed}: the range's end that was run)
FAILURES = ("every run is stable, up to {speed:g} m/s", "every run is unstable, down to {speed:g} m/s")


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
    """Result of :func:`find_critical_velocity` (m/s); ``rounds``: the parallel sweeps it took; ``fix``: when
    the range holds no change (``message``), the options of ``penetrate critical`` that would find one."""

    critical_velocity: float | None
    bracket: list[float] | None
    indicator: list[ScanRun] = field(default_factory=list)
    message: str = ""
    rounds: int = 0
    fix: str = ""
    guide: Guide = field(default_factory=lambda: Guide("none", "unguided"))

    def as_dict(self) -> dict:
        return {
            "critical_velocity": self.critical_velocity,
            "bracket": self.bracket,
            "indicator": [asdict(run) for run in self.indicator],
            "message": self.message,
            "fix": self.fix,
            "runs": len(self.indicator),
            "rounds": self.rounds,
            "guide": self.guide.name,
            "guide_text": self.guide.text,
            "predicted_velocity": self.guide.predicted,
        }


def find_critical_velocity(
    sweep_base: Sweep,
    store: RunStore,
    speeds: Sequence[float],
    resolution: float = 5.0,
    pool: Pool | None = None,
    guess: Sequence[float] | None = None,
    guide: str = "auto",
) -> CriticalSearch:
    """The critical impact velocity between the lowest and highest of ``speeds``, to ``resolution``.

    Parameters
    ----------
    sweep_base : Sweep
        The scene (its first variation's overrides apply to every run).
    store : RunStore
        Run store; runs done before are reused.
    speeds : sequence of float
        The range searched (m/s): only its lowest and highest value count.
    resolution : float
        The search stops when a stable and an unstable run are at most this far apart (m/s).
    pool : Pool, optional
        Where the runs go; each round holds as many runs as it has workers (:attr:`Pool.width`).
    guess : (low, high), optional
        A first bracket inside the range (a neighbour's result, a prediction); its ends count only once
        runs confirm them, and the search widens to the range when they do not.  It replaces the guide.
    guide : {"auto", "reduced", "none"}
        ``auto``: the reduced model's first bracket where it applies (:mod:`.guide`), else unguided, and
        the result says why; ``reduced``: refuse a scene it does not apply to; ``none``: unguided.
    """
    guesses = None if guess is None else [guess]
    return find_critical_velocities([sweep_base], store, speeds, resolution, pool, guesses, guide)[0]


def _scan(
    bases: Sequence[Sweep],
    store: RunStore,
    pool: Pool | None,
    seen: list[dict[float, ScanRun]],
    wanted: list[list[float]],
) -> None:
    """Run the wanted speeds of every base not seen yet, as one parallel sweep; record them in ``seen``."""
    jobs = [(i, v) for i, values in enumerate(wanted) for v in values if v not in seen[i]]
    if not jobs:
        return
    parts = [(bases[i], Variation({**bases[i].variations[0].values, "impact.speed": v})) for i, v in jobs]
    result = run_sweep(Sweep.combined(parts), store, pool)
    for (i, v), run, s in zip(jobs, result.runs, result.summaries([f"at {v:g} m/s" for _, v in jobs])):
        seen[i][v] = ScanRun(v, s.max_attack_angle, s.axis_angle_change, s.end_reason, run.key)


def _first_brackets(
    bases: Sequence[Sweep],
    speeds: Sequence[float],
    resolution: float,
    guesses: Sequence[Sequence[float] | None] | None,
    guide: str,
) -> tuple[list[Bracket], list[Guide]]:
    """A bracket per scene: its guess, else its guide's, else the range; bad input is refused before anything
    runs."""
    low, high = float(min(speeds)), float(max(speeds))
    if not 0 < low < high:
        raise InputError(f"the range of speeds needs 0 < lowest < highest, got {low:g} and {high:g} m/s")
    guesses = list(guesses) if guesses is not None else [None] * len(bases)
    if len(guesses) != len(bases):
        raise ValueError(f"{len(guesses)} guesses for {len(bases)} scenes")
    for guess in guesses:
        g_low, g_high = (low, high) if guess is None else (float(min(guess)), float(max(guess)))
        if not low <= g_low < g_high <= high:
            raise InputError(
                f"the guess {g_low:g} to {g_high:g} m/s must lie inside the range of speeds, {low:g} to {high:g} m/s"
            )
    # every speed a search may run lies in the range: a speed the scene refuses fails here, not mid-search
    Sweep.combined(
        [(base, Variation({**base.variations[0].values, "impact.speed": v})) for base in bases for v in (low, high)]
    )
    brackets, guides = [], []
    for base, guess in zip(bases, guesses):
        if guess is not None:
            brackets.append(Bracket(float(min(guess)), float(max(guess)), (low, high), resolution, failures=FAILURES))
            guides.append(Guide("none", "unguided: a guess given"))
            continue
        found, first = critical_guide(base.scenes[0], (low, high), resolution, guide)
        guides.append(found)
        if first is None:
            brackets.append(Bracket(low, high, (low, high), resolution, failures=FAILURES))
        else:
            brackets.append(
                Bracket(first[0], first[1], (low, high), resolution, centre=0.5 * sum(first), failures=FAILURES)
            )
    return brackets, guides


def find_critical_velocities(
    bases: Sequence[Sweep],
    store: RunStore,
    speeds: Sequence[float],
    resolution: float = 5.0,
    pool: Pool | None = None,
    guesses: Sequence[Sequence[float] | None] | None = None,
    guide: str = "auto",
) -> list[CriticalSearch]:
    """:func:`find_critical_velocity` for several scenes at once.

    The searches advance in lockstep, every round one parallel sweep: each
    open search splits its bracket into equal parts with the runs it gets
    (together a whole number of rounds of :attr:`Pool.width` runs: one
    search alone gets every worker, a family shares them).  A run is stable
    or unstable by :func:`is_unstable`; the new bracket is the lowest
    unstable run and the highest stable run below it.  The range's ends and
    a guess's are assumed until runs confirm them: an end contradicted by its
    run widens the bracket to the range (a guided search's moves out step by
    step), and a range without the change says so (``critical_velocity`` None).
    """
    brackets, guides = _first_brackets(bases, speeds, resolution, guesses, guide)
    seen: list[dict[float, ScanRun]] = [{} for _ in bases]

    def scan(wanted: list[list[float]]) -> list[dict[float, bool]]:
        _scan(bases, store, pool, seen, wanted)
        return [{v: is_unstable(run.axis_angle_change) for v, run in runs.items()} for runs in seen]

    with study_progress("critical"):  # one progress bar for every round
        rounds = search(brackets, (pool or Pool()).width, scan)
    results = []
    for i, bracket in enumerate(brackets):
        rows = sorted(seen[i].values(), key=lambda r: r.speed)
        if bracket.failure:
            fix = range_fix(bracket.below_throughout, bracket.limits, bases[i].scenes[0])
            results.append(CriticalSearch(None, None, rows, bracket.failure, rounds[i], fix, guides[i]))
        else:
            ends = [bracket.low, bracket.high]
            results.append(CriticalSearch(bracket.middle, ends, rows, "", rounds[i], "", guides[i]))
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
    guide: Guide = field(default_factory=lambda: Guide("none", "unguided"))

    def as_dict(self) -> dict:
        return {
            "characteristic_convergent_velocity": self.characteristic_convergent_velocity,
            "runs": [asdict(run) for run in self.runs],
            "message": self.message,
            "guide": self.guide.name,
            "guide_text": self.guide.text,
        }


def _convergent_runs(
    sweep_base: Sweep, store: RunStore, pool: Pool | None, speeds: list[float], threshold: float
) -> list[tuple[ConvergentRun, pd.DataFrame]]:
    """Runs of the scene at ``speeds`` (one parallel sweep), each with its history."""
    base_values = dict(sweep_base.variations[0].values)
    variations = [Variation({**base_values, "impact.speed": v}) for v in speeds]
    result = run_sweep(Sweep(sweep_base.base, variations, sweep_base.source), store, pool)
    done = []
    for i, (speed, s) in enumerate(zip(speeds, result.summaries([f"at {v:g} m/s" for v in speeds]))):
        history = result.history(i)
        unstable = is_unstable(s.axis_angle_change)
        converged = convergence_speed(history, threshold)
        done.append(
            (ConvergentRun(speed, s.max_attack_angle, s.axis_angle_change, converged, unstable, s.end_reason), history)
        )
    return done


def measure_convergent_velocity(
    sweep_base: Sweep,
    store: RunStore,
    threshold: float = CONVERGENCE_THRESHOLD,
    raise_factor: float = RAISE_FACTOR,
    max_speed: float = MAX_SPEED,
    pool: Pool | None = None,
    guide: str = "auto",
) -> ConvergentResult:
    """The characteristic convergent velocity from an unstable run of the scene.

    The scene runs at its own impact speed; if that run is stable (see
    :func:`is_unstable`), the speed is raised by ``raise_factor`` until a run
    is unstable, and the message says so.  Guided (``guide``, as in
    :func:`find_critical_velocity`), the first runs are the first raised speed
    whose reduced run is unstable and the speed below it, together; the
    speeds below those are not run (the message says so), and the search
    goes down or on up from there when the full runs disagree with the guide.
    """
    scene = sweep_base.scenes[0]
    found, raised = convergent_guide(scene, raise_factor, max_speed, guide)
    ladder = raised_speeds(scene.impact.speed, raise_factor, max_speed)

    def rung(j: int) -> float:
        return round(ladder[j], 6)

    done: dict[int, tuple[ConvergentRun, pd.DataFrame]] = {}
    batch = [0] if not raised else [raised - 1, raised]
    with study_progress("convergent"):  # one progress bar for the raised runs
        while True:
            for j, outcome in zip(
                batch, _convergent_runs(sweep_base, store, pool, [rung(j) for j in batch], threshold)
            ):
                done[j] = outcome
            unstable = [j for j in done if done[j][0].unstable]
            if unstable and (min(unstable) == 0 or min(unstable) - 1 in done):
                break
            if unstable:  # the guide's stable run is not: go down, two rungs at a time when guided
                lowest = min(unstable)
                batch = [
                    j for j in ((lowest - 2, lowest - 1) if found.guided else (lowest - 1,)) if j >= 0 and j not in done
                ]
                continue
            top = max(done)
            if top + 1 == len(ladder):
                runs = [done[j][0] for j in sorted(done)]
                return ConvergentResult(
                    None, runs, f"no unstable run up to {max_speed:g} m/s: {disturbance_fix(scene)}", found
                )
            batch = [j for j in ((top + 1, top + 2) if found.guided else (top + 1,)) if j < len(ladder)]
    first = min(unstable)
    runs = [done[j][0] for j in sorted(done)]
    run, history = done[first]
    messages = []
    if first:
        messages.append(
            f"the run at {scene.impact.speed:g} m/s is stable; raised the impact speed to {run.speed:.6g} m/s to get"
            " an unstable run"
        )
    skipped = [rung(j) for j in range(first) if j not in done]
    if skipped:
        messages.append(f"not run: {', '.join(f'{v:.6g}' for v in skipped)} m/s, stable in the reduced model")
    if run.convergence_speed is None:
        messages.append(_threshold_fix(history, threshold))
    return ConvergentResult(run.convergence_speed, runs, "; ".join(messages), found)


def _threshold_fix(history: pd.DataFrame, threshold: float) -> str:
    """Why a run has no convergence speed at ``threshold``, and the ``--threshold`` that would give it one:
    just above the least attack angle after the peak."""
    angle = np.asarray(history["total_attack_angle"], dtype=float)[attack_angle_peak(history) :]
    least = float(np.nanmin(angle)) if np.isfinite(angle).any() else math.nan
    text = f"the attack angle never fell below {threshold} deg"
    if not least > 0:  # nothing finite after the peak: no threshold would find a crossing
        return text
    larger = typed_number(1.1 * least, up=True)
    return f"{text} (its least after the peak: {least:.3g} deg): a larger threshold finds one, --threshold {larger:g}"
