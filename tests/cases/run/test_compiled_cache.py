"""numba's cache is named for the code compiled into the steps: found from the entry points' imports, so that an
edit of any module compiled into a step compiles it afresh, and an edit elsewhere does not."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from cases.run import compiled
from cases.run.compiled import ROOT, compiled_sources

PACKAGES = ("mesh", "fem_loads", "dynamics", "cases")


@pytest.fixture(scope="module")
def tree(tmp_path_factory) -> Path:
    """A copy of the project's Python sources, to edit."""
    root = tmp_path_factory.mktemp("tree")
    for package in PACKAGES:
        shutil.copytree(ROOT / package, root / package, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return root


def digest(root: Path) -> str:
    return compiled._sources_digest.__wrapped__(root)


def test_the_sources_are_what_the_steps_compile():
    sources = compiled_sources()
    # the entry points, the Runge-Kutta step with its arithmetic, the load kernels and the law
    for name in ("cases.run.dafl_step", "cases.run.pitch_plane_step", "dynamics.compiled_rk", "dynamics.quaternion"):
        assert name in sources
    for name in (
        "fem_loads.kernels.mesh_loop",
        "fem_loads.kernels.point",
        "fem_loads.kernels.rings",
        "fem_loads.resistance",
    ):
        assert name in sources
    assert "dynamics.rigid_body" in sources  # euler_scalars is compiled into both steps
    # neither the command line, the studies nor the meshing is compiled
    assert not any(name.startswith(("cases.cli", "cases.studies", "mesh.cad", "mesh.symmetry")) for name in sources)


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_an_edit_of_any_compiled_module_names_a_new_cache_folder(tree):
    before = digest(tree)
    for name in compiled_sources(tree):
        path = compiled._module_file(name, tree)
        assert path is not None
        text = path.read_bytes()
        path.write_bytes(text + b"\n# one more byte\n")
        try:
            assert digest(tree) != before, name
        finally:
            path.write_bytes(text)
    assert digest(tree) == before


@pytest.mark.parametrize("name", ["cases.cli.run", "cases.studies.engine.sweep", "mesh.cad"])
def test_an_edit_elsewhere_keeps_the_cache(tree, name):
    before = digest(tree)
    path = compiled._module_file(name, tree)
    assert path is not None
    text = path.read_bytes()
    path.write_bytes(text + b"\n# one more byte\n")
    try:
        assert digest(tree) == before
    finally:
        path.write_bytes(text)


def test_an_entry_point_needs_compiling_until_it_is_cached_for_this_copy(tmp_path, monkeypatch):
    """Each compiled function has its own index file, looked for by its own name (the trajectory's does not stand
    for the batch of runs beside it); one found in the folder of another copy of the code (another checkout) is
    not this copy's machine code."""
    from numba.core.caching import _CacheLocator

    monkeypatch.setattr(compiled, "numba_cache_folder", lambda: tmp_path)
    source = Path(compiled.__file__).with_name("pitch_plane_step.py")
    here = tmp_path / _CacheLocator.get_suitable_cache_subpath(str(source))
    elsewhere = tmp_path / _CacheLocator.get_suitable_cache_subpath(str(tmp_path / "other" / "run" / "x.py"))
    for folder in (here, elsewhere):
        folder.mkdir(parents=True)
    (elsewhere / "pitch_plane_step.pitch_plane_trajectory-35.py311.nbi").touch()
    (elsewhere / "pitch_plane_step.pitch_plane_turns-52.py311.nbi").touch()
    assert compiled.needs_compiling("pitch_plane_trajectory") and compiled.needs_compiling("pitch_plane_turns")
    (here / "pitch_plane_step.pitch_plane_trajectory-35.py311.nbi").touch()
    assert not compiled.needs_compiling("pitch_plane_trajectory")
    assert compiled.needs_compiling("pitch_plane_turns")
    (here / "pitch_plane_step.pitch_plane_turns-52.py311.nbi").touch()
    assert not compiled.needs_compiling("pitch_plane_turns")
    assert compiled.needs_compiling("dafl_step")
