"""Multi-fidelity ensembles: the stratified estimate is unbiased and its interval covers, whatever the sort gets
wrong (synthetic strata with known truth); the choice of full runs keeps the budget; the reduced model's sort
is its runs at the speed -/+ the margin; a scene or key the model cannot take is refused in one line."""

import json

import numpy as np
import pytest

from cases import scene_path
from cases.run import RunStore
from cases.scene import InputError, load_scene
from cases.studies import Pool
from cases.studies.ensemble.multifidelity import MARGIN, STRATA, check_applies, choose, sort_chunk, stratified
from cases.studies.ensemble.study import run_ensemble


def synthetic(rng, size=20_000, wrong=0.03):
    """Strata like #3's (60 % stable, 38 % unstable, 2 % near) whose sort calls a fraction ``wrong`` of the
    stable samples stable that are not."""
    codes = rng.choice(3, size=size, p=[0.60, 0.38, 0.02])
    truth = np.where(codes == 2, rng.random(size) < 0.5, codes == 1)
    flip = (codes == 0) & (rng.random(size) < wrong)
    return codes, truth ^ flip


def test_the_estimate_is_unbiased_and_its_interval_covers_even_when_the_sort_is_wrong():
    rng = np.random.default_rng(1)
    codes, truth = synthetic(rng)
    exact = truth.mean()
    estimates, covered = [], 0
    for seed in range(400):
        ran = np.zeros(len(codes), dtype=bool)
        ran[choose(codes, 300, seed)] = True
        found = stratified(codes, ran, truth)
        estimates.append(found["probability"])
        low, high = found["interval"]
        covered += low <= exact <= high
    # unbiased: the mean of 400 estimates within 3 standard errors of the exact proportion
    error = np.std(estimates) / np.sqrt(len(estimates))
    assert abs(np.mean(estimates) - exact) < 3 * error
    assert covered / 400 >= 0.95
    # the sort's labels alone would be off by its mistakes, 1.8 %: some 40 standard errors
    naive = np.where(codes == 2, 0.5, codes == 1).mean()
    assert exact - naive > 20 * error


def test_every_sample_run_gives_the_exact_proportion_and_only_the_samples_own_error():
    rng = np.random.default_rng(2)
    codes, truth = synthetic(rng, size=2000)
    found = stratified(codes, np.ones(len(codes), dtype=bool), truth)
    assert found["probability"] == pytest.approx(truth.mean(), abs=1e-12)
    low, high = found["interval"]
    assert low < truth.mean() < high and high - low < 0.06  # the Wilson interval of 2000 samples, about +-0.022
    assert found["strata"]["near"]["runs"] == found["strata"]["near"]["samples"]


def test_a_stratum_without_runs_spans_its_share():
    codes = np.array([0] * 90 + [2] * 10)
    ran = np.array([True] * 90 + [False] * 10)
    found = stratified(codes, ran, np.zeros(100, dtype=bool))
    assert found["probability"] == pytest.approx(0.05) and found["interval"][1] >= 0.1


def test_the_full_runs_keep_the_budget_and_the_seed():
    rng = np.random.default_rng(3)
    codes, _ = synthetic(rng)
    chosen = choose(codes, 1024, 0)
    assert len(chosen) == 1024 == len(set(chosen.tolist()))
    near = (codes[chosen] == 2).sum()
    assert near == 256  # a quarter to the near samples
    audit = [(codes[chosen] == h).sum() for h in (0, 1)]
    assert audit[0] / audit[1] == pytest.approx((codes == 0).sum() / (codes == 1).sum(), rel=0.02)
    assert np.array_equal(chosen, choose(codes, 1024, 0)) and not np.array_equal(chosen, choose(codes, 1024, 1))
    assert len(choose(codes, 10**6, 0)) == len(codes)  # a budget above the samples runs them all
    few = np.array([2] * 5 + [0] * 1000)
    assert (few[choose(few, 100, 0)] == 2).sum() == 5  # the near samples are fewer than their share: all run


@pytest.fixture(scope="module")
def coarse_p3():
    return load_scene(scene_path("paper_p3"), {"numerics.mesh_size": 0.04})


@pytest.mark.parametrize("stable_first", [False, True])
def test_the_sort_is_the_reduced_runs_at_the_speed_minus_and_plus_the_margin(coarse_p3, stable_first):
    from cases.run import prepare_projectile
    from cases.studies.reduced.pitch_plane import ReducedModel

    speeds = np.array([700.0, 905.0, 915.0, 1300.0, 1000.0])
    attacks = np.array([1.0, 1.0, 1.0, 0.05, 3.0])
    obliques = np.zeros(5)
    codes = sort_chunk(coarse_p3.model_dump_json(), speeds, attacks, obliques, np.full(5, stable_first))
    for speed, attack, code in zip(speeds, attacks, codes):
        scene = coarse_p3.model_copy(update={"impact": coarse_p3.impact.model_copy(update={"attack_angle": attack})})
        model = ReducedModel(scene, prepare_projectile(scene))
        low, high = (model.run(speed * f, turn_limit=30.0).unstable for f in (1 - MARGIN, 1 + MARGIN))
        assert STRATA[code] == ("unstable" if low else "near" if high else "stable")
    assert list(codes) == [0, 2, 2, 0, 1]


def test_the_pilot_guess_changes_the_runs_a_sample_costs_not_its_stratum(coarse_p3, monkeypatch):
    from cases.studies.ensemble import multifidelity
    from cases.studies.reduced.pitch_plane import ReducedModel

    rng = np.random.default_rng(5)
    values = {"impact.speed": rng.uniform(700.0, 1300.0, 400), "impact.attack_angle": rng.uniform(0.0, 3.0, 400)}
    runs = [0]
    unstable = ReducedModel.unstable

    def counted(self, speeds, starts):
        runs[0] += len(speeds)
        return unstable(self, speeds, starts)

    monkeypatch.setattr(ReducedModel, "unstable", counted)
    monkeypatch.setattr(multifidelity, "PILOT", 100)
    guessed = multifidelity.sort_samples(coarse_p3, values, 1)
    guessed_runs, runs[0] = runs[0], 0
    columns = (values["impact.speed"], values["impact.attack_angle"], np.zeros(400))
    lowered_first = sort_chunk(coarse_p3.model_dump_json(), *columns, np.zeros(400, dtype=bool))
    np.testing.assert_array_equal(guessed, lowered_first)
    assert set(guessed) == {0, 1, 2}  # all three strata, so that the guess had something to get wrong
    # the lowered speed first costs a second run for every sample not unstable; after the pilot (sorted that
    # way), the guess costs a second run only for the near samples and the few it gets wrong (here under 5 %)
    assert runs[0] == 400 + np.count_nonzero(lowered_first != 1)
    pilot, rest = lowered_first[:100], lowered_first[100:]
    assert guessed_runs <= 100 + np.count_nonzero(pilot != 1) + 300 + np.count_nonzero(rest == 2) + 15 < runs[0]


@pytest.mark.parametrize(
    "name, keys, message",
    [
        ("eroded_test2", ["impact.speed"], "--fidelity multi: the reduced model does not apply (projectile.geometry"),
        ("paper_p3", ["impact.speed", "projectile.mass"], "--fidelity multi: the reduced model sorts samples of"),
    ],
)
def test_a_scene_or_key_the_reduced_model_cannot_take_is_refused_in_one_line(name, keys, message):
    with pytest.raises(InputError) as error:
        check_applies(load_scene(scene_path(name)), keys)
    assert str(error.value).startswith(message) and "\n" not in str(error.value)
    assert str(error.value).endswith("use --fidelity full")


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_a_multi_fidelity_ensemble_says_how_many_full_runs_it_made(tmp_path):
    record = run_ensemble(
        scene_path("paper_p3"),
        {"numerics.mesh_size": 0.04},
        ["impact.speed=uniform:700:1300", "impact.attack_angle=halfnormal:1"],
        400,
        RunStore(tmp_path / "store"),
        tmp_path / "out",
        by="impact.speed=700:1300:200",
        pool=Pool(workers=2, progress=False),
        fidelity="multi",
        full_runs=40,
    )
    assert record["fidelity"] == "multi" and record["runs"] == 400 and record["full_runs"] == 40
    assert sum(record["strata"].values()) == 400
    low, high = record["interval"]["unstable"]
    assert low <= record["probability"]["unstable"] <= high
    written = json.loads((tmp_path / "out" / "ensemble.json").read_text())
    assert written["full_runs"] == 40 and len(written["curve"]) == 3
    assert "40 full runs" in (tmp_path / "out" / "ensemble.md").read_text().splitlines()[0]
    table = (tmp_path / "out" / "ensemble.csv").read_text().splitlines()
    assert len(table) == 401 and table[0].startswith("sample,impact.speed,impact.attack_angle,stratum,full_run")
