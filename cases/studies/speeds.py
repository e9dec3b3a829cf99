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
  middle of the final bracket.
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
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..run import CONVERGENCE_THRESHOLD, RunStore, convergence_speed
from ..run.history import attack_angle_peak
from ..scene import InputError, Scene
from ..scene.schema import Impact
from .pool import Pool, study_progress
from .sweep import Sweep, Variation, run_sweep

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "CriticalSearch",
    "find_critical_velocity",
    "find_critical_velocities",
    "is_unstable",
    "indicator",
    "ConvergentResult",
    "measure_convergent_velocity",
    "UNSTABLE_TURN",
    "ScanRun",
    "undisturbed",
    "disturbance_fix",
    "range_fix",
]

UNSTABLE_TURN = 30.0  # deg of axis turn that marks an unstable run


def indicator(axis_angle_change: float) -> float:
    """The instability indicator of a run: how far its axis turned (deg)."""
    return abs(axis_angle_change)


def is_unstable(axis_angle_change: float) -> bool:
    """Whether a run went unstable: its axis turned by at least :data:`UNSTABLE_TURN` degrees."""
    return indicator(axis_angle_change) >= UNSTABLE_TURN


# What a search that found nothing tells the user to change: the options that would find something.


def _bound(name: str, kind: str) -> float:
    """The schema's bound ``kind`` (``le``, ``ge``) of ``impact.NAME``: a suggested value stays allowed."""
    return next(getattr(m, kind) for m in Impact.model_fields[name].metadata if hasattr(m, kind))


def _typed(value: float, up: bool) -> float:
    """``value`` rounded to two significant digits, up or down: a number a person would type."""
    # the decimal exponent from the printed value: 10 ** exponent underflows for the smallest floats
    exponent = int(f"{value:.12e}".split("e")[1]) - 1
    units = float(f"{value:.12e}".split("e")[0]) * 10
    # a value already on the grid stays (2400, not 2500); rounding of the division is not a step
    units = math.ceil(units - 1e-9) if up else math.floor(units + 1e-9)
    return float(f"{units}e{exponent}")


def undisturbed(scene: Scene) -> bool:
    """Whether the scene starts without a disturbance: straight, square to the surface, not spinning.

    Such a run stays symmetric about its axis, never turns, and no speed makes it unstable.
    """
    impact = scene.impact
    return not (impact.attack_angle or impact.oblique_angle or impact.yaw_angle or any(impact.angular_velocity))


def disturbance_fix(scene: Scene) -> str:
    """The option that would make the scene turn: a disturbance when it has none, else a larger attack angle."""
    if undisturbed(scene):
        return "give the scene a disturbance (--set impact.attack_angle=1)"
    attack, top = scene.impact.attack_angle, _bound("attack_angle", "le")
    if abs(attack) >= top:
        return f"no larger attack angle is allowed (impact.attack_angle is {attack:g} deg)"
    # at least a degree: twice a vanishing angle (1e-300 deg) is still no disturbance
    larger = min(max(_typed(2 * abs(attack), up=True), 1.0), top)
    # the same side as the scene's (a mirrored disturbance turns the same)
    return f"a larger disturbance may turn it (--set impact.attack_angle={math.copysign(larger, attack):g})"


def range_fix(stable: bool, limits: Sequence[float], scene: Scene, option: str = "--speeds") -> str:
    """What to change when every run of the range ``limits`` was ``stable`` (else unstable): a wider range
    (half as wide again above, half the lowest speed below), and a disturbance where the scene has none or
    the range cannot grow."""
    low, high = float(min(limits)), float(max(limits))
    fixes = []
    if stable:
        top = min(_typed(1.5 * high, up=True), _bound("speed", "le"))
        if top > high:
            fixes.append(f"widen the range with {option} {low:g}:{top:g}")
        if undisturbed(scene) or not fixes:
            fixes.append(disturbance_fix(scene))
    else:
        fixes.append(f"lower the range with {option} {_typed(0.5 * low, up=False):g}:{high:g}")
    return ", or ".join(fixes)


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

    def as_dict(self) -> dict:
        return {
            "critical_velocity": self.critical_velocity,
            "bracket": self.bracket,
            "indicator": [asdict(run) for run in self.indicator],
            "message": self.message,
            "fix": self.fix,
            "runs": len(self.indicator),
            "rounds": self.rounds,
        }


def find_critical_velocity(
    sweep_base: Sweep,
    store: RunStore,
    speeds: Sequence[float],
    resolution: float = 5.0,
    pool: Pool | None = None,
    guess: Sequence[float] | None = None,
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
        runs confirm them, and the search widens to the range when they do not.
    """
    return find_critical_velocities([sweep_base], store, speeds, resolution, pool, None if guess is None else [guess])[
        0
    ]


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
    for (i, v), run in zip(jobs, result.runs):
        if run.failed:
            raise RuntimeError(f"the run at {v:g} m/s failed: {run.error}")
        s = run.summary
        assert s is not None  # not failed
        seen[i][v] = ScanRun(v, s.max_attack_angle, s.axis_angle_change, s.end_reason, run.key)


@dataclass
class _Bracket:
    """One search's state: the bracket ``[low, high]`` and whether a run confirms each end.

    An end not confirmed is assumed (the range's, or a guess's): stable at ``low``,
    unstable at ``high``.  ``limits`` is the range the search may widen to.
    """

    low: float
    high: float
    limits: tuple[float, float]
    low_run: bool = False
    high_run: bool = False
    failure: str = ""
    stable_throughout: bool = False

    def finished(self, resolution: float) -> bool:
        return bool(self.failure) or (self.low_run and self.high_run and self.high - self.low <= resolution * _SLACK)

    def wanted(self, count: int, resolution: float) -> list[float]:
        """The speeds to run next: up to ``count`` that split the bracket evenly on the grid of half the
        resolution, or, once it is narrow enough, the ends not confirmed yet."""
        low, high = self.low, self.high
        if high - low <= resolution * _SLACK:
            return [v for v, known in ((low, self.low_run), (high, self.high_run)) if not known][:count]
        count = min(count, math.ceil((high - low) / resolution - 1e-9) - 1)
        step = 0.5 * resolution
        points = {round(round((low + j * (high - low) / (count + 1)) / step) * step, 6) for j in range(1, count + 1)}
        return sorted(v for v in points if low < v < high)

    def update(self, seen: dict[float, ScanRun]) -> None:
        """The new bracket: the lowest unstable run from its bottom up, and the highest stable run below
        that; an end that its run contradicts moves out to the range's end (or the search fails there)."""
        unstable = {v for v, run in seen.items() if is_unstable(run.axis_angle_change)}
        stable = set(seen) - unstable
        bottom, top = self.limits
        high = _end([v for v in unstable if v >= self.low], min, self.high, stable, top)
        if high is None:
            self.failure = f"every run is stable, up to {max(stable):g} m/s"
            self.stable_throughout = True
            return
        self.high, self.high_run = high
        low = _end([v for v in stable if v < self.high], max, self.low, unstable, bottom)
        if low is None:
            self.failure = f"every run is unstable, down to {min(unstable):g} m/s"
            return
        self.low, self.low_run = low


def _end(
    side: list[float], nearest: Callable[[list[float]], float], assumed: float, wrong_side: set[float], limit: float
) -> tuple[float, bool] | None:
    """One end of a bracket and whether a run confirms it: the ``nearest`` run on its side; else the assumed
    end, unless its run lay on the wrong side: then the range's ``limit`` (None if that too was run and did)."""
    if side:
        return nearest(side), True
    if assumed not in wrong_side:
        return assumed, False
    return None if limit in wrong_side else (limit, False)


_SLACK = 1 + 1e-9  # a bracket this close to the resolution is narrow enough (rounding of the grid)


def _shares(brackets: Sequence[_Bracket], width: int) -> list[int]:
    """How many runs each bracket gets this round: together a whole number of rounds of ``width`` runs (at least
    one each), the widest brackets taking what is left over."""
    budget = width * math.ceil(len(brackets) / width)
    share, extra = divmod(budget, len(brackets))
    widest = sorted(range(len(brackets)), key=lambda i: brackets[i].low - brackets[i].high)
    counts = [share] * len(brackets)
    for i in widest[:extra]:
        counts[i] += 1
    return counts


def _first_brackets(
    bases: Sequence[Sweep], speeds: Sequence[float], guesses: Sequence[Sequence[float] | None] | None
) -> list[_Bracket]:
    """A bracket per scene: its guess, else the range; bad input is refused before anything runs."""
    low, high = float(min(speeds)), float(max(speeds))
    if not 0 < low < high:
        raise InputError(f"the range of speeds needs 0 < lowest < highest, got {low:g} and {high:g} m/s")
    guesses = list(guesses) if guesses is not None else [None] * len(bases)
    if len(guesses) != len(bases):
        raise ValueError(f"{len(guesses)} guesses for {len(bases)} scenes")
    brackets = []
    for guess in guesses:
        g_low, g_high = (low, high) if guess is None else (float(min(guess)), float(max(guess)))
        if not low <= g_low < g_high <= high:
            raise InputError(
                f"the guess {g_low:g} to {g_high:g} m/s must lie inside the range of speeds, {low:g} to {high:g} m/s"
            )
        brackets.append(_Bracket(g_low, g_high, (low, high)))
    # every speed a search may run lies in the range: a speed the scene refuses fails here, not mid-search
    Sweep.combined(
        [(base, Variation({**base.variations[0].values, "impact.speed": v})) for base in bases for v in (low, high)]
    )
    return brackets


def find_critical_velocities(
    bases: Sequence[Sweep],
    store: RunStore,
    speeds: Sequence[float],
    resolution: float = 5.0,
    pool: Pool | None = None,
    guesses: Sequence[Sequence[float] | None] | None = None,
) -> list[CriticalSearch]:
    """:func:`find_critical_velocity` for several scenes at once.

    The searches advance in lockstep, every round one parallel sweep: each
    open search splits its bracket into equal parts with the runs it gets
    (together a whole number of rounds of :attr:`Pool.width` runs: one
    search alone gets every worker, a family shares them).  A run is stable
    or unstable by :func:`is_unstable`; the new bracket is the lowest
    unstable run and the highest stable run below it.  The range's ends and
    a guess's are assumed until runs confirm them: an end contradicted by its
    run widens the bracket to the range, and a range without the change says
    so (``critical_velocity`` None).
    """
    brackets = _first_brackets(bases, speeds, guesses)
    width = (pool or Pool()).width
    seen: list[dict[float, ScanRun]] = [{} for _ in bases]
    rounds = [0] * len(bases)
    with study_progress("critical"):  # one progress bar for every round
        while True:
            open_ = [i for i, b in enumerate(brackets) if not b.finished(resolution)]
            if not open_:
                break
            counts = dict(zip(open_, _shares([brackets[i] for i in open_], width)))
            wanted = [brackets[i].wanted(counts[i], resolution) if i in counts else [] for i in range(len(bases))]
            if all(v in seen[i] for i in open_ for v in wanted[i]):  # cannot happen: every round runs something new
                raise RuntimeError("the critical-speed search stalled: no new speed to run")
            _scan(bases, store, pool, seen, wanted)
            for i in open_:
                rounds[i] += 1
                brackets[i].update(seen[i])
    results = []
    for i, bracket in enumerate(brackets):
        rows = sorted(seen[i].values(), key=lambda r: r.speed)
        if bracket.failure:
            fix = range_fix(bracket.stable_throughout, bracket.limits, bases[i].scenes[0])
            results.append(CriticalSearch(None, None, rows, bracket.failure, rounds[i], fix))
        else:
            results.append(
                CriticalSearch(0.5 * (bracket.low + bracket.high), [bracket.low, bracket.high], rows, "", rounds[i])
            )
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
        return {
            "characteristic_convergent_velocity": self.characteristic_convergent_velocity,
            "runs": [asdict(run) for run in self.runs],
            "message": self.message,
        }


def measure_convergent_velocity(
    sweep_base: Sweep,
    store: RunStore,
    threshold: float = CONVERGENCE_THRESHOLD,
    raise_factor: float = 1.15,
    max_speed: float = 4000.0,
    pool: Pool | None = None,
) -> ConvergentResult:
    """The characteristic convergent velocity from an unstable run of the scene.

    The scene runs at its own impact speed; if that run is stable (see
    :func:`is_unstable`), the speed is raised by ``raise_factor`` until a run
    is unstable, and the message says so.
    """
    base_values = dict(sweep_base.variations[0].values)
    scene = sweep_base.scenes[0]
    speed = scene.impact.speed
    runs: list[ConvergentRun] = []
    with study_progress("convergent"):  # one progress bar for the raised runs
        while True:
            variation = Variation({**base_values, "impact.speed": round(speed, 6)})
            result = run_sweep(Sweep(sweep_base.base, [variation], sweep_base.source), store, pool)
            run = result.runs[0]
            if run.failed:
                raise RuntimeError(f"the run at {speed:g} m/s failed: {run.error}")
            s = run.summary
            assert s is not None  # not failed
            history = result.history(0)
            runs.append(
                ConvergentRun(
                    round(speed, 6),
                    s.max_attack_angle,
                    s.axis_angle_change,
                    convergence_speed(history, threshold),
                    is_unstable(s.axis_angle_change),
                    s.end_reason,
                )
            )
            if runs[-1].unstable:
                break
            if speed * raise_factor > max_speed:
                return ConvergentResult(
                    None, runs, f"no unstable run up to {max_speed:g} m/s: {disturbance_fix(scene)}"
                )
            speed *= raise_factor
    value = runs[-1].convergence_speed
    message = ""
    if len(runs) > 1:
        message = (
            f"the run at {scene.impact.speed:g} m/s is stable; raised the impact speed to"
            f" {speed:.6g} m/s to get an unstable run"
        )
    if value is None:
        message += ("; " if message else "") + _threshold_fix(history, threshold)
    return ConvergentResult(value, runs, message)


def _threshold_fix(history: pd.DataFrame, threshold: float) -> str:
    """Why a run has no convergence speed at ``threshold``, and the ``--threshold`` that would give it one:
    just above the least attack angle after the peak."""
    angle = np.asarray(history["total_attack_angle"], dtype=float)[attack_angle_peak(history) :]
    least = float(np.nanmin(angle)) if np.isfinite(angle).any() else math.nan
    text = f"the attack angle never fell below {threshold} deg"
    if not least > 0:  # nothing finite after the peak: no threshold would find a crossing
        return text
    larger = _typed(1.1 * least, up=True)
    return f"{text} (its least after the peak: {least:.3g} deg): a larger threshold finds one, --threshold {larger:g}"
