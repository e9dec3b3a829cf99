"""The critical-speed search on fake runs whose critical speed is known exactly: where it ends, how many runs
and rounds it takes, and what it does when a guess or the range does not hold the change."""

import json
import math
import sys
from types import SimpleNamespace

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from cases import scene_path
from cases.scene import InputError
from cases.studies import Pool, Sweep, find_critical_velocities, find_critical_velocity, is_unstable
from cases.studies.speeds import characteristic as speeds_module

RANGE = (200, 1600)  # the default range of `penetrate critical`


def turn(speed: float, critical: float) -> float:
    """An axis turn like the real one: rising slowly to about 12 degrees below the critical speed, 50-180 above."""
    if speed < critical:
        return 2.0 + 10.0 * (speed / critical) ** 8
    return min(50.0 + 0.2 * (speed - critical), 180.0)


def gradual_turn(speed: float, critical: float) -> float:
    """Like projectile #1's: 11 degrees just below the jump, 20 just above it, 30 about 7 m/s and 45 about
    50 m/s higher (docs/paper: 1570, 1575, 1580, 1600, 1620 m/s turn by 11, 20, 30, 41, 45 degrees)."""
    if speed < critical:
        return 2.0 + 9.0 * (speed / critical) ** 8
    return 20.0 + 28.0 * (1.0 - math.exp(-(speed - critical) / 18.0))


def reaches_30(jump: float) -> float:
    """Where :func:`gradual_turn` reaches 30 degrees."""
    return jump + 18.0 * math.log(28.0 / 18.0)


class FakeRuns:
    """Stands in for ``run_sweep``: the critical speed of a scene is ``critical(scene)``; records every round."""

    def __init__(self, critical, turn=turn):
        self.critical = critical
        self.turn = turn
        self.rounds: list[list[float]] = []

    def __call__(self, sweep, store, pool=None):
        self.rounds.append([scene.impact.speed for scene in sweep.scenes])
        runs = []
        for scene in sweep.scenes:
            summary = SimpleNamespace(
                max_attack_angle=1.0,
                end_reason="stopped",
                axis_angle_change=-self.turn(scene.impact.speed, self.critical(scene)),
            )
            runs.append(
                SimpleNamespace(
                    failed=False,
                    error=None,
                    summary=summary,
                    key=f"{scene.projectile.centre_of_mass_ratio}@{scene.impact.speed}",
                )
            )
        from cases.studies.engine.sweep import SweepResult

        return SweepResult(sweep, runs, store)

    @property
    def runs(self) -> int:
        return sum(len(r) for r in self.rounds)


@pytest.fixture(scope="module")
def base():
    return Sweep.from_file(scene_path("paper_p3"))


def search(
    monkeypatch, base, critical: float, workers: int = 2, guess=None, speeds=RANGE, resolution=5.0, guide="none"
):
    fake = FakeRuns(lambda scene: critical)
    monkeypatch.setattr(speeds_module, "run_sweep", fake)
    pool = Pool(workers=workers, progress=False)
    result = find_critical_velocity(base, None, speeds, resolution, pool, guess, guide)
    return result, fake


def assert_confirmed(result, critical: float, resolution: float = 5.0):
    """The bracket holds the critical speed, is no wider than the resolution, and runs at both ends confirm it."""
    low, high = result.bracket
    assert low < critical <= high and high - low <= resolution * (1 + 1e-9)
    by_speed = {run.speed: run for run in result.indicator}
    assert not is_unstable(by_speed[low].axis_angle_change) and is_unstable(by_speed[high].axis_angle_change)
    assert result.critical_velocity == 0.5 * (low + high)


@pytest.mark.parametrize("critical", [907.3, 201.0, 640.0, 1333.3, 1599.0])
def test_two_workers_find_the_critical_speed_in_at_most_six_rounds_of_two_runs(monkeypatch, base, critical):
    """1400 m/s to 5 m/s: three parts a round, 3^6 = 729 >= 280 (bisection from the scan needed 15 + 5 runs)."""
    result, fake = search(monkeypatch, base, critical)
    assert_confirmed(result, critical)
    near_an_end = critical < 210 or critical > 1590  # the final bracket touches an assumed end: one more round
    # four rounds leave at least 1400 / 3^4 = 17 m/s; the grid of 2.5 m/s sometimes saves the sixth
    assert 5 <= result.rounds == len(fake.rounds) <= (7 if near_an_end else 6)
    assert all(len(speeds) <= 2 for speeds in fake.rounds)
    assert fake.runs == len(result.indicator) <= 2 * result.rounds
    assert result.as_dict()["runs"] == fake.runs and result.as_dict()["rounds"] == result.rounds


def test_more_workers_take_fewer_rounds(monkeypatch, base):
    rounds = {}
    for workers in (1, 2, 3, 4):
        result, fake = search(monkeypatch, base, 907.3, workers=workers)
        assert_confirmed(result, 907.3)
        assert all(len(speeds) <= workers for speeds in fake.rounds)
        rounds[workers] = result.rounds
    # at most ceil(log_(w+1)(1400 / 5)) = 9, 6, 5, 5 rounds; the grid of 2.5 m/s saves one here
    assert rounds == {1: 8, 2: 5, 3: 4, 4: 4}


def test_a_good_guess_saves_rounds(monkeypatch, base):
    result, _ = search(monkeypatch, base, 907.3, guess=(880, 940))
    assert_confirmed(result, 907.3)
    assert result.rounds == 3  # 60 m/s: 20, 7.5 (grid of 2.5), 2.5


@pytest.mark.parametrize("guess", [(1000, 1100), (300, 600), (905, 907)])
def test_a_guess_without_the_change_is_widened(monkeypatch, base, guess):
    result, _ = search(monkeypatch, base, 907.3, guess=guess)
    assert_confirmed(result, 907.3)
    ran = {run.speed for run in result.indicator}
    assert ran & set(guess), "the guess's end next to the change was run to confirm it, and it failed"


@pytest.mark.parametrize("jump", [1572.3, 1347.1, 907.3, 230.0])
def test_a_gradual_change_is_bracketed_where_the_turn_reaches_30_degrees(monkeypatch, base, jump):
    """Stable and unstable are 30 degrees of turn apart, like everywhere else: where the turn jumps from 11 to
    20 degrees and only reaches 30 degrees 8 m/s higher (projectile #1), the bracket holds the 30 degrees."""
    fake = FakeRuns(lambda scene: jump, gradual_turn)
    monkeypatch.setattr(speeds_module, "run_sweep", fake)
    result = find_critical_velocity(base, None, RANGE, 5.0, Pool(workers=2, progress=False), guide="none")
    assert_confirmed(result, reaches_30(jump))
    assert result.critical_velocity - jump == pytest.approx(8, abs=2.5)


@pytest.mark.parametrize(
    "critical, message",
    [(1700.0, "every run is stable, up to 1600 m/s"), (150.0, "every run is unstable, down to 200 m/s")],
)
def test_no_change_in_the_range(monkeypatch, base, critical, message):
    result, fake = search(monkeypatch, base, critical)
    assert result.critical_velocity is None and result.bracket is None
    assert result.message == message
    end = RANGE[1] if critical > RANGE[1] else RANGE[0]
    assert end in {run.speed for run in result.indicator}  # the range's end was run: no change is a finding
    assert result.rounds <= 7 and fake.runs <= 13  # up to six rounds to the end of the range, one to run the end


def test_a_family_shares_the_workers_round_by_round(monkeypatch, base):
    """Nine searches in lockstep on two workers: ten runs a round (five rounds of the workers), every search
    bisecting and one trisecting; each ends within the resolution of its own critical speed."""
    ratios = [0.4448, 0.4745, 0.5042, 0.5339, 0.5636, 0.5933, 0.6230, 0.56, 0.57]
    critical = dict(zip(ratios, [1572.3, 1347.1, 1172.8, 1027.6, 907.3, 811.9, 732.2, 827.7, 1007.4]))
    fake = FakeRuns(lambda scene: critical[scene.projectile.centre_of_mass_ratio])
    monkeypatch.setattr(speeds_module, "run_sweep", fake)
    bases = [Sweep.from_file(scene_path("paper_p3"), {"projectile.centre_of_mass_ratio": r}) for r in ratios]
    results = find_critical_velocities(
        bases, None, list(range(400, 2001, 100)), 5.0, Pool(workers=2, progress=False), guide="none"
    )
    for r, result in zip(ratios, results):
        assert_confirmed(result, critical[r])
    open_searches = [sum(result.rounds > n for result in results) for n in range(len(fake.rounds))]
    assert all(len(speeds) <= 2 * math.ceil(n / 2) for speeds, n in zip(fake.rounds, open_searches))
    assert [len(speeds) for speeds in fake.rounds[:8]] == [10] * 8  # no worker idles while all nine are open
    # 81 runs in 9 rounds, 41 turns of the two workers (the old scan of 17 speeds alone: 153 runs, 77 turns)
    assert sum(math.ceil(len(speeds) / 2) for speeds in fake.rounds) <= 41 and len(fake.rounds) <= 9


def test_bad_ranges_and_guesses_are_refused_before_anything_runs(monkeypatch, base):
    fake = FakeRuns(lambda scene: 900.0)
    monkeypatch.setattr(speeds_module, "run_sweep", fake)
    for speeds, guess in [
        ((900, 900), None),
        ((0, 1600), None),
        (RANGE, (100, 300)),
        (RANGE, (900, 900)),
        ((200, 1e9), None),
    ]:
        with pytest.raises(InputError):
            find_critical_velocity(base, None, speeds, 5.0, Pool(workers=2, progress=False), guess)
    assert fake.rounds == []


@settings(max_examples=400, deadline=None)
@given(
    critical=st.floats(201, 1599),
    workers=st.integers(1, 5),
    resolution=st.sampled_from([1.0, 5.0, 20.0]),
    guess=st.one_of(
        st.none(),
        st.tuples(st.floats(200, 1600), st.floats(1, 800))
        .map(lambda g: (g[0], min(g[0] + g[1], 1600.0)))
        .filter(lambda g: g[1] > g[0]),
    ),
    shape=st.sampled_from([turn, gradual_turn]),
)
def test_any_critical_speed_workers_resolution_and_guess(base, critical, workers, resolution, guess, shape):
    """Whatever the guess, the bracket is confirmed and narrow; without a guess it takes no more rounds
    than splitting the range into workers + 1 parts a round needs, plus one (the grid) and one (an end)."""
    assume(shape is turn or reaches_30(critical) < RANGE[1])
    fake = FakeRuns(lambda scene: critical, shape)
    original = speeds_module.run_sweep
    speeds_module.run_sweep = fake
    try:
        pool = Pool(workers=workers, progress=False)
        result = find_critical_velocity(base, None, RANGE, resolution, pool, guess, guide="none")
    finally:
        speeds_module.run_sweep = original
    assert_confirmed(result, critical if shape is turn else reaches_30(critical), resolution)
    assert all(len(speeds) <= workers for speeds in fake.rounds)
    if guess is None:
        assert result.rounds <= math.ceil(math.log(1400 / resolution) / math.log(workers + 1)) + 2


def test_the_command_passes_range_and_guess_and_says_runs_and_rounds(monkeypatch, capsys, tmp_path):
    from cases.cli import main

    fake = FakeRuns(lambda scene: 907.3)
    monkeypatch.setattr(speeds_module, "run_sweep", fake)
    scene = str(scene_path("paper_p3"))
    common = ["--store", str(tmp_path / "store"), "--workers", "2", "--no-progress", "--guide", "none"]
    assert main(["critical", scene, "--guess", "880:940", "--json", *common]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["bracket"] == [905.0, 907.5] and (record["runs"], record["rounds"]) == (5, 3)
    assert min(fake.rounds[0]) > 880 and max(fake.rounds[0]) < 940  # the guess's parts, not the range's
    assert main(["critical", scene, "--speeds", "1000:1600", *common]) == 1  # 907 m/s is below the range
    assert capsys.readouterr().out.splitlines()[-1].startswith("every run is unstable, down to 1000 m/s (")
    assert main(["critical", scene, "--speeds", "800:1000", *common]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == (
        "critical impact velocity 907.5 m/s (between 905 and 910 m/s; 7 full runs in 4 rounds)"
    )
    assert min(fake.rounds[-4]) > 800 and max(fake.rounds[-4]) < 1000


@pytest.mark.parametrize("command", ["critical", "map", "ballistic-limit", "predict"])
@pytest.mark.parametrize("given", ["800,900,1000", "800:1000:100", "800"])
def test_a_list_or_a_grid_where_a_range_is_meant_is_refused_in_one_line(command, given, capsys):
    """``--speeds 800,900,1000`` used to search 800-1000 silently: every command that takes a range refuses
    anything but ``LOW:HIGH``, in one line naming that form, before anything runs."""
    from cases.cli import main

    with pytest.raises(SystemExit) as exit_:
        main([command, str(scene_path("forrestal_luk_test2")), "--speeds", given])
    assert exit_.value.code == 2
    errors = [line for line in capsys.readouterr().err.splitlines() if "error:" in line]
    assert len(errors) == 1 and "--speeds" in errors[0] and "LOW:HIGH" in errors[0], errors


@pytest.mark.parametrize(
    "critical, attack, fix",
    [
        # #3 at 1 degree: the range is too narrow; the scene has its disturbance
        (1700.0, 1.0, "widen the range with --speeds 200:2400"),
        # a straight impact never turns: a wider range alone would not help
        (
            1700.0,
            0.0,
            "widen the range with --speeds 200:2400, or give the scene a disturbance (--set impact.attack_angle=1)",
        ),
        (150.0, 1.0, "lower the range with --speeds 100:1600"),
        (150.0, 0.0, "lower the range with --speeds 100:1600"),
    ],
)
def test_no_change_in_the_range_names_the_option_that_finds_one(monkeypatch, critical, attack, fix):
    base = Sweep.from_file(scene_path("paper_p3"), {"impact.attack_angle": attack})
    result, _ = search(monkeypatch, base, critical)
    assert result.critical_velocity is None and result.fix == fix
    assert result.as_dict()["fix"] == fix


def test_a_range_at_the_schemas_top_suggests_a_larger_disturbance(monkeypatch, base):
    """Nothing above 10 000 m/s is a scene: the search cannot widen, so the disturbance is what can change."""
    result, _ = search(monkeypatch, base, 20000.0, speeds=(9000, 10000))
    assert result.fix == "a larger disturbance may turn it (--set impact.attack_angle=2)"


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_the_command_ends_a_stable_range_with_the_options_to_change(monkeypatch, capsys, tmp_path):
    """The acceptance case: #3 without its disturbance (every run stable) ends with the options to change."""
    from cases.cli import main

    monkeypatch.setattr(
        speeds_module, "run_sweep", FakeRuns(lambda scene: math.inf if not scene.impact.attack_angle else 907.3)
    )
    args = ["critical", str(scene_path("paper_p3")), "--set", "impact.attack_angle=0", "--store", str(tmp_path)]
    assert main([*args, "--workers", "2"]) == 1
    last = capsys.readouterr().out.splitlines()[-1]
    assert last.startswith("every run is stable, up to 1600 m/s (")
    assert last.endswith(
        "round): widen the range with --speeds 200:2400, or give the scene a disturbance (--set impact.attack_angle=1)"
    )


# -- one progress bar per search, on fake runs made through the real pool and run store


def fake_job(critical: float):
    """A worker's job (cases.studies.engine.pool.run_job) whose run turns like :func:`turn` at its impact speed."""
    from cases.run import RunSummary, code_version

    fields = dict.fromkeys(RunSummary.model_fields, 0.0)
    fields.update(scene="fake", end_reason="stopped", final_position=[0.0, 0.0, 0.0], warnings=[])
    fields.update(surface_points=1, tetrahedra=1, steps=1, rejected_steps=0, forced_steps=0)
    fields.update(energy_rejections=0, energy_projections=0, load_evaluations=1)

    def job(scene_json: str):
        speed = json.loads(scene_json)["impact"]["speed"]
        return {**fields, "axis_angle_change": -turn(speed, critical)}, None, code_version("run")

    return job


class Bars(list):
    """Every tqdm bar made, with what it counted when it closed."""

    def install(self, monkeypatch):
        import tqdm

        bars = self

        class Recorded(tqdm.tqdm):
            def __init__(self, *args, **kwargs):
                super().__init__(*args, **kwargs)
                bars.append(self)

        monkeypatch.setattr(tqdm, "tqdm", Recorded)
        return self


def critical_command(tmp_path, *options):
    from cases.cli import main

    store = tmp_path / "store"
    args = ["critical", str(scene_path("paper_p3")), "--store", str(store), "--workers", "1", "--guide", "none"]
    code = main([*args, "--json", *options])
    return code, store


def test_a_search_of_several_rounds_shows_one_bar_counting_every_run(monkeypatch, capsys, tmp_path):
    from cases.run import RunStore
    from cases.studies.engine import pool as pool_module

    monkeypatch.setattr(pool_module, "run_job", fake_job(907.3))
    bars = Bars().install(monkeypatch)
    code, store = critical_command(tmp_path, "--progress")
    assert code == 0
    record = json.loads(capsys.readouterr().out)
    made = len(RunStore(store).records())
    assert record["rounds"] >= 5 and record["runs"] == made  # one worker: a bisection, a run a round
    assert len(bars) == 1, "one bar for the whole search, not one a round"
    assert bars[0].n == bars[0].total == made and bars[0].desc == "critical"


def test_progress_shows_on_a_terminal_or_when_asked(monkeypatch, capsys, tmp_path):
    from cases.studies.engine import pool as pool_module

    monkeypatch.setattr(pool_module, "run_job", fake_job(907.3))
    bars = Bars().install(monkeypatch)
    # stderr is a pipe here (pytest's capture): no bar unless asked
    assert critical_command(tmp_path / "quiet")[0] == 0
    assert bars == [] and capsys.readouterr().err == ""
    assert critical_command(tmp_path / "asked", "--progress")[0] == 0
    assert len(bars) == 1 and "critical" in capsys.readouterr().err
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)  # a terminal: a bar by default
    assert critical_command(tmp_path / "terminal")[0] == 0
    assert len(bars) == 2
    assert critical_command(tmp_path / "refused", "--no-progress")[0] == 0
    assert len(bars) == 2


def test_a_search_found_in_the_store_counts_its_runs_as_done(monkeypatch, capsys, tmp_path):
    """Run again with a finer resolution: the first search's runs count as done at once, the new ones as made."""
    from cases.run import RunStore
    from cases.studies.engine import pool as pool_module

    monkeypatch.setattr(pool_module, "run_job", fake_job(907.3))
    assert critical_command(tmp_path, "--no-progress")[0] == 0
    before = len(RunStore(tmp_path / "store").records())
    bars = Bars().install(monkeypatch)
    assert critical_command(tmp_path, "--progress", "--resolution", "1")[0] == 0
    record = json.loads(capsys.readouterr().out.splitlines()[-1])
    after = len(RunStore(tmp_path / "store").records())
    assert after > before and len(bars) == 1
    assert bars[0].n == bars[0].total == record["runs"]  # every run of this search: found or made


def test_a_failed_run_ends_the_search_naming_its_speed_and_error(monkeypatch, base):
    def failing(sweep, store, pool=None):
        from cases.studies.engine.sweep import SweepResult

        runs = [SimpleNamespace(failed=True, error="ValueError: boom", summary=None, key="k") for _ in sweep.scenes]
        return SweepResult(sweep, runs, store)

    monkeypatch.setattr(speeds_module, "run_sweep", failing)
    with pytest.raises(RuntimeError, match=r"^the run at 667.5 m/s failed: ValueError: boom$"):  # the first split
        find_critical_velocity(base, None, RANGE, 5.0, Pool(workers=2, progress=False), guide="none")
