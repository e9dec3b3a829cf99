"""The references of a normal impact against what they must equal: the nose factors' closed forms, the closed-form
depth after embedding, and the sharp law as the limit of a vanishing contact ramp."""

import math

import pytest

from cases.reference.normal_impact import (
    axial_depth_1d,
    axial_force,
    closed_form_depth,
    embedded_axial_force,
    nose_factors,
)
from fem_loads import resistance_law
from mesh.profile import ConeNose, OgiveNose, Profile

SOIL = resistance_law("soil")
NOSES = {"ogive CRH 3": OgiveNose(3.0), "cone 20 deg": ConeNose(20.0)}
EXACT_N = {"ogive CRH 3": (8 * 3.0 - 1) / (24 * 3.0**2), "cone 20 deg": math.sin(math.radians(20.0)) ** 2}


@pytest.mark.parametrize("name", NOSES)
def test_the_embedded_nose_s_force_is_its_nose_factor_s(name):
    """The 1-D force on a fully embedded nose, integrated along its meridian, is the closed form
    ``pi a^2 (A sigma_0 + N B rho_0 V^2)`` with the published ``N`` of the nose."""
    profile = Profile(0.0762, 0.6, NOSES[name])
    assert nose_factors(profile) == pytest.approx((1.0, EXACT_N[name]), rel=1e-12)
    for speed in (100.0, 400.0):
        integrated = axial_force(profile, SOIL, profile.nose_length + 0.1, speed, 0.0)
        assert integrated == pytest.approx(embedded_axial_force(profile, SOIL, speed), rel=1e-9)


def test_after_embedding_the_depth_is_the_closed_form():
    """A run that enters at speed ``V`` and leaves the entry phase at ``V1`` goes on, to rest, exactly the closed
    form's distance from ``V1``; started at rest it goes nowhere."""
    profile, mass = Profile(0.0762, 0.6, OgiveNose(3.0)), 13.0
    depth, embedded_at = axial_depth_1d(profile, SOIL, mass, 300.0)
    assert depth == pytest.approx(profile.nose_length + closed_form_depth(profile, SOIL, mass, embedded_at), rel=1e-12)
    assert 0.0 < embedded_at < 300.0 and closed_form_depth(profile, SOIL, mass, 0.0) == 0.0


def test_the_sharp_law_is_the_limit_of_a_vanishing_contact_ramp():
    """The whole-run integration with a contact ramp of width ``w`` (m/s) converges to the sharp law's path as
    ``w`` shrinks, at second order while the speed stays well above ``w`` (to 30 m/s here): the ramp only lowers
    the stress, so every path is longer than the sharp one."""
    profile, mass = Profile(0.0762, 0.6, OgiveNose(3.0)), 13.0
    sharp, _ = axial_depth_1d(profile, SOIL, mass, 300.0, stop_speed=30.0)
    gaps = [
        axial_depth_1d(profile, SOIL, mass, 300.0, stop_speed=30.0, contact_width=w)[0] - sharp
        for w in (4.0, 2.0, 1.0, 0.5)
    ]
    assert all(gap > 0.0 for gap in gaps)
    assert all(3.5 < coarser / finer < 4.5 for coarser, finer in zip(gaps, gaps[1:]))
    assert gaps[-1] < 1e-4 * sharp
