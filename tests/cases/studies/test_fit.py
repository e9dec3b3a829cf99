"""penetrate fit: synthetic recovery, the acceptance fit, resumption, identifiability, bad input."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from cases import load_scene, run_scene, summarise
from cases.cli import main
from cases.run import RunStore
from cases.studies import Pool
from cases.studies.measured.fit import NotIdentifiable, fit

TEST2 = "cases/forrestal_luk_test2.toml"
TRUTH = {"A": 1.718, "sigma_0": 10e6, "B": 1.227, "rho_0": 1860.0}
START = {"A": 1.4, "sigma_0": 10e6, "B": 1.5, "rho_0": 1860.0}  # the fit starts away from the truth
START_B = {**TRUTH, "B": 1.5}  # for fits of B alone: A at its true value
COARSE = ("numerics.mesh_size", 0.04)  # 40 mm: about 0.1 s a run; the model is the model at any mesh


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    return RunStore(tmp_path_factory.mktemp("fit-store"))


def truth(scene: str, quantity: str) -> float:
    """The quantity of ``scene`` run at the true soil constants (the synthetic observation without noise)."""
    result = run_scene(load_scene(scene, [("target.law", TRUTH), COARSE]))
    return float(getattr(summarise(result), quantity))


def scene_at_speed(tmp_path, speed: float) -> str:
    path = tmp_path / f"test2_{speed:g}.toml"
    path.write_text(Path(TEST2).read_text().replace("speed = 280.0", f"speed = {speed}"))
    return str(path)


def observe(scene: str, quantity: str, sigma: float, rng, own: str | None = None) -> str:
    value = truth(scene, quantity) + rng.normal(0.0, sigma)
    prefix = "" if scene == own else f"{scene}:"
    return f"{prefix}{quantity}={value!r}+-{sigma!r}"


def assert_recovered(result, keys):
    """Each fitted value within two of its reported standard errors of the truth (95 % for a normal error)."""
    for key in keys:
        true = TRUTH[key.rsplit(".", 1)[1]]
        error = result.standard_errors[key]
        assert error is not None and error > 0
        assert abs(result.parameters[key] - true) < 2 * error, (key, result.parameters[key], true, error)


def test_one_parameter_from_one_scene(store):
    rng = np.random.default_rng(1)
    observation = observe(TEST2, "depth", 0.01, rng, own=TEST2)
    result = fit(
        TEST2, [("target.law", START_B), COARSE], ["target.law.B=0.3:3"], [observation], store, Pool(progress=False)
    )
    assert_recovered(result, ["target.law.B"])
    # one observation, one parameter: the error is the noise over the slope, so the fit meets it exactly
    assert abs(result.observations[0]["residual"]) < 1e-6


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_two_parameters_from_one_scene(store):
    """Depth and stopping time of one shot tell A from B (the time weighs the slow end, where A rules)."""
    rng = np.random.default_rng(2)
    observations = [observe(TEST2, "depth", 0.005, rng, own=TEST2), observe(TEST2, "final_time", 5e-5, rng, own=TEST2)]
    result = fit(
        TEST2,
        [("target.law", START), COARSE],
        ["target.law.B=0.3:3", "target.law.A=0.5:3"],
        observations,
        store,
        Pool(progress=False),
    )
    assert_recovered(result, ["target.law.A", "target.law.B"])
    correlation = np.array(result.correlation)
    assert correlation.shape == (2, 2) and np.allclose(np.diag(correlation), 1.0) and correlation[0, 1] < -0.5


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_one_and_two_parameters_from_several_scenes(store, tmp_path):
    """Depths at 150, 280 and 600 m/s: B alone, then A and B (the static term rules the slow shot)."""
    rng = np.random.default_rng(3)
    scenes = [scene_at_speed(tmp_path, v) for v in (150.0, 280.0, 600.0)]
    observations = [observe(s, "depth", 0.005, rng) for s in scenes]
    one = fit(
        TEST2, [("target.law", START_B), COARSE], ["target.law.B=0.3:3"], observations, store, Pool(progress=False)
    )
    assert {row["scene"] for row in one.observations} == set(scenes)
    assert_recovered(one, ["target.law.B"])
    two = fit(
        TEST2,
        [("target.law", START), COARSE],
        ["target.law.B=0.3:3", "target.law.A=0.5:3"],
        observations,
        store,
        Pool(progress=False),
    )
    assert_recovered(two, ["target.law.A", "target.law.B"])
    # B alone with A held at a wrong value absorbs what it can; the residuals show what it cannot
    wrong = fit(
        TEST2, [("target.law", START), COARSE], ["target.law.B=0.3:3"], observations, store, Pool(progress=False)
    )
    assert sum(r["residual"] ** 2 for r in wrong.observations) > 4 * sum(r["residual"] ** 2 for r in two.observations)


def test_the_acceptance_fit_reaches_the_depth_in_at_most_ten_runs(tmp_path, capsys):
    """Test 2 at its shipped numerics: the B whose run gives 5.5 m, within 0.2 %, in at most 10 runs."""
    law = "target.law={A = 1.718, sigma_0 = 10e6, B = 1.227, rho_0 = 1860}"
    arguments = [
        "fit",
        TEST2,
        "--set",
        law,
        "--param",
        "target.law.B=0.3:3",
        "--observe",
        "depth=5.5",
        "--store",
        str(tmp_path / "store"),
        "--out",
        str(tmp_path / "out"),
        "--no-progress",
        "--json",
    ]
    assert main(arguments) == 0
    record = json.loads(capsys.readouterr().out)
    assert set(record) >= {"parameters", "standard_errors", "observations", "runs"}
    assert record["runs"] <= 10
    b = record["parameters"]["target.law.B"]
    check = summarise(run_scene(load_scene(TEST2, [("target.law", {**TRUTH, "B": b})])))
    assert abs(check.depth / 5.5 - 1) < 2e-3
    assert record["observations"][0] | {"fitted": 0, "residual": 0} == {
        "scene": TEST2,
        "quantity": "depth",
        "impact_speed": 280.0,
        "observed": 5.5,
        "sigma": None,
        "fitted": 0,
        "residual": 0,
    }
    assert {p.name for p in (tmp_path / "out").iterdir()} == {"fit.md", "fit.json", "fit.png"}
    # the same fit again: every run is in the store, none is made
    assert main(arguments) == 0
    again = json.loads(capsys.readouterr().out)
    assert again["new_runs"] == 0 and again["parameters"] == record["parameters"]


def test_two_parameters_from_one_observation_are_not_identifiable(store):
    with pytest.raises(NotIdentifiable, match=r"2 parameters .* from 1 observation"):
        fit(
            TEST2,
            [("target.law", START), COARSE],
            ["target.law.B=0.3:3", "target.law.A=0.5:3"],
            ["depth=5.0"],
            store,
            Pool(progress=False),
        )


@pytest.mark.parametrize(
    "params, observations",
    [
        (["target.law.B=0.3:3", "target.law.A=0.5:3"], ["depth=5.0"]),
        (["target.law.B=0.3:3", "target.law.A=0.5:3", "impact.speed=200:400"], ["depth=5.0+-0.1", "final_time=0.04"]),
    ],
)
def test_too_few_observations_are_refused_before_any_run(params, observations, tmp_path, capsys, monkeypatch):
    """Counting alone shows it: the command says how many observations the parameters need, and makes no run."""
    from cases.studies.engine import sweep as sweep_module

    def no_runs(*args, **kwargs):
        raise AssertionError("a run was started")

    monkeypatch.setattr(sweep_module, "run_missing", no_runs)
    options = [o for p in params for o in ("--param", p)] + [o for v in observations for o in ("--observe", v)]
    law = "target.law={A = 1.4, sigma_0 = 10e6, B = 1.5, rho_0 = 1860}"
    store, out = tmp_path / "s", tmp_path / "o"
    assert main(["fit", TEST2, "--set", law, *options, "--store", str(store), "--out", str(out)]) == 1
    err = capsys.readouterr().err
    count = len(params)
    assert err.count("\n") == 1 and err.startswith("penetrate fit: not identifiable:"), err
    assert f"{count} parameters need at least {count} observations (--observe; {count + 1} for standard" in err
    assert not store.exists() and not out.exists()  # the run store stays empty: no run was made


@pytest.mark.slow  # the default suite keeps within 4 minutes on 2 cores; CI runs it
def test_a_characteristic_speed_not_found_says_what_to_change(tmp_path, monkeypatch):
    """#3 without a disturbance never turns: the fit stops at its first search, naming what would find one."""
    from types import SimpleNamespace

    from cases.studies.engine.sweep import SweepResult
    from cases.studies.speeds import characteristic as speeds_module

    def stable(sweep, store, pool=None):
        summary = SimpleNamespace(max_attack_angle=0.0, end_reason="stopped", axis_angle_change=0.0)
        runs = [SimpleNamespace(failed=False, summary=summary, key=str(s.impact.speed)) for s in sweep.scenes]
        return SweepResult(sweep, runs, store)

    monkeypatch.setattr(speeds_module, "run_sweep", stable)
    with pytest.raises(RuntimeError) as caught:
        fit(
            "cases/paper_p3.toml",
            [("impact.attack_angle", 0.0)],
            ["projectile.transverse_inertia_scale=1:3"],
            ["critical_velocity=1000+-10"],
            RunStore(tmp_path),
            Pool(progress=False),
        )
    assert str(caught.value).endswith(
        "(every run is stable, up to 2400 m/s): keep the --param ranges where the scene has one between 200 and"
        " 2400 m/s, or give the scene a disturbance (--set impact.attack_angle=1)"
    )


def test_a_flat_parameter_is_not_identifiable(store):
    """Test 2 stops at 0.04 s: the time limit (default 1 s) changes nothing."""
    with pytest.raises(NotIdentifiable, match="no observation changes with numerics.time_limit"):
        fit(TEST2, [COARSE], ["numerics.time_limit=0.5:2"], ["depth=5.0"], store, Pool(progress=False))


def test_collinear_parameters_are_not_identifiable(store):
    """Two shots at 280 m/s move with A and B together (docs/calibration.md): a combination only."""
    with pytest.raises(NotIdentifiable, match="collinear"):
        fit(
            TEST2,
            [("target.law", START), COARSE],
            ["target.law.B=0.3:3", "target.law.A=0.5:3"],
            ["depth=5.0", "cases/forrestal_luk_test5.toml:path_length=5.0"],
            store,
            Pool(progress=False),
        )


def test_not_identifiable_is_one_line_and_exit_code_1(tmp_path, capsys):
    assert (
        main(
            [
                "fit",
                TEST2,
                "--set",
                "numerics.mesh_size=0.04",
                "--param",
                "numerics.time_limit=0.5:2",
                "--observe",
                "depth=5",
                "--store",
                str(tmp_path / "s"),
                "--out",
                str(tmp_path / "o"),
                "--no-progress",
            ]
        )
        == 1
    )
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("penetrate fit: not identifiable")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    "options, message",
    [
        (["--param", "target.law.B=0.3:3", "--observe", "depth=5.5"], "holds no number at target.law.B"),
        (["--param", "impact.speed=400:100", "--observe", "depth=5.5"], "need LO < HI"),
        (["--param", "impact.speed=1:nan", "--observe", "depth=5.5"], "must be a finite number"),
        (["--param", "impact.speed=1:2", "--observe", "depth=5.5"], "must lie inside 1:2"),
        (["--param", "impact.speed", "--observe", "depth=5.5"], "expected KEY=LO:HI"),
        (["--param", "impact..speed=1:2", "--observe", "depth=5.5"], "dotted path"),
        (["--param", "impact.speed=100:400", "--observe", "dept=5.5"], "unknown quantity 'dept'"),
        (["--param", "impact.speed=100:400", "--observe", "depth"], "expected [SCENE:]QUANTITY=VALUE"),
        (["--param", "impact.speed=100:400", "--observe", "depth=5+-0"], "standard deviation must be > 0"),
        (["--param", "impact.speed=100:400", "--observe", "nope.toml:depth=5"], "scene file 'nope.toml' not found"),
        (["--param", "impact.speed=100:400"], "give at least one observation"),
        (["--observe", "depth=5"], "give at least one parameter"),
        (
            ["--param", "impact.speed=100:400", "--param", "impact.speed=100:400", "--observe", "depth=5"],
            "each key once",
        ),
        (["--param", "impact.speed=100:400", "--observe", "depth=5", "--difference-step", "2"], "must be below 1"),
    ],
)
def test_bad_fit_input_is_one_line_exit_2(options, message, tmp_path, capsys):
    assert (
        main(["fit", TEST2, *options, "--store", str(tmp_path / "s"), "--out", str(tmp_path / "o"), "--no-progress"])
        == 2
    )
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err, err
    assert not (tmp_path / "s").exists() and not (tmp_path / "o").exists()


@pytest.mark.slow
def test_standard_errors_cover_the_truth_about_as_often_as_they_say(store):
    """Over 30 noise draws, |fit - truth| < SE in about 68 % of fits (binomial: 14-26 of 30 at 99.6 %)."""
    inside = 0
    rng = np.random.default_rng(10)
    depth = truth(TEST2, "depth")
    for _ in range(30):
        observation = f"depth={depth + rng.normal(0.0, 0.02)!r}+-0.02"
        result = fit(
            TEST2, [("target.law", START_B), COARSE], ["target.law.B=0.3:3"], [observation], store, Pool(progress=False)
        )
        inside += abs(result.parameters["target.law.B"] - TRUTH["B"]) < result.standard_errors["target.law.B"]
    assert 14 <= inside <= 26, inside


@pytest.mark.slow
def test_a_characteristic_speed_is_fitted_through_its_search(store):
    """#3 at 40 mm: the transverse inertia scale whose critical speed is 1000 m/s, +-10 m/s."""
    result = fit(
        "cases/paper_p3.toml",
        [COARSE, ("projectile.transverse_inertia_scale", 1.5)],
        ["projectile.transverse_inertia_scale=1:3"],
        ["critical_velocity=1000+-10"],
        store,
        Pool(progress=False),
        resolution=5.0,
    )
    scale = result.parameters["projectile.transverse_inertia_scale"]
    assert 1.0 < scale < 3.0 and math.isfinite(result.standard_errors["projectile.transverse_inertia_scale"])
    assert abs(result.observations[0]["fitted"] - 1000.0) <= 10.0


@pytest.mark.slow
def test_the_calibrated_family_reproduces_3s_critical_speed(tmp_path, capsys):
    """cases/paper_fitted_p3.toml at its shipped numerics: within 2 % of the paper's 1110 m/s."""
    assert (
        main(["critical", "cases/paper_fitted_p3.toml", "--store", str(tmp_path / "s"), "--no-progress", "--json"]) == 0
    )
    critical = json.loads(capsys.readouterr().out)["critical_velocity"]
    assert abs(critical / 1110.0 - 1.0) < 0.02, critical


@pytest.mark.parametrize("member", [1, 2, 3, 4])
def test_the_calibrated_scenes_differ_from_the_family_only_by_the_factor(member):
    fitted = load_scene(f"cases/paper_fitted_p{member}.toml")
    plain = load_scene(f"cases/paper_p{member}.toml")
    assert fitted.projectile.transverse_inertia_scale == 2.12 and plain.projectile.transverse_inertia_scale == 1.0
    same = fitted.model_dump()
    same["projectile"]["transverse_inertia_scale"] = 1.0
    same["name"], same["description"] = plain.name, plain.description
    assert same == plain.model_dump()
