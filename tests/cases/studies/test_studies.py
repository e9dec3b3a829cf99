"""Characteristic speeds: definitions on exact data, and on real runs of projectile #3."""

import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from cases import scene_path
from cases.run import RunStore, convergence_speed
from cases.studies import Pool, Sweep, find_critical_velocity, is_unstable, measure_convergent_velocity

STUDY = {"numerics.mesh_size": 0.02, "numerics.integrator": "rk4", "numerics.time_step": 2e-5}
QUIET, SERIAL = Pool(workers=2, progress=False), Pool(workers=1, progress=False)


def test_convergence_speed_on_an_exact_history():
    """Attack angle rises to 10 deg at 800 m/s, then falls linearly to 0 at 300 m/s."""
    speed = np.linspace(1000.0, 0.0, 1001)
    angle = np.where(speed > 800, 1 + 9 * (1000 - speed) / 200, np.clip(10 * (speed - 300) / 500, 0, None))
    history = pd.DataFrame({"speed": speed, "total_attack_angle": angle})
    for threshold in (0.1, 1.0, 5.0):
        assert convergence_speed(history, threshold) == pytest.approx(300 + 50 * threshold, abs=1e-9)
    assert convergence_speed(history.assign(total_attack_angle=angle + 1.0), 0.1) is None


def test_unstable_means_an_axis_turn_of_at_least_the_threshold_either_way():
    """The one definition (``UNSTABLE_TURN``, 30 degrees, docs/studies.md): at the threshold a run is unstable, a
    hair below it stable, whichever way the axis turned."""
    from cases.studies.speeds.instability import UNSTABLE_TURN

    assert UNSTABLE_TURN == 30.0
    for sign in (1.0, -1.0):
        assert is_unstable(sign * UNSTABLE_TURN) and is_unstable(sign * 52.0)
        assert not is_unstable(sign * np.nextafter(UNSTABLE_TURN, 0.0)) and not is_unstable(sign * 13.0)


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    return RunStore(tmp_path_factory.mktemp("studies"))


def test_critical_velocity_brackets_the_jump(store):
    sweep = Sweep.from_file(scene_path("paper_p3"), STUDY)
    search = find_critical_velocity(sweep, store, [800, 1000], resolution=50.0, pool=QUIET)
    low, high = search.bracket
    assert 800 < low < high < 1000 and high - low <= 50
    by_speed = {run.speed: run for run in search.indicator}
    # the two ends of the final bracket were run and sit on either side of the jump
    assert not is_unstable(by_speed[low].axis_angle_change)
    assert is_unstable(by_speed[high].axis_angle_change)
    # one round of two runs splits 200 m/s into three parts on the grid of 25 m/s: 875 and 925 m/s
    record = search.as_dict()
    assert [run["speed"] for run in record["indicator"]] == [875, 925] and record["rounds"] == 1
    assert search.critical_velocity == pytest.approx(0.5 * (low + high))


def test_convergent_velocity_barely_moves_with_the_threshold(store):
    """In an unstable run the attack angle collapses: 0.05 to 1 degree moves the speed by < 2 %."""
    sweep = Sweep.from_file(scene_path("paper_p3"), {**STUDY, "impact.speed": 1000})
    values = [
        measure_convergent_velocity(sweep, store, threshold, pool=SERIAL).characteristic_convergent_velocity
        for threshold in (0.05, 0.1, 0.5, 1.0)
    ]
    assert all(v is not None for v in values)
    assert (max(values) - min(values)) / min(values) < 0.02


def test_convergent_raises_a_stable_scene_and_says_so(store):
    sweep = Sweep.from_file(scene_path("paper_p3"), {**STUDY, "impact.speed": 800})
    result = measure_convergent_velocity(sweep, store, 0.1, raise_factor=1.25, pool=SERIAL)
    assert not result.runs[0].unstable and result.runs[-1].unstable
    assert "raised the impact speed" in result.message
    assert result.characteristic_convergent_velocity < result.runs[-1].speed


def test_cli_convergent_json(store):
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "cases.cli",
            "convergent",
            str(scene_path("paper_p3")),
            "--set",
            "numerics.mesh_size=0.02",
            "--set",
            "numerics.time_step=2e-5",
            "--set",
            "impact.speed=1000",
            "--store",
            str(store.root),
            "--json",
            "--no-progress",
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    record = json.loads(done.stdout)
    assert record["characteristic_convergent_velocity"] > 0 and record["runs"][0]["unstable"]


# what a study that finds nothing says to change: the option that would find something


class FakeConvergentRuns:
    """Stands in for ``run_sweep`` in ``measure_convergent_velocity``: runs from ``unstable_from`` m/s up turn
    by 60 degrees; each run's attack angle peaks at 5 degrees and falls to ``least`` at rest."""

    def __init__(self, unstable_from: float, least: float = 0.0):
        self.unstable_from, self.least = unstable_from, least

    def __call__(self, sweep, store, pool=None):
        from types import SimpleNamespace

        from cases.studies.engine.sweep import SweepResult

        runs, histories = [], []
        for scene in sweep.scenes:
            speed = scene.impact.speed
            turn = 60.0 if speed >= self.unstable_from else 2.0
            summary = SimpleNamespace(max_attack_angle=5.0, axis_angle_change=turn, end_reason="stopped")
            runs.append(SimpleNamespace(failed=False, error=None, summary=summary, key=str(speed)))
            speeds = np.linspace(speed, 0.0, 201)
            angle = np.interp(speeds, [0.0, 0.5 * speed, 0.9 * speed, speed], [self.least, self.least + 1.0, 5.0, 1.0])
            histories.append(pd.DataFrame({"speed": speeds, "total_attack_angle": angle}))
        result = SweepResult(sweep, runs, store)
        result.history = histories.__getitem__  # type: ignore[method-assign]
        return result


@pytest.mark.parametrize(
    "scene, attack, fix",
    [
        ("forrestal_luk_test2", 0.0, "give the scene a disturbance (--set impact.attack_angle=1)"),
        ("paper_p3", 1.0, "a larger disturbance may turn it (--set impact.attack_angle=2)"),
        ("paper_p3", 3.0, "a larger disturbance may turn it (--set impact.attack_angle=6)"),
        # the smallest float: twice it is still no disturbance, and 10 ** its exponent underflows
        ("paper_p3", -5e-324, "a larger disturbance may turn it (--set impact.attack_angle=-1)"),
        ("paper_p3", 0.2, "a larger disturbance may turn it (--set impact.attack_angle=1)"),
    ],
)
def test_convergent_without_an_unstable_run_names_the_option_to_change(monkeypatch, scene, attack, fix):
    from cases.studies.speeds import characteristic as speeds_module

    monkeypatch.setattr(speeds_module, "run_sweep", FakeConvergentRuns(unstable_from=np.inf))
    sweep = Sweep.from_file(scene_path(scene), {"impact.attack_angle": attack})
    result = measure_convergent_velocity(sweep, None, 0.1, pool=SERIAL)
    assert result.characteristic_convergent_velocity is None and not any(run.unstable for run in result.runs)
    assert result.message == f"no unstable run up to 4000 m/s: {fix}"


@pytest.mark.parametrize("least", [0.34, 2.0, 0.1])
def test_convergent_that_never_falls_below_the_threshold_suggests_one_that_does(monkeypatch, least):
    from cases.studies.speeds import characteristic as speeds_module

    monkeypatch.setattr(speeds_module, "run_sweep", FakeConvergentRuns(unstable_from=0.0, least=least))
    sweep = Sweep.from_file(scene_path("paper_p3"))
    result = measure_convergent_velocity(sweep, None, 0.1, pool=SERIAL)
    assert result.characteristic_convergent_velocity is None
    suggested = float(result.message.rsplit("--threshold ", 1)[1])
    assert result.message.startswith(
        f"the attack angle never fell below 0.1 deg (its least after the peak: {least:.3g}"
    )
    assert least < suggested <= 1.2 * least  # just above the least angle, as a person would type it
    found = measure_convergent_velocity(sweep, None, suggested, pool=SERIAL)
    assert found.characteristic_convergent_velocity is not None and found.message == ""


def test_predict_names_the_option_that_finds_each_missing_speed():
    from cases import load_scene
    from cases.studies import predict

    coarse = {"numerics.mesh_size": 0.04}
    straight = predict(load_scene(scene_path("forrestal_luk_test2"), coarse))
    assert straight.messages == [
        "no unstable reduced run up to 4000 m/s: no characteristic convergent velocity;"
        " give the scene a disturbance (--set impact.attack_angle=1)",
        "no unstable reduced run up to 1600 m/s: no critical impact velocity in the range;"
        " widen the range with --speeds 200:2400, or give the scene a disturbance (--set impact.attack_angle=1)",
    ]
    p3 = load_scene(scene_path("paper_p3"), coarse)  # critical near 910 m/s
    assert predict(p3, (200, 600)).messages[-1].endswith("; widen the range with --speeds 200:900")
    assert predict(p3, (1000, 1600)).messages[-1].endswith("; lower the range with --speeds 500:1600")
