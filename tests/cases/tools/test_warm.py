"""The set-up's warm-up of the caches a first run or study would fill."""

from cases import scene_path
from cases.run import prepare
from cases.tools.warm import warm_caches


def test_warming_meshes_and_compiles_what_is_missing_and_then_nothing(tmp_path, monkeypatch):
    """A scene missing from the mesh cache is meshed and said so; run again, it finds everything cached, says
    nothing and reports nothing filled."""
    monkeypatch.setenv("PENETRATE_CACHE_DIR", str(tmp_path))  # an empty mesh cache (numba's stays put)
    prepare._prepare.cache_clear()  # as in the fresh process ./dev starts: nothing prepared in memory either
    said: list[str] = []
    _, filled = warm_caches([scene_path("forrestal_luk_test2")], say=said.append)
    assert filled and said == ["penetrate: meshing forrestal_luk_test2.toml (gmsh; a few seconds, once)"]
    said.clear()
    _, filled = warm_caches([scene_path("forrestal_luk_test2")], say=said.append)
    assert not filled and said == []
