"""``penetrate ballistic-limit``: the lowest impact speed that perforates a target with a rear face.

* **Perforation**: a run that ends ``perforated``, every point of the body past the target's rear face.  A run
  that stops, comes back out or ends otherwise does not perforate.
* **Ballistic limit**: the speed at which runs change from not perforating to perforating, found to
  ``resolution``: the lowest perforating run with a run that does not perforate at most ``resolution`` below it.
  The limit is the middle of that bracket, found by the critical speed's threshold search (:mod:`..engine.search`),
  perforation in place of instability.  Each round runs as many speeds as the pool has workers.
* **Guide**: for a normal impact of a body of revolution whose nose alone presses (no friction, no free-surface
  reduction, separation), a 1-D integration of the nose through the target's slices
  (:func:`~cases.reference.normal_impact.ballistic_limit_1d`) gives the limit in about a second; the first bracket is
  one resolution wide around it.  Full runs confirm its ends, and an end that its run contradicts gallops away,
  one resolution and then doubling.  Elsewhere the search splits the range of speeds (k-section).

Runs are kept in the run store, so a search that stops is resumed by running it again.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field

from ...reference.normal_impact import ballistic_limit_1d, check_nose_alone_presses, scene_slices
from ...run import RunStore, prepare_projectile
from ...run.runner import PERFORATED
from ...scene import InputError, Scene
from ..engine.pool import Pool, study_progress
from ..engine.search import Bracket, search
from ..engine.sweep import Sweep, Variation, run_sweep

__all__ = ["LimitRun", "BallisticLimit", "find_ballistic_limit", "ballistic_guide", "check_rear_face"]

#: a range without the change: no run perforates up to its top, or every run does down to its bottom
FAILURES = (
    "no run perforates, up to {speed:g} m/s (--speeds)",
    "every run perforates, down to {speed:g} m/s (--speeds)",
)


@dataclass(frozen=True)
class LimitRun:
    """One full run of a ballistic-limit search: its speed and residual velocity (m/s; NaN unless perforated)."""

    speed: float
    end_reason: str
    residual_velocity: float
    key: str

    @property
    def perforated(self) -> bool:
        return self.end_reason == PERFORATED


@dataclass
class BallisticLimit:
    """The result of :func:`find_ballistic_limit` (m/s): the limit and its bracket (None when the range holds no
    change: ``message`` says why), every full run, the rounds, and the guide (``predicted``: the 1-D limit)."""

    ballistic_limit: float | None
    bracket: list[float] | None
    runs: list[LimitRun] = field(default_factory=list)
    rounds: int = 0
    message: str = ""
    guide: str = "unguided"
    predicted: float | None = None

    def as_dict(self) -> dict:
        return {
            "ballistic_limit": self.ballistic_limit,
            "bracket": self.bracket,
            "runs": [dict(asdict(run), perforated=run.perforated) for run in self.runs],
            "full_runs": len(self.runs),
            "rounds": self.rounds,
            "message": self.message,
            "guide": self.guide,
            "predicted_limit": self.predicted,
        }


def check_rear_face(scene: Scene) -> None:
    """One line refusing a target without a rear face, whose ballistic limit is infinite."""
    if scene.target.build_rear_face() is None:
        raise InputError(
            "target.layers: penetrate ballistic-limit needs a target with a rear face (allowed: layers whose"
            " last one has a thickness, m); this target goes on forever"
        )


def ballistic_guide(scene: Scene) -> tuple[float | None, str]:
    """The 1-D model's ballistic limit (m/s) of ``scene`` where it applies, and what the result says about it."""
    impact, effects, target = scene.impact, scene.effects, scene.target
    why = ""
    if scene.projectile.geometry is not None:
        why = "a projectile read from a file"
    elif impact.oblique_angle or impact.attack_angle or impact.yaw_angle or any(impact.angular_velocity):
        why = "not a normal impact"
    elif target.inclination:
        why = "an inclined target"
    elif effects.friction.model != "none" or effects.free_surface is not None or not effects.separation:
        why = "friction, a free-surface reduction or no separation"
    if why:
        return None, f"unguided: the 1-D model does not apply ({why})"
    prepared = prepare_projectile(scene)
    try:
        check_nose_alone_presses(prepared.profile)
    except ValueError:
        return None, "unguided: the 1-D model does not apply (a flare behind the nose)"
    limit = ballistic_limit_1d(prepared.profile, scene_slices(scene), prepared.mass.mass, **effects.contact_ramp)
    return limit, f"guided by the 1-D model of the nose through the target ({limit:.2f} m/s)"


def find_ballistic_limit(
    base: Sweep,
    store: RunStore,
    speeds: Sequence[float],
    resolution: float = 1.0,
    pool: Pool | None = None,
    guide: bool = True,
) -> BallisticLimit:
    """The ballistic limit of ``base``'s scene between the lowest and highest of ``speeds`` (m/s), to
    ``resolution`` (m/s); ``guide`` False: unguided even where the 1-D model applies."""
    low, high = float(min(speeds)), float(max(speeds))
    if not 0.0 < low < high:
        raise InputError(f"--speeds: need 0 < LOW < HIGH, got {low:g} and {high:g} m/s")
    scene = base.scenes[0]
    check_rear_face(scene)
    # every speed the search may run lies in the range: a speed the scene refuses fails here, not mid-search
    _sweep(base, [low, high])
    predicted, text = ballistic_guide(scene) if guide else (None, "unguided: --guide none")
    bracket = Bracket(low, high, (low, high), resolution, failures=FAILURES)
    if predicted is not None and low <= predicted - 0.5 * resolution and predicted + 0.5 * resolution <= high:
        first = round(predicted - 0.5 * resolution, 6), round(predicted + 0.5 * resolution, 6)
        bracket = Bracket(*first, (low, high), resolution, centre=predicted, failures=FAILURES)
    seen: dict[float, LimitRun] = {}

    def scan(wanted: list[list[float]]) -> list[dict[float, bool]]:
        runs = run_sweep(_sweep(base, wanted[0]), store, pool).runs
        for speed, run in zip(wanted[0], runs):
            summary = run.summary
            end = summary.end_reason if summary is not None else "failed"
            residual = summary.residual_velocity if summary is not None else math.nan
            seen[speed] = LimitRun(speed, end, residual, run.key)
        return [{v: run.perforated for v, run in seen.items()}]

    with study_progress("ballistic-limit"):
        (rounds,) = search([bracket], max(2, (pool or Pool()).width), scan)
    result = BallisticLimit(None, None, guide=text, predicted=predicted, rounds=rounds, message=bracket.failure)
    result.runs = sorted(seen.values(), key=lambda run: run.speed)
    if not bracket.failure:
        result.bracket = [bracket.low, bracket.high]
        result.ballistic_limit = bracket.middle
    return result


def _sweep(base: Sweep, speeds: Sequence[float]) -> Sweep:
    return Sweep.combined([(base, Variation({**base.variations[0].values, "impact.speed": v})) for v in speeds])
