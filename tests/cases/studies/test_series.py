"""Test series in, predictions out: series files, penetrate validate, compare --series and fit --series.

The predictions of a series are the runs of its shots, so each is checked against a run of the same scene
made apart (``penetrate run``'s own path); the summaries against the rows they summarise; a fit against a
brute-force scan of its sum of squares; the concrete family against its cavity-expansion form.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from cases import load_scene, run_scene, scene_path, summarise
from cases.cli import main
from cases.run import RunStore
from cases.scene import InputError
from cases.studies.engine.pool import Pool
from cases.studies.measured.compare import compare_series
from cases.studies.measured.fit import parse_observation
from cases.studies.measured.fit_series import Holdout, fit_series, parse_holdout, split_series
from cases.studies.measured.series import SERIES_DIR, read_series
from cases.studies.measured.validate import error_summary, validate
from fem_loads.resistance import concrete_cavity_expansion, concrete_strength_factor

SERIAL = Pool(workers=1, progress=False)
CONCRETE = SERIES_DIR / "forrestal1996_concrete.csv"
COARSE = [("numerics.mesh_size", 0.012)]  # a coarser mesh than the shipped 6 mm: the checks are of the plumbing
FIT_TRAINING = ["v405", "v446", "v545", "v651"]  # the four slowest shots


def run_apart(scene: str | Path, overrides) -> dict:
    """The summary of a scene with ``overrides``, run as ``penetrate run`` runs it."""
    return summarise(run_scene(load_scene(scene, overrides))).record()


# -- the concrete family


def test_concrete_strength_factor_is_frews_fit():
    # 82.6 * 51^-0.544, worked by hand: ln 51 = 3.93183, x 0.544 = 2.13891, exp(-2.13891) = 0.117785
    assert concrete_strength_factor(51e6) == pytest.approx(9.7290, abs=2e-4)
    assert concrete_strength_factor(13.5e6) == pytest.approx(20.05, abs=0.01)
    law = concrete_cavity_expansion(51e6, 2300.0)
    assert law.c0 == pytest.approx(concrete_strength_factor(51e6) * 51e6, rel=1e-15)
    assert law.c2 == 2300.0  # B = 1
    with pytest.raises(ValueError, match="compressive_strength"):
        concrete_strength_factor(-1.0)


def test_concrete_family_runs_as_its_cavity_expansion_form():
    scene = scene_path("forrestal1996_concrete")
    s = load_scene(scene).target.law.S  # filled in from f'c when the scene is read
    assert s == pytest.approx(concrete_strength_factor(51e6), rel=1e-15)
    family = run_apart(scene, COARSE)
    coefficients = {"A": s, "sigma_0": 51e6, "B": 1.0, "rho_0": 2300.0}
    plain = run_apart(scene, [*COARSE, ("target.law", coefficients)])
    assert family["end_reason"] == plain["end_reason"] == "stopped"
    assert family["depth"] == pytest.approx(plain["depth"], rel=1e-9)
    # a given S replaces Frew's
    given = load_scene(scene, [("target.law.S", 12.0)]).target.build()
    assert given.c0 == pytest.approx(12.0 * 51e6, rel=1e-15)


# -- validate


def test_validate_predicts_each_shot_as_a_run_of_its_own(tmp_path):
    """The shipped 1996 series (coarser mesh): every prediction is the shot's own run within 1e-6, and the
    summary is what the rows give."""
    series = read_series(CONCRETE)
    validation = validate(series, COARSE, RunStore(tmp_path / "store"), SERIAL, curve_points=0)
    assert [row["label"] for row in validation.rows] == series.labels
    for shot, row in zip(series.shots, validation.rows):
        apart = run_apart(shot.scene, [*COARSE, *shot.values.items()])
        assert row["predicted"] == pytest.approx(apart["depth"], rel=1e-6)
        assert row["error_percent"] == pytest.approx(100 * (apart["depth"] - row["measured"]) / row["measured"])
        assert row["end_reason"] == "stopped"
    errors = np.array([row["error_percent"] for row in validation.rows])
    summary = validation.summary["depth"]
    assert summary["shots"] == 10 and summary["failed"] == 0
    assert summary["mean_abs_error_percent"] == pytest.approx(np.mean(np.abs(errors)), rel=1e-12)
    assert summary["bias_percent"] == pytest.approx(np.mean(errors), rel=1e-12)
    assert summary["rms_percent"] == pytest.approx(math.sqrt(np.mean(errors**2)), rel=1e-12)
    assert summary["chi2"] is None  # the shipped series gives no sigmas


def test_validate_command_writes_its_outputs(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(
        ["validate", "forrestal1996_concrete", "--set", "numerics.mesh_size=0.012", "--store", str(tmp_path / "s")]
        + ["--out", str(out), "--curve-points", "4", "--no-progress", "--json", "--formulas"]
    )
    assert code == 0
    record = json.loads(capsys.readouterr().out)
    # --formulas: each shot's depth by every formula of its own scene (penetrate formulas), beside the model's
    from cases.studies.measured.formulas import formulas

    assert len(record["formulas"]) == 10 * 5 and record["formulas_refused"] == []  # Degen gives no depth
    first = read_series(CONCRETE).shots[0]
    own = formulas(load_scene(scene_path(first.scene), dict(first.values)))
    by_formula = [(r["formula"], r["predicted"]) for r in record["formulas"][:5]]
    assert by_formula == [(e.name, e.depth) for e in own.estimates if e.depth is not None]
    assert "| the model (DAFL run) | 10 |" in (out / "validate.md").read_text()
    assert set(record) >= {"shots", "summary", "groups"}
    assert set(record["shots"][0]) >= {"label", "group", "predicted", "measured", "error_percent", "end_reason"}
    assert set(record["summary"]["depth"]) >= {"mean_abs_error_percent", "bias_percent", "rms_percent", "shots"}
    assert record["groups"]["51 MPa"]["depth"]["shots"] == 10
    assert record["set"] == ["numerics.mesh_size=0.012"]
    curve = record["curves"]["51 MPa"]
    assert curve["impact_speed"] == pytest.approx(np.linspace(405.0, 1201.0, 4), rel=1e-6)
    assert all(a < b for a, b in zip(curve["depth"], curve["depth"][1:]))  # faster goes deeper
    assert any("projectile.mass" in note for note in curve["notes"])  # each shot's mass: the curve at their mean
    assert {p.name for p in out.iterdir()} == {"validate.md", "validate.csv", "validate.json", "validate.png"}
    assert "Set on every shot" in (out / "validate.md").read_text()


SCENE = """
name = "cone into clay"
[projectile]
diameter = 0.05
length = 0.3
nose = { shape = "cone", half_angle = 15.0 }
mass = 3.0
[target]
law = { model = "polynomial", c0 = 2e7, c1 = 2e3, c2 = 1500 }
[impact]
speed = 300.0
[numerics]
mesh_size = 0.01
integrator = "dopri54"
rtol = 1e-5
"""

OTHER_SERIES = """# a made-up series: another projectile, target and set of columns
label,scene,impact.attack_angle,target.law.c0,measured.path_length,sigma.path_length,measured.axis_angle_change,sigma.axis_angle_change
a,cone.toml,0,2e7,3.0,0.1,,
b,cone.toml,2,2e7,2.7,5%,3,1
c,cone.toml,2,3e7,2.2,5%,2,0.5
"""


def test_any_series_runs_unchanged(tmp_path):
    """A series with another projectile, target and columns than the shipped ones: each prediction is its shot's
    run, sigmas absolute and relative, chi-squared the sum of the squared residuals in sigmas."""
    (tmp_path / "cone.toml").write_text(SCENE)
    path = tmp_path / "made_up.csv"
    path.write_text(OTHER_SERIES)
    series = read_series(path)
    assert series.columns == ["impact.attack_angle", "target.law.c0"]
    assert series.quantities == ["path_length", "axis_angle_change"]
    assert series.shots[1].measured("path_length").sigma == pytest.approx(0.135)  # 5 % of 2.7
    assert series.shots[0].measured("axis_angle_change") is None
    validation = validate(series, None, RunStore(tmp_path / "store"), SERIAL)
    assert validation.curves == {}  # no impact.speed column: no curve
    for row in validation.rows:
        shot = next(s for s in series.shots if s.label == row["label"])
        apart = run_apart(shot.scene, shot.values.items())
        assert row["predicted"] == pytest.approx(apart[row["quantity"]], rel=1e-6, abs=1e-9)
        measured = shot.measured(row["quantity"])
        assert row["residual_sigmas"] == pytest.approx((row["predicted"] - measured.value) / measured.sigma)
    turns = [r for r in validation.rows if r["quantity"] == "axis_angle_change"]
    assert validation.summary["axis_angle_change"]["chi2"] == pytest.approx(
        sum(r["residual_sigmas"] ** 2 for r in turns)
    )
    assert validation.summary["path_length"]["shots"] == 3
    assert validation.groups == {"cone": validation.summary}  # the group defaults to the scene's name


# -- bad series


BAD = {
    "missing scene": ("scene,measured.depth\nnowhere.toml,1.0\n", "column 'scene': 'nowhere.toml': no such scene file"),
    "unknown column": ("scene,measurd.depth\nforrestal_luk_test2,1.0\n", "column 'measurd.depth': unknown column"),
    "unknown quantity": ("scene,measured.dept\nforrestal_luk_test2,1\n", "unknown quantity 'dept'"),
    "not a number": ("scene,measured.depth\nforrestal_luk_test2,deep\n", "column 'measured.depth': 'deep'"),
    "negative sigma": ("scene,measured.depth,sigma.depth\nforrestal_luk_test2,1,-0.1\n", "must be > 0"),
    "empty file": ("", "empty"),
    "header only": ("scene,measured.depth\n", "no shots"),
    "comments only": ("# nothing here\n", "empty"),
    "nothing measured": ("scene,measured.depth\nforrestal_luk_test2,\n", "nothing measured"),
    "bad scene key": ("scene,impact.speed,measured.depth\nforrestal_luk_test2,-5,1\n", "impact.speed"),
    "bad key value": ("scene,impact.sped,measured.depth\nforrestal_luk_test2,5,1\n", "impact.sped: unknown key"),
    "twice the label": ("label,scene,measured.depth\nx,forrestal_luk_test2,1\nx,forrestal_luk_test2,2\n", "also the"),
    "short row": ("scene,measured.depth\nforrestal_luk_test2\n", "1 cells for 2 columns"),
    "sigma alone": ("scene,sigma.depth\nforrestal_luk_test2,1\n", "no measured.depth column"),
    "no scene column": ("impact.speed,measured.depth\n300,1\n", "no 'scene' column"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_series_are_refused_in_one_line_before_any_run(tmp_path, capsys, case):
    text, expected = BAD[case]
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=expected.replace("(", r"\(").replace(")", r"\)")) as error:
        read_series(path)
    assert "\n" not in str(error.value)
    store, out = tmp_path / "store", tmp_path / "out"
    code = main(["validate", str(path), "--store", str(store), "--out", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "row" in err or "header" in err or "empty" in err or "line" in err
    assert not store.exists() and not out.exists()  # nothing run, nothing written


def test_a_bad_row_is_named_by_its_row_and_line(tmp_path):
    path = tmp_path / "s.csv"
    path.write_text(
        "# a comment\nscene,impact.speed,measured.depth\nforrestal_luk_test2,280,5\nforrestal_luk_test2,x y,5\n"
    )
    with pytest.raises(InputError, match=r"line 4 \(row 2\)|impact.speed"):
        read_series(path)


# -- compare --series


def test_compare_series_ranks_the_laws(tmp_path):
    series = read_series(CONCRETE).subset(["v405", "v651", "v1009"])
    laws = [
        ("scene", None),
        ("li_chen", {"A": 72 / math.sqrt(51), "sigma_0": 51e6, "B": 1.0, "rho_0": 2300.0}),
        ("weak", {"A": 5.0, "sigma_0": 51e6, "B": 1.0, "rho_0": 2300.0}),
    ]
    store = RunStore(tmp_path / "store")
    comparison = compare_series(series, COARSE, laws, store, tmp_path / "out", SERIAL)
    means = [entry["mean_abs_error_percent"] for entry in comparison.ranking]
    assert means == sorted(means) and [e["rank"] for e in comparison.ranking] == [1, 2, 3]
    assert comparison.ranking[-1]["law"] == "weak"  # half the strength: far too deep
    own = validate(series, COARSE, store, SERIAL, curve_points=0)
    scene_rows = [row for row in comparison.rows if row["law"] == "scene"]
    assert [r["predicted"] for r in scene_rows] == [r["predicted"] for r in own.rows]  # the same runs
    for entry in comparison.ranking:
        rows = [row for row in comparison.rows if row["law"] == entry["law"]]
        assert entry["mean_abs_error_percent"] == pytest.approx(error_summary(rows)["mean_abs_error_percent"])
    assert {p.name for p in (tmp_path / "out").iterdir()} == {
        "compare.md",
        "compare.csv",
        "compare.json",
        "compare.png",
    }


def test_compare_series_ranks_the_formulas_with_the_laws(tmp_path):
    """``with_formulas``: each formula of a depth enters the ranking (``kind`` "formula") with the error summary
    of its depths on the shots' own scenes, the same as validate --formulas gives, whatever law is compared."""
    series = read_series(CONCRETE).subset(["v405", "v1009"])
    store = RunStore(tmp_path / "store")
    laws = [("weak", {"A": 5.0, "sigma_0": 51e6, "B": 1.0, "rho_0": 2300.0})]
    comparison = compare_series(series, COARSE, laws, store, tmp_path / "out", SERIAL, with_formulas=True)
    kinds = {entry["law"]: entry["kind"] for entry in comparison.ranking}
    assert kinds["weak"] == "law" and len(kinds) == 1 + 5 and {"Li and Chen", "Young", "ACE"} <= set(kinds)
    means = [entry["mean_abs_error_percent"] for entry in comparison.ranking]
    assert means == sorted(means) and [e["rank"] for e in comparison.ranking] == list(range(1, 7))
    own = validate(series, COARSE, store, SERIAL, curve_points=0, with_formulas=True)
    for entry in (e for e in comparison.ranking if e["kind"] == "formula"):
        mine = [row for row in own.formulas if row["formula"] == entry["law"]]
        assert entry["mean_abs_error_percent"] == pytest.approx(error_summary(mine)["mean_abs_error_percent"])
    markdown = (tmp_path / "out" / "compare.md").read_text()
    assert markdown.startswith("# forrestal1996_concrete.csv: 2 shots under 1 resistance law and 5 empirical formulas")
    assert "| Li and Chen (formula) |" in markdown


def test_compare_formulas_on_a_scene_is_refused_in_one_line(tmp_path, capsys):
    """The formulas are ranked on a test series only; on one scene the command says where to go, writes nothing."""
    out = tmp_path / "o"
    code = main(
        ["compare", str(scene_path("forrestal1996_concrete")), "--laws", "scene", "--formulas"] + ["--out", str(out)]
    )
    assert code == 2 and not out.exists()
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "compare --formulas" in line and "--series" in line and "penetrate formulas" in line


def test_compare_series_refuses_a_series_that_sets_the_law(tmp_path):
    path = tmp_path / "s.csv"
    path.write_text("scene,target.law,measured.depth\nforrestal_luk_test2,softer_soil,5\n")
    with pytest.raises(InputError, match="sets target.law per shot"):
        compare_series(read_series(path), None, [("soil", "soil")], RunStore(tmp_path / "s"), tmp_path / "o", SERIAL)


def test_compare_header_counts_one_law(tmp_path, capsys):
    code = main(
        ["compare", str(scene_path("forrestal_luk_test2")), "--laws", "scene", "--set", "numerics.mesh_size=0.03"]
        + ["--store", str(tmp_path / "s"), "--out", str(tmp_path / "o"), "--no-progress"]
    )
    assert code == 0
    assert "under 1 resistance law\n" in capsys.readouterr().out


# -- fit --series


@pytest.mark.slow
def test_fit_on_the_slowest_shots_agrees_with_a_scan_and_reports_the_rest_apart(tmp_path):
    """S fitted to the four slowest shots lies within its standard error of the minimum of the sum of squared
    residuals, found by a scan of S (a parabola through the three lowest points of a 0.25-step grid); the
    other six are predictions, apart from the fit's residuals."""
    series = read_series(CONCRETE)
    store = RunStore(tmp_path / "store")
    held = [label for label in series.labels if label not in FIT_TRAINING]
    result = fit_series(series, COARSE, ["target.law.S=5:20"], store, SERIAL, holdout=Holdout("label", tuple(held)))
    assert result.converged
    s, error = result.parameters["target.law.S"], result.standard_errors["target.law.S"]
    assert error is not None and 0 < error < 1
    training = series.subset(FIT_TRAINING)
    grid = np.arange(9.0, 13.01, 0.25)
    sums = []
    for value in grid:
        rows = validate(training, [*COARSE, ("target.law.S", float(value))], store, SERIAL, curve_points=0).rows
        sums.append(sum((row["predicted"] - row["measured"]) ** 2 for row in rows))
    best = int(np.argmin(sums))
    assert 0 < best < len(grid) - 1  # the minimum inside the scanned range
    a, b, _ = np.polyfit(grid[best - 1 : best + 2], sums[best - 1 : best + 2], 2)
    scanned = -b / (2 * a)
    assert abs(s - scanned) < error, (s, scanned, error)
    assert [row["scene"] for row in result.observations] == FIT_TRAINING  # the fit saw only these
    assert result.predictions is not None and result.predictions["held_out"] == held
    assert [row["label"] for row in result.predictions["rows"]] == held
    before = [row["predicted"] for row in result.predictions["start_rows"]]
    after = [row["predicted"] for row in result.predictions["rows"]]
    assert all(b > a for a, b in zip(after, before))  # a stronger target (S > Frew's 9.73) stops them sooner


@pytest.mark.slow
def test_k_fold_cross_validation_predicts_every_training_shot_once(tmp_path):
    series = read_series(CONCRETE).subset(["v405", "v446", "v545", "v651", "v804", "v821"])
    result = fit_series(series, COARSE, ["target.law.S=5:20"], RunStore(tmp_path / "s"), SERIAL, folds=3, seed=1)
    cv = result.cross_validation
    assert cv is not None and len(cv["folds"]) == 3
    left_out = [label for fold in cv["folds"] for label in fold["left_out"]]
    assert sorted(left_out) == sorted(series.labels)
    assert sorted(row["label"] for row in cv["rows"]) == sorted(series.labels)
    assert cv["summary"]["depth"]["shots"] == 6


def test_holdouts_by_label_group_and_fraction():
    series = read_series(CONCRETE)
    assert split_series(series, parse_holdout("label=v405,v1201"))[1] == ["v405", "v1201"]
    assert (
        split_series(series, parse_holdout("fraction=0.3"), seed=3)[1]
        == split_series(series, parse_holdout("fraction=0.3"), seed=3)[1]
    )
    assert len(split_series(series, parse_holdout("fraction=0.3"))[1]) == 3
    with pytest.raises(InputError, match="every shot"):
        split_series(series, parse_holdout("group=51 MPa"))
    with pytest.raises(InputError, match="no shot has the label 'v999'"):
        split_series(series, parse_holdout("label=v999"))
    for text in ("fraction=1.5", "labels=x", "label="):
        with pytest.raises(InputError, match="--holdout"):
            parse_holdout(text)


def test_relative_sigma_of_an_observation():
    assert parse_observation("depth=0.370+-5%", "s.toml").sigma == pytest.approx(0.0185)
    assert parse_observation("depth=0.370+-0.02", "s.toml").sigma == pytest.approx(0.02)
    with pytest.raises(InputError, match="must be > 0"):
        parse_observation("depth=0.370+--5%", "s.toml")


def test_a_fit_that_does_not_converge_says_so_and_fails(tmp_path, capsys):
    code = main(
        ["fit", "--series", str(CONCRETE), "--param", "target.law.S=5:20", "--max-evaluations", "1"]
        + ["--set", "numerics.mesh_size=0.012", "--store", str(tmp_path / "s"), "--out", str(tmp_path / "o")]
        + ["--no-progress", "--json"]
    )
    captured = capsys.readouterr()
    assert code == 1
    assert json.loads(captured.out)["converged"] is False
    assert "not converged" in captured.err and captured.err.count("\n") == 1
    assert "NOT CONVERGED" in (tmp_path / "o" / "fit.md").read_text()


def test_fit_series_without_a_parameter_is_validate_and_says_so(tmp_path, capsys):
    code = main(
        ["fit", "--series", str(CONCRETE), "--set", "numerics.mesh_size=0.012", "--store", str(tmp_path / "s")]
        + ["--out", str(tmp_path / "o"), "--no-progress"]
    )
    captured = capsys.readouterr()
    assert code == 0
    assert "nothing is fitted" in captured.err and "validate" in captured.err
    assert "predicted against measured" in captured.out


def test_a_set_over_several_observations_is_named(tmp_path):
    from cases.studies.measured.fit import fit

    scene = str(scene_path("forrestal1996_concrete"))
    result = fit(
        scene,
        [*COARSE, ("impact.speed", 446.0)],
        ["target.law.S=5:20"],
        ["depth=0.370", f"{scene}:depth=0.420"],
        RunStore(tmp_path / "s"),
        SERIAL,
    )
    notes = " ".join(result.notes)
    assert "applies to every observation's scene" in notes
    assert "observations 1 and 2 are the same quantity of the same run" in notes
    assert [row["impact_speed"] for row in result.observations] == [446.0, 446.0]


def test_compare_flags_the_stress_of_a_state_a_run_never_reaches(tmp_path, capsys):
    """At 200 m/s the concrete rod stops short of one body length: the stress one length in is flagged."""
    code = main(
        ["compare", str(scene_path("forrestal1996_concrete")), "--laws", "scene", "--set", "impact.speed=200"]
        + ["--set", "numerics.mesh_size=0.012", "--store", str(tmp_path / "s"), "--out", str(tmp_path / "o")]
        + ["--no-progress"]
    )
    assert code == 0
    out = capsys.readouterr().out
    assert "a state these runs never reach: scene stopped at" in out and "short of one body length (0.305 m)" in out


@pytest.mark.slow
def test_validate_on_a_dask_cluster_gives_the_local_predictions(tmp_path):
    """Separate ``dask scheduler`` and ``dask worker`` processes (nothing shared with this one) and a LocalCluster
    predict the shots as local workers do."""
    distributed = pytest.importorskip("distributed")
    from support import dask_cluster

    series = read_series(CONCRETE).subset(["v405", "v1201"])
    local = validate(series, COARSE, RunStore(tmp_path / "local"), SERIAL, curve_points=0)
    with dask_cluster(tmp_path) as address:
        remote = validate(series, COARSE, RunStore(tmp_path / "cluster"), Pool(scheduler=address, progress=False), 0)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        pool = Pool(scheduler=cluster.scheduler_address, progress=False)
        in_process = validate(series, COARSE, RunStore(tmp_path / "localcluster"), pool, 0)
    for other in (remote, in_process):
        assert [r["predicted"] for r in other.rows] == pytest.approx([r["predicted"] for r in local.rows], rel=1e-12)
