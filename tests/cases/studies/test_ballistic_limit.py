"""``penetrate ballistic-limit``: the lowest speed that perforates, against the 1-D model of the nose (an
independent integration over the exact profile, without the mesh)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from cases import scene_path
from cases.cli import main
from cases.reference.normal_impact import ballistic_limit_1d, slab_run_1d, target_layers
from cases.run import prepare_projectile
from cases.scene import load_scene
from fem_loads.target import LayeredTarget

# test 2's projectile and soil, its target made a 2 m slab: the scene file with its [target] table replaced
SLAB = '[target]\nlayers = [{ thickness = 2.0, law = "soil" }]\n'


@pytest.fixture(scope="module")
def slab_scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    text = scene_path("forrestal_luk_test2").read_text()
    head, rest = text.split("[target]\n", 1)
    path = tmp_path_factory.mktemp("slab") / "slab.toml"
    path.write_text(head + SLAB + rest[rest.index("\n[impact]") :])
    return path


@pytest.fixture(scope="module")
def limit_1d(slab_scene: Path) -> float:
    scene = load_scene(slab_scene)
    prepared = prepare_projectile(scene)
    built = scene.target.build()
    assert isinstance(built, LayeredTarget)
    slices = target_layers([2.0, None], [built.laws[0], None])
    return ballistic_limit_1d(prepared.profile, slices, prepared.mass.mass, **scene.effects.contact_ramp)


def search(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, dict]:
    code = main(["ballistic-limit", *args, "--json", "--workers", "1", "--no-progress"])
    return code, json.loads(capsys.readouterr().out)


def test_the_1d_limit_is_where_the_1d_runs_change(slab_scene: Path, limit_1d: float) -> None:
    scene = load_scene(slab_scene)
    prepared = prepare_projectile(scene)
    built = scene.target.build()
    assert isinstance(built, LayeredTarget)
    slices = target_layers([2.0, None], [built.laws[0], None])
    ramp = scene.effects.contact_ramp
    below = slab_run_1d(prepared.profile, slices, prepared.mass.mass, limit_1d * (1 - 1e-4), **ramp)
    above = slab_run_1d(prepared.profile, slices, prepared.mass.mass, limit_1d * (1 + 1e-4), **ramp)
    assert math.isnan(below[0]) and 0.0 < above[0] < 0.05 * limit_1d


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_the_ballistic_limit_agrees_with_the_1d_model_in_few_runs(
    slab_scene: Path, limit_1d: float, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    store = tmp_path / "store"
    code, result = search(capsys, str(slab_scene), "--store", str(store))
    assert code == 0 and result["guide"].startswith("guided")
    assert result["ballistic_limit"] == pytest.approx(limit_1d, rel=1e-2)
    assert result["full_runs"] <= 8
    low, high = result["bracket"]
    assert high - low <= 1.0 + 1e-9
    runs = {run["speed"]: run for run in result["runs"]}
    assert not runs[low]["perforated"] and runs[high]["perforated"]
    assert 0.0 < runs[high]["residual_velocity"] < 0.2 * high
    # resumed: the same answer from the store, no run made again
    stored = sorted(p.name for p in store.rglob("*"))
    assert search(capsys, str(slab_scene), "--store", str(store)) == (code, result)
    assert sorted(p.name for p in store.rglob("*")) == stored


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_an_unguided_search_splits_the_range(
    slab_scene: Path, limit_1d: float, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = ["--guide", "none", "--speeds", "100:220", "--resolution", "4", "--store", str(tmp_path / "store")]
    code, result = search(capsys, str(slab_scene), *args)
    assert code == 0 and result["guide"].startswith("unguided")
    low, high = result["bracket"]
    assert low < limit_1d * 1.01 and high > limit_1d * 0.99 and high - low <= 4.0 + 1e-9


def test_a_range_without_the_change_says_so(slab_scene: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]):
    args = ["--guide", "none", "--speeds", "100:120", "--resolution", "5", "--store", str(tmp_path / "store")]
    code, result = search(capsys, str(slab_scene), *args)
    assert code == 1 and result["ballistic_limit"] is None
    assert result["message"] == "no run perforates, up to 120 m/s (--speeds)"


def test_a_target_without_a_rear_face_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["ballistic-limit", str(scene_path("forrestal_luk_test2")), "--store", str(tmp_path / "store")])
    error = capsys.readouterr().err.strip()
    assert code == 2 and len(error.splitlines()) == 1
    assert "target.layers: penetrate ballistic-limit needs a target with a rear face" in error
    assert not (tmp_path / "store").exists()
