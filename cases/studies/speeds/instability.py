"""When a run is unstable, and what to change when a search finds no change of stability.

* **Instability indicator** of a run: ``|axis_angle_change|``, how far the projectile axis turns in
  the vertical plane over the run (deg).
* **Unstable run**: ``|axis_angle_change| >= UNSTABLE_TURN`` (30 degrees); docs/studies.md says why.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from ...scene import Scene
from ...scene.schema import Impact

__all__ = [
    "UNSTABLE_TURN",
    "RAISE_FACTOR",
    "MAX_SPEED",
    "indicator",
    "is_unstable",
    "raised_speeds",
    "undisturbed",
    "disturbance_fix",
    "range_fix",
    "typed_number",
]

UNSTABLE_TURN = 30.0  # deg of axis turn that marks an unstable run
RAISE_FACTOR, MAX_SPEED = 1.15, 4000.0  # how a stable run's impact speed is raised for an unstable one (m/s)


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


def typed_number(value: float, up: bool) -> float:
    """``value`` rounded to two significant digits, up or down: a number a person would type."""
    # the decimal exponent from the printed value: 10 ** exponent underflows for the smallest floats
    exponent = int(f"{value:.12e}".split("e")[1]) - 1
    units = float(f"{value:.12e}".split("e")[0]) * 10
    # a value already on the grid stays (2400, not 2500); rounding of the division is not a step
    units = math.ceil(units - 1e-9) if up else math.floor(units + 1e-9)
    return float(f"{units}e{exponent}")


def raised_speeds(speed: float, factor: float = RAISE_FACTOR, top: float = MAX_SPEED) -> list[float]:
    """The impact speeds tried in turn for an unstable run (m/s): ``speed``, then each the one before times
    ``factor``, as long as it stays at or below ``top`` (the first always, whatever its value)."""
    speeds = [speed]
    while speeds[-1] * factor <= top:
        speeds.append(speeds[-1] * factor)
    return speeds


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
    larger = min(max(typed_number(2 * abs(attack), up=True), 1.0), top)
    # the same side as the scene's (a mirrored disturbance turns the same)
    return f"a larger disturbance may turn it (--set impact.attack_angle={math.copysign(larger, attack):g})"


def range_fix(stable: bool, limits: Sequence[float], scene: Scene, option: str = "--speeds") -> str:
    """What to change when every run of the range ``limits`` was ``stable`` (else unstable): a wider range
    (half as wide again above, half the lowest speed below), and a disturbance where the scene has none or
    the range cannot grow."""
    low, high = float(min(limits)), float(max(limits))
    fixes = []
    if stable:
        top = min(typed_number(1.5 * high, up=True), _bound("speed", "le"))
        if top > high:
            fixes.append(f"widen the range with {option} {low:g}:{top:g}")
        if undisturbed(scene) or not fixes:
            fixes.append(disturbance_fix(scene))
    else:
        fixes.append(f"lower the range with {option} {typed_number(0.5 * low, up=False):g}:{high:g}")
    return ", or ".join(fixes)
