"""Shared fixtures: a private mesh cache and the paper's projectiles."""

from __future__ import annotations

import os

import pytest

from mesh import Interior, OgiveNose, Profile, ProjectileGeometry, place_counterweight

STEEL, TUNGSTEN = 7850.0, 18000.0


@pytest.fixture(autouse=True, scope="session")
def private_mesh_cache(tmp_path_factory):
    """Keep the tests' meshes out of the user's cache (and start from an empty one)."""
    folder = tmp_path_factory.mktemp("mesh-cache")
    # the compiled kernels are not meshes: they stay in the user's cache (in a folder named for their code,
    # cases/run/compiled.py), so that each test session does not compile them again (about 10 s)
    if "NUMBA_CACHE_DIR" not in os.environ:
        from cases.run import cache_dir

        os.environ["NUMBA_CACHE_DIR"] = str(cache_dir() / "numba")
    # compile the compiled step here, once, before any test spawns study workers that would each compile it
    from cases.run.compiled import precompile

    precompile()
    old = os.environ.get("PENETRATE_CACHE_DIR")
    os.environ["PENETRATE_CACHE_DIR"] = str(folder)
    yield folder
    if old is None:
        os.environ.pop("PENETRATE_CACHE_DIR", None)
    else:
        os.environ["PENETRATE_CACHE_DIR"] = old


@pytest.fixture(scope="session")
def paper_profile() -> Profile:
    """The paper's 155 mm, CRH 5, 6-calibre projectile."""
    return Profile(0.155, 0.93, OgiveNose(5.0))


@pytest.fixture(scope="session")
def projectile3(paper_profile) -> ProjectileGeometry:
    """Projectile #3 (Lc/L = 56.36 %) with the brief's stand-in interior."""
    interior = Interior(0.01, 0.02)
    span = place_counterweight(paper_profile, interior, STEEL, TUNGSTEN, 75.67, 0.5636 * 0.93)
    return ProjectileGeometry(paper_profile, interior, span)
