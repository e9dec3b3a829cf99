"""Mass properties from scikit-fem against independent 1-D integrals of the profile."""

import numpy as np
import pytest

from fem_loads import mass_properties
from mesh import BODY, COUNTERWEIGHT, ProjectileGeometry, analytic_mass_properties, build_mesh

DEFAULT_SIZE = 0.01  # the shipped scenes' mesh size (m)


def _errors(geometry, size, densities, order=2):
    exact = analytic_mass_properties(geometry, densities[BODY], densities.get(COUNTERWEIGHT, 0.0))
    fem = mass_properties(build_mesh(geometry, size, order), densities)
    return np.array(
        [
            fem.volume / exact.volume - 1,
            fem.mass / exact.mass - 1,
            fem.centre_from_tip / exact.centre_from_tip - 1,
            fem.axial_inertia / exact.axial_inertia - 1,
            fem.inertia[1, 1] / exact.transverse_inertia - 1,
            fem.inertia[2, 2] / exact.transverse_inertia - 1,
        ]
    ), fem


@pytest.mark.parametrize("which", ["projectile3", "solid_ogive"])
def test_mass_properties_match_1d_integrals(which, projectile3, paper_profile):
    geometry = projectile3 if which == "projectile3" else ProjectileGeometry(paper_profile)
    densities = {BODY: 7850.0, COUNTERWEIGHT: 18000.0}
    coarse, _ = _errors(geometry, 2 * DEFAULT_SIZE, densities)
    default, fem = _errors(geometry, DEFAULT_SIZE, densities)
    assert np.abs(default).max() <= 1e-3
    assert np.abs(default).max() < np.abs(coarse).max()  # falls with refinement
    # symmetry: the centre lies on the axis and the body axes are principal
    assert np.abs(fem.centre[1:]).max() < 1e-12
    off_diagonal = fem.inertia - np.diag(np.diag(fem.inertia))
    assert np.abs(off_diagonal).max() < 1e-12 * fem.inertia.max()


def test_first_order_geometry_converges_at_second_order(paper_profile):
    geometry = ProjectileGeometry(paper_profile)
    coarse, _ = _errors(geometry, 0.02, {BODY: 1.0}, order=1)
    fine, _ = _errors(geometry, 0.01, {BODY: 1.0}, order=1)
    rate = np.log2(abs(coarse[0]) / abs(fine[0]))
    assert 1.5 < rate < 2.5  # flat facets cut the curved surface: O(h^2) volume error


def test_missing_density_is_an_error(projectile3):
    with pytest.raises(ValueError, match="no density"):
        mass_properties(build_mesh(projectile3, 0.03, 1), {BODY: 7850.0})
