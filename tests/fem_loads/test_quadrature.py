"""The outer-surface quadrature: closure, enclosed volume and area, under refinement."""

import math

import numpy as np
import pytest
from support import meshed

from fem_loads import surface_quadrature
from mesh import ProjectileGeometry, analytic_mass_properties, build_mesh

DEFAULT_SIZE = 0.01


def _errors(profile, size, model, order=2):
    mesh = meshed(ProjectileGeometry(profile), size, order)
    q = surface_quadrature(mesh, np.zeros(3), profile, model)
    closure = np.abs(q.normals.T @ q.weights).max() / (math.pi * profile.radius**2)
    volume = analytic_mass_properties(ProjectileGeometry(profile), 1.0).volume
    return np.array([closure, abs(q.enclosed_volume() / volume - 1), abs(q.area / profile.surface_area() - 1)])


@pytest.mark.parametrize("model", ["exact", "mesh"])
def test_surface_identities_at_default_mesh_and_under_refinement(paper_profile, model):
    """sum n dA ~ 0, sum (p . n) dA / 3 = V, sum dA = analytic area; errors fall as h halves."""
    coarse = _errors(paper_profile, 2 * DEFAULT_SIZE, model)
    default = _errors(paper_profile, DEFAULT_SIZE, model)
    # closure relative to the nose's projected area; volume and area relative
    assert default[0] < (1e-12 if model == "mesh" else 2e-4)
    assert default[1] < 1e-4 and default[2] < 1e-4
    falling = default[1:] < coarse[1:]
    if model == "exact":
        falling = np.append(falling, default[0] < coarse[0])
    assert falling.all()


def test_flat_mesh_normals_load_the_shank_but_exact_ones_do_not(paper_profile):
    """Flat facets on the cylinder tilt forward or back; exact normals are radial on the shank."""
    mesh = build_mesh(ProjectileGeometry(paper_profile), DEFAULT_SIZE, 1)
    shank = None
    for model in ("mesh", "exact"):
        q = surface_quadrature(mesh, np.zeros(3), paper_profile, model)
        s = -q.points[:, 0]
        shank = (s > paper_profile.nose_length + 0.01) & (s < 0.92)
        forward = q.normals[shank, 0]
        if model == "mesh":
            assert np.abs(forward).max() > 0.01
        else:
            assert np.abs(forward).max() == 0.0
