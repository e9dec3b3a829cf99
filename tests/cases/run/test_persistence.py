"""The one persistence layer: content-addressed caches keyed on the code, runs from the cache bit-identical."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from cases import load_scene, prepare_projectile, run_scene, scene_path
from cases.run import ContentCache, RunStore, cache_dir, cached_mesh, code_version, write_json
from cases.run.persistence import CODE, atomic_write
from cases.run.prepare import _prepare, preparation_key, prepared_path

COARSE = {"numerics.mesh_size": 0.04}


def test_a_mesh_is_made_once_and_read_back(projectile3):
    first = cached_mesh(projectile3, 0.03, 2)
    files = sorted((cache_dir() / "mesh").glob("*.vtu"))
    inputs = {"geometry": dataclasses.asdict(projectile3), "nose": "OgiveNose", "size": 0.03, "order": 2}
    path = ContentCache(cache_dir()).path("mesh", inputs, ".vtu")
    assert path in files
    stamp = path.stat().st_mtime_ns
    second = cached_mesh(projectile3, 0.03, 2)
    assert path.stat().st_mtime_ns == stamp  # read, not written again
    np.testing.assert_array_equal(first.points, second.points)
    np.testing.assert_array_equal(first.tetra, second.tetra)
    assert ContentCache.key("mesh", {**inputs, "order": 1}) != ContentCache.key("mesh", inputs)


def test_cache_keys_follow_the_code_that_computes_the_entry(monkeypatch):
    """An edit of any source file of the packages behind an entry gives it a new key (a stale entry is never
    served); the mesh's key does not depend on the dynamics, a run's does."""
    key = ContentCache.key("run", "abc")
    assert key == ContentCache.key("run", "abc") and key != ContentCache.key("run", "abd")
    assert "dynamics" in CODE["run"][0] and "dynamics" not in CODE["mesh"][0]
    versions = {kind: code_version(kind) for kind in CODE}
    assert len(set(versions.values())) == 3
    monkeypatch.setattr("cases.run.persistence.code_version", lambda kind: "edited")
    assert ContentCache.key("run", "abc") != key


def test_code_version_reads_every_source_file(tmp_path, monkeypatch):
    package = tmp_path / "probe_pkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "a.py").write_text("x = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setitem(CODE, "probe", (("probe_pkg",), ("numpy",)))
    first = code_version.__wrapped__("probe")
    (package / "a.py").write_text("x = 1  # a comment\n")
    assert code_version.__wrapped__("probe") != first


def test_prepared_projectile_comes_back_bit_identical_from_the_disk_cache():
    scene = load_scene(scene_path("forrestal_luk_test5"), COARSE)
    first = prepare_projectile(scene)
    path = prepared_path(*preparation_key(scene))
    assert path.exists()
    _prepare.cache_clear()  # forget the in-memory copy: the next one is read from disk
    again = prepare_projectile(scene)
    assert again is not first
    for name in ("points", "normals", "weights", "moment_arms"):
        np.testing.assert_array_equal(getattr(again.quadrature, name), getattr(first.quadrature, name))
    np.testing.assert_array_equal(again.mass.inertia, first.mass.inertia)
    np.testing.assert_array_equal(again.mass.centre, first.mass.centre)
    assert again.mass.mass == first.mass.mass and again.n_tetra == first.n_tetra
    # a corrupt entry is recomputed, not trusted
    path.write_bytes(b"not an npz file")
    _prepare.cache_clear()
    recomputed = prepare_projectile(scene)
    np.testing.assert_array_equal(recomputed.quadrature.weights, first.quadrature.weights)
    assert path.stat().st_size > 1000


def test_runs_from_the_cache_and_from_scratch_agree_bitwise():
    scene = load_scene(scene_path("forrestal_luk_test2"), COARSE)
    prepared_path(*preparation_key(scene)).unlink(missing_ok=True)
    _prepare.cache_clear()
    cold = run_scene(scene).trajectory  # mass properties and quadrature assembled by scikit-fem
    _prepare.cache_clear()
    warm = run_scene(scene).trajectory  # read back from the disk cache
    np.testing.assert_array_equal(cold.position, warm.position)
    np.testing.assert_array_equal(cold.attitude, warm.attitude)


def test_a_placed_counterweight_comes_back_from_the_cache_without_placing_it_again(monkeypatch):
    """#3's counterweight is placed by root finding on the mass and centre of mass (about 0.6 s); the
    prepared entry keeps the span it found, the very same floats, and a projectile read back from the
    disk places nothing."""
    import cases.scene.projectile as projectile_module

    scene = load_scene(scene_path("paper_p3"), COARSE)
    prepared_path(*preparation_key(scene)).unlink(missing_ok=True)
    _prepare.cache_clear()
    placed = prepare_projectile(scene).geometry
    assert placed.counterweight is not None

    def refuse(*args, **kwargs):
        raise AssertionError("placed again")

    monkeypatch.setattr(projectile_module, "place_counterweight", refuse)
    _prepare.cache_clear()
    again = prepare_projectile(scene).geometry
    assert again.counterweight == placed.counterweight and again == placed
    with pytest.raises(AssertionError, match="placed again"):
        scene.projectile.shape()  # the same spec with nothing cached places it


def test_run_store_keeps_records_under_the_scene_and_the_code(tmp_path):
    store = RunStore(tmp_path / "store")
    assert not (tmp_path / "store").exists()  # made at the first save only
    store.save("scene-a", {"depth": float("nan"), "end_reason": "stopped"}, b"gzipped history")
    assert store.finished("scene-a") and not store.finished("scene-b")
    assert json.loads(store.record_path("scene-a").read_text())["depth"] is None  # never NaN in JSON
    assert store.history_path("scene-a").read_bytes() == b"gzipped history"
    assert store.record_path("scene-a").parent == tmp_path / "store" / "run"
    store.save("scene-b", {"error": "RuntimeError: boom"}, None)
    assert store.load("scene-b") == {"error": "RuntimeError: boom"} and not store.finished("scene-b")
    file = tmp_path / "a-file"
    file.write_text("")
    with pytest.raises(ValueError, match="must be a folder"):
        RunStore(file)


def test_atomic_write_leaves_the_old_file_when_the_writer_fails(tmp_path):
    target = tmp_path / "out.txt"
    atomic_write(target, b"old")
    with pytest.raises(ZeroDivisionError):
        from cases.run.persistence import atomic_path

        with atomic_path(target) as tmp:
            tmp.write_bytes(b"half")
            raise ZeroDivisionError
    assert target.read_bytes() == b"old" and [p.name for p in tmp_path.iterdir()] == ["out.txt"]


def test_a_study_record_is_strict_json_with_null_for_non_finite_numbers(tmp_path):
    """Every study writes its record through ``write_json``: NaN and infinities become ``null`` (a strict reader
    takes the file), and what JSON cannot hold is refused, not written as its ``str``."""
    path = write_json(tmp_path / "record.json", {"a": [1.0, float("nan")], "b": {"c": np.float64(np.inf)}, "d": (2,)})
    text = path.read_text()
    assert "NaN" not in text and "Infinity" not in text
    record = json.loads(text, parse_constant=lambda name: pytest.fail(f"{name} in the file"))
    assert record == {"a": [1.0, None], "b": {"c": None}, "d": [2]}
    with pytest.raises(TypeError):
        write_json(tmp_path / "array.json", {"a": np.zeros(2)})
    assert not (tmp_path / "array.json").exists()  # nothing half written
