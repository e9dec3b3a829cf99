"""The guided critical-speed search on fake runs whose critical speed is known exactly: the reduced model's
bracket is confirmed by two runs when it holds the change, and moved out step by step when it does not; where
the reduced model does not apply, the search runs unguided and says why."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_critical_search import RANGE, FakeRuns, assert_confirmed

from cases import scene_path
from cases.scene import InputError
from cases.studies import Pool, Sweep, find_critical_velocity
from cases.studies.speeds import characteristic as speeds_module
from cases.studies.speeds.guide import Guide, critical_guide, grid_bracket

POOL = Pool(workers=2, progress=False)


@pytest.fixture(scope="module")
def base():
    return Sweep.from_file(scene_path("paper_p3"))


def guided(monkeypatch, base, critical: float, predicted: float | None, resolution: float = 5.0, workers: int = 2):
    """A search whose guide predicts ``predicted`` (None: the reduced model found the range stable throughout)."""

    def guide(scene, limits, resolution, guide="auto"):
        centre = limits[1] if predicted is None else predicted
        return Guide("reduced", "fake", predicted), grid_bracket(centre, limits, resolution)

    fake = FakeRuns(lambda scene: critical)
    monkeypatch.setattr(speeds_module, "run_sweep", fake)
    monkeypatch.setattr(speeds_module, "critical_guide", guide)
    result = find_critical_velocity(base, None, RANGE, resolution, Pool(workers=workers, progress=False))
    return result, fake


def test_a_bracket_on_the_grid_one_resolution_wide_around_the_prediction():
    assert grid_bracket(910.4, RANGE, 5.0) == (907.5, 912.5)
    assert grid_bracket(909.0, RANGE, 5.0) == (907.5, 912.5)
    assert grid_bracket(911.5, RANGE, 5.0) == (910.0, 915.0)
    assert grid_bracket(1600.0, RANGE, 5.0) == (1595.0, 1600.0)  # at the range's ends, inside it
    assert grid_bracket(100.0, RANGE, 5.0) == (200.0, 205.0)
    assert grid_bracket(250.0, (240.0, 243.0), 5.0) == (240.0, 243.0)  # a range narrower than the resolution


def test_a_right_prediction_takes_two_runs_in_one_round(monkeypatch, base):
    result, fake = guided(monkeypatch, base, 909.3, 910.4)
    assert_confirmed(result, 909.3)
    assert (result.rounds, len(result.indicator)) == (1, 2) and fake.rounds == [[907.5, 912.5]]
    assert result.guide.guided and result.as_dict()["guide"] == "reduced"


@pytest.mark.parametrize("error", [-10.0, -7.0, -3.0, 3.0, 7.0, 10.0])
def test_a_prediction_within_two_resolutions_takes_at_most_four_runs(monkeypatch, base, error):
    result, fake = guided(monkeypatch, base, 909.3, 909.3 + error)
    assert_confirmed(result, 909.3)
    assert len(result.indicator) <= 4 and result.rounds <= 2


@pytest.mark.parametrize("critical", [205.0, 640.0, 1333.3, 1598.0])
def test_a_wrong_prediction_is_moved_out_to_the_change(monkeypatch, base, critical):
    """The end a run contradicts moves by the resolution, then twice as far each time: a prediction 700 m/s off
    costs about as many rounds as the unguided search (six to eight), not a failure."""
    result, _ = guided(monkeypatch, base, critical, 909.3)
    assert_confirmed(result, critical)
    assert result.rounds <= 2 * math.ceil(math.log2(abs(critical - 909.3) / 5.0)) + 2


@pytest.mark.parametrize(
    "critical, predicted, message",
    [
        (1700.0, None, "every run is stable, up to 1600 m/s"),
        (1700.0, 1500.0, "every run is stable, up to 1600 m/s"),
        (150.0, 400.0, "every run is unstable, down to 200 m/s"),
    ],
)
def test_no_change_in_the_range_is_found_as_unguided(monkeypatch, base, critical, predicted, message):
    result, fake = guided(monkeypatch, base, critical, predicted)
    assert result.critical_velocity is None and result.message == message
    if predicted is None:  # the reduced model said so: two runs at the top confirm it
        assert fake.rounds == [[1595.0, 1600.0]]


@settings(max_examples=300, deadline=None)
@given(
    critical=st.floats(201, 1599),
    predicted=st.one_of(st.none(), st.floats(200, 1600)),
    workers=st.integers(1, 4),
    resolution=st.sampled_from([1.0, 5.0, 20.0]),
)
def test_any_prediction_ends_in_a_confirmed_bracket(base, critical, predicted, workers, resolution):
    with pytest.MonkeyPatch.context() as monkeypatch:
        result, fake = guided(monkeypatch, base, critical, predicted, resolution, workers)
    assert_confirmed(result, critical, resolution)
    assert all(len(speeds) <= workers for speeds in fake.rounds)
    assert len({run.speed for run in result.indicator}) == fake.runs  # no speed is run twice


def test_the_reduced_model_guides_p3_and_a_file_projectile_falls_back_saying_why():
    guide, bracket = critical_guide(Sweep.from_file(scene_path("paper_p3")).scenes[0], RANGE, 5.0)
    # docs/theory.md: the reduced model puts #3's critical speed within 0.3 % of the measured 910 m/s
    assert guide.guided and guide.predicted == pytest.approx(910.0, rel=3e-3)
    assert bracket[1] - bracket[0] == 5.0 and bracket[0] < guide.predicted < bracket[1]
    eroded = Sweep.from_file(scene_path("eroded_test2")).scenes[0]
    guide, bracket = critical_guide(eroded, RANGE, 5.0)
    assert bracket is None and not guide.guided
    assert guide.text.startswith("unguided: the reduced model does not apply (projectile.geometry: ")
    with pytest.raises(InputError, match=r"^--guide reduced: the reduced model does not apply here \(projectile"):
        critical_guide(eroded, RANGE, 5.0, "reduced")
    assert critical_guide(eroded, RANGE, 5.0, "none")[0].text == "unguided (--guide none)"


def test_the_command_says_which_guide_it_used_and_refuses_reduced_where_it_does_not_apply(capsys, tmp_path):
    from cases.cli import main

    eroded = str(scene_path("eroded_test2"))
    common = ["--store", str(tmp_path), "--workers", "2", "--no-progress"]
    assert main(["critical", eroded, "--guide", "reduced", *common]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("penetrate: error: --guide reduced: the reduced model does not apply here (projectile")
    assert "\n" not in error
    assert main(["convergent", eroded, "--guide", "reduced", *common]) == 2
    assert capsys.readouterr().err.startswith("penetrate: error: --guide reduced: the reduced model does not apply")


def test_a_multi_fidelity_ensemble_of_a_file_projectile_is_refused_in_one_line(capsys, tmp_path):
    from cases.cli import main

    args = ["ensemble", str(scene_path("eroded_test2")), "--sample", "impact.speed=uniform:250:300", "-n", "4"]
    common = ["--store", str(tmp_path / "store"), "--out", str(tmp_path / "out"), "--no-progress"]
    assert main([*args, "--fidelity", "multi", *common]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("penetrate: error: --fidelity multi: the reduced model does not apply (projectile.geometry")
    assert error.endswith("use --fidelity full") and "\n" not in error
    assert not (tmp_path / "out").exists() and not (tmp_path / "store").exists()
