"""Exact (1-D) mass properties of a projectile and the counterweight placement helper.

The paper's projectile family (brief section 4) shares one steel case; a
tungsten counterweight fills the cavity between two cross-sections whose
position sets the centre of mass.  :func:`place_counterweight` finds those two
cross-sections for a target mass and centre of mass from 1-D integrals of the
profile, independently of any mesh.
"""

from __future__ import annotations

from dataclasses import dataclass

from .profile import Interior, Profile, ProjectileGeometry, RevolvedMoments, revolved_moments

__all__ = ["AxisymmetricMassProperties", "analytic_mass_properties", "place_counterweight"]


@dataclass(frozen=True)
class AxisymmetricMassProperties:
    """Mass properties of an axisymmetric body.

    Attributes
    ----------
    mass : float
        Mass (kg).
    centre_from_tip : float
        Distance of the centre of mass from the nose tip (m).
    axial_inertia : float
        Moment of inertia about the axis (kg m^2).
    transverse_inertia : float
        Moment of inertia about a transverse axis through the centre of mass (kg m^2).
    volume : float
        Volume of solid material (m^3).
    """

    mass: float
    centre_from_tip: float
    axial_inertia: float
    transverse_inertia: float
    volume: float


def _outer_moments(profile: Profile, s0: float = 0.0, s1: float | None = None) -> RevolvedMoments:
    s1 = profile.length if s1 is None else s1
    return revolved_moments(profile.radius_at, s0, s1, profile.breakpoints, profile.curve is not None)


def _cavity_moments(geometry: ProjectileGeometry, s0: float, s1: float) -> RevolvedMoments:
    s0 = max(s0, geometry.cavity_start)
    s1 = min(s1, geometry.cavity_end)
    return revolved_moments(
        geometry.cavity_radius_at, s0, s1, geometry.profile.breakpoints, geometry.profile.curve is not None
    )


def region_moments(geometry: ProjectileGeometry) -> tuple[RevolvedMoments, RevolvedMoments]:
    """Per-unit-density moments of the body (case) and of the counterweight."""
    outer = _outer_moments(geometry.profile)
    if geometry.interior is None:
        return outer, RevolvedMoments(0.0, 0.0, 0.0, 0.0)
    body = outer - _cavity_moments(geometry, geometry.cavity_start, geometry.cavity_end)
    if geometry.counterweight is None:
        return body, RevolvedMoments(0.0, 0.0, 0.0, 0.0)
    return body, _cavity_moments(geometry, *geometry.counterweight)


def analytic_mass_properties(
    geometry: ProjectileGeometry, body_density: float, counterweight_density: float = 0.0
) -> AxisymmetricMassProperties:
    """Exact mass properties from 1-D integrals of the profile.

    Parameters
    ----------
    geometry : ProjectileGeometry
        Outer profile, cavity and counterweight.
    body_density, counterweight_density : float
        Densities (kg/m^3).
    """
    body, weight = region_moments(geometry)
    total = body * body_density + weight * counterweight_density
    mass = total.volume
    centre = total.first_moment / mass
    return AxisymmetricMassProperties(
        mass=mass,
        centre_from_tip=centre,
        axial_inertia=total.axial_second_moment,
        transverse_inertia=total.transverse_second_moment - mass * centre**2,
        volume=body.volume + weight.volume,
    )


def place_counterweight(
    profile: Profile,
    interior: Interior,
    body_density: float,
    counterweight_density: float,
    mass: float,
    centre_from_tip: float,
) -> tuple[float, float]:
    """Find the cross-sections ``(start, end)`` of a counterweight filling the cavity.

    The counterweight fills the cavity between ``start`` and ``end`` (m from
    the tip); the rest of the cavity is empty.  The two are chosen so that the
    whole projectile has the given ``mass`` (kg) and its centre of mass lies
    ``centre_from_tip`` (m) behind the tip.

    Raises
    ------
    ValueError
        If no placement inside the cavity gives that mass and centre.
    """
    from scipy import optimize  # imported where used (slow to import)

    shell_geometry = ProjectileGeometry(profile, interior)
    shell, _ = region_moments(shell_geometry)
    lo, hi = shell_geometry.cavity_start, shell_geometry.cavity_end
    weight_mass = mass - body_density * shell.volume
    weight_volume = weight_mass / counterweight_density
    cavity = _cavity_moments(shell_geometry, lo, hi)
    if not (0.0 < weight_volume < cavity.volume):
        raise ValueError(
            f"mass = {mass} kg: with this case ({body_density * shell.volume:.6g} kg) the counterweight"
            f" would need {weight_volume:.6g} m^3, but the cavity holds (0, {cavity.volume:.6g}) m^3"
        )
    weight_centre = (mass * centre_from_tip - body_density * shell.first_moment) / weight_mass

    def end_for(start: float) -> float:
        # volume between start and end grows monotonically with end
        def excess(end: float) -> float:
            return _cavity_moments(shell_geometry, start, end).volume - weight_volume

        if excess(hi) <= 0.0:
            return hi
        return optimize.brentq(excess, start, hi, xtol=1e-14, rtol=1e-14)

    # the last start that still leaves room for the whole volume
    start_max = optimize.brentq(
        lambda start: _cavity_moments(shell_geometry, start, hi).volume - weight_volume,
        lo,
        hi,
        xtol=1e-14,
        rtol=1e-14,
    )

    def centre_error(start: float) -> float:
        end = end_for(start)
        part = _cavity_moments(shell_geometry, start, end)
        return part.first_moment / part.volume - weight_centre

    low_centre, high_centre = centre_error(lo), centre_error(start_max)
    if not (low_centre <= 0.0 <= high_centre):
        reach = (low_centre + weight_centre, high_centre + weight_centre)
        lc_lo = (body_density * shell.first_moment + weight_mass * reach[0]) / mass
        lc_hi = (body_density * shell.first_moment + weight_mass * reach[1]) / mass
        raise ValueError(
            f"centre_of_mass = {centre_from_tip} m: with mass {mass} kg the counterweight can place it"
            f" only within [{lc_lo:.6g}, {lc_hi:.6g}] m from the tip"
        )
    start = optimize.brentq(centre_error, lo, start_max, xtol=1e-13, rtol=1e-14)
    return start, end_for(start)
