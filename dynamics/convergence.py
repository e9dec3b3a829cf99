"""The convergence of a turning run, defined once: where the attack angle, after its peak, falls below a threshold.

A run's attack angle grows from its impact value to a peak and, in a stable run, decays; the *convergence speed* is
the speed at which it first falls below a threshold after that peak, interpolated linearly between the two steps
around the crossing (:func:`crossing_speed_scalars`): in the full model's history (``cases.run``) and, compiled,
while the reduced model (:mod:`dynamics.pitch_plane`) integrates.
"""

from __future__ import annotations

__all__ = ["crossing_speed_scalars"]


def crossing_speed_scalars(
    previous_angle: float, angle: float, previous_speed: float, speed: float, threshold: float
) -> float:
    """The speed (m/s) at which the attack angle crosses ``threshold`` between two steps, linear in between: the
    angle goes from ``previous_angle`` at ``previous_speed`` to ``angle`` at ``speed`` (any one unit of angle);
    ``speed`` itself when the two angles are equal."""
    if previous_angle == angle:
        return speed
    share = (previous_angle - threshold) / (previous_angle - angle)
    return previous_speed + share * (speed - previous_speed)
