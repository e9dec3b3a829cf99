"""Ensembles: distributions parsed and sampled, designs, reproducibility, the interval's coverage, bins."""

import json

import numpy as np
import pandas as pd
import pytest
from scipy.stats import binom, binomtest
from support import dask_cluster

from cases import scene_path
from cases.scene import InputError, load_scene
from cases.studies.ensemble.sampling import (
    RANDOM_BLOCK,
    Estimate,
    curve,
    draw,
    estimate,
    parse_bins,
    parse_sample,
    unit_points,
    variations,
    wilson_interval,
)


@pytest.fixture(scope="module")
def base():
    return load_scene(scene_path("forrestal_luk_test2"))


@pytest.mark.parametrize(
    "text, mean, sd",
    [
        ("impact.speed=normal:300:10", 300.0, 10.0),
        ("impact.speed=truncnormal:300:20:280:340", None, None),
        ("impact.speed=uniform:250:350", 300.0, 100 / 12**0.5),
        ("impact.speed=lognormal:300:0.1", 300 * np.exp(0.005), 300 * np.sqrt((np.exp(0.01) - 1) * np.exp(0.01))),
        ("impact.speed=choice:260,280,330", 290.0, np.std([260, 280, 330])),
        # |N(0, s)|: mean s sqrt(2/pi), SD s sqrt(1 - 2/pi)
        ("impact.attack_angle=halfnormal:2", 2 * np.sqrt(2 / np.pi), 2 * np.sqrt(1 - 2 / np.pi)),
    ],
)
def test_sample_mean_and_sd_within_two_percent(text, mean, sd):
    dist = parse_sample(text)
    if mean is None:  # the truncated normal's moments from scipy's closed form
        mean, sd = dist.frozen().mean(), dist.frozen().std()
    values = draw([dist], 10_000, seed=3)[:, 0]
    assert values.mean() == pytest.approx(mean, rel=0.02)
    assert values.std() == pytest.approx(sd, rel=0.02)


def test_truncated_normal_stays_in_its_bounds():
    values = draw([parse_sample("impact.speed=truncnormal:300:50:280:310")], 2000, seed=1)[:, 0]
    assert values.min() >= 280 and values.max() <= 310


def test_latin_hypercube_puts_one_point_in_each_stratum():
    n = 64
    points = unit_points("lhs", n, 3, seed=5)
    for j in range(3):
        assert sorted(np.floor(points[:, j] * n).astype(int)) == list(range(n))


def test_sobol_is_balanced_at_powers_of_two_and_extends():
    points = unit_points("sobol", 64, 2, seed=5)
    for j in range(2):  # a (t, m, s)-net: each of the 64 strata of one dimension holds one point
        assert sorted(np.floor(points[:, j] * 64).astype(int)) == list(range(64))
    assert np.array_equal(unit_points("sobol", 10, 2, seed=5), points[:10])  # raising n keeps the first points


def test_random_design_is_reproducible_and_extends():
    dists = [parse_sample("impact.speed=normal:300:10"), parse_sample("impact.attack_angle=uniform:0:2")]
    first = draw(dists, 20, seed=11)
    assert np.array_equal(first, draw(dists, 20, seed=11))
    assert np.array_equal(draw(dists, 50, seed=11)[:20], first)
    assert not np.array_equal(draw(dists, 20, seed=12), first)
    # across the generators' blocks: more runs keep the earlier points, and the blocks are not copies
    many = unit_points("random", 2 * RANDOM_BLOCK + 5, 2, seed=11)
    assert np.array_equal(unit_points("random", RANDOM_BLOCK + 3, 2, seed=11), many[: RANDOM_BLOCK + 3])
    assert not np.any(np.all(many[:RANDOM_BLOCK] == many[RANDOM_BLOCK : 2 * RANDOM_BLOCK], axis=1))


def test_latin_hypercube_is_reproducible_but_not_extensible():
    assert np.array_equal(unit_points("lhs", 16, 2, seed=2), unit_points("lhs", 16, 2, seed=2))
    assert not np.array_equal(unit_points("lhs", 32, 2, seed=2)[:16], unit_points("lhs", 16, 2, seed=2))


def test_variations_are_typed(base):
    dists = [parse_sample("numerics.quadrature_order=choice:2,4", base), parse_sample("impact.speed=uniform:1:2", base)]
    for variation in variations(dists, draw(dists, 8, seed=0)):
        assert type(variation.values["numerics.quadrature_order"]) is int
        assert type(variation.values["impact.speed"]) is float


def test_wilson_interval_matches_scipy():
    for k, n in ((0, 10), (3, 10), (10, 10), (37, 200)):
        ci = binomtest(k, n).proportion_ci(0.95, method="wilson")
        assert wilson_interval(k, n) == pytest.approx((ci.low, ci.high), abs=1e-12)
    assert np.isnan(Estimate.of(0, 0).probability) and np.isnan(Estimate.of(0, 0).interval[0])


@pytest.mark.parametrize("p, n", [(0.3, 40), (0.05, 200), (0.5, 15)])
def test_wilson_interval_covers_about_95_percent(p, n):
    """The exact coverage: the binomial probability of every count whose interval holds p."""
    k = np.arange(n + 1)
    low, high = wilson_interval(k, np.full_like(k, n))
    coverage = binom.pmf(k, n, p)[(low <= p) & (p <= high)].sum()
    assert 0.92 <= coverage <= 0.98


def test_estimates_count_failed_runs_apart():
    table = pd.DataFrame(
        {
            "unstable": [True, False, False, False],
            "exited": [False] * 4,
            "stopped": [False, True, True, False],
            "failed": [False, False, False, True],
        }
    )
    estimates = estimate(table)
    assert estimates["failed"].probability == 0.25 and estimates["failed"].runs == 4
    assert estimates["stopped"].probability == pytest.approx(2 / 3) and estimates["stopped"].runs == 3
    assert estimates["unstable"].interval[0] < 1 / 3 < estimates["unstable"].interval[1]


def test_curve_bins_by_a_sampled_key():
    key, edges = parse_bins("impact.speed=200:300:50", ["impact.speed"])
    assert key == "impact.speed" and list(edges) == [200, 250, 300]
    assert list(parse_bins("impact.speed=0:10:4", ["impact.speed"])[1]) == [0, 4, 8, 10]
    values = np.array([210.0, 240.0, 260.0, 300.0, 310.0])
    table = pd.DataFrame(
        {
            "unstable": [False, False, True, True, True],
            "exited": [False] * 5,
            "stopped": [True, True, False, False, False],
            "failed": [False] * 5,
        }
    )
    bins = curve(values, table, edges)
    assert [b["runs"] for b in bins] == [2, 2]  # 310 lies outside; 300 is in the last bin
    assert bins[0]["unstable"] == 0.0 and bins[1]["unstable"] == 1.0
    assert bins[1]["interval"]["unstable"][1] == 1.0 and bins[1]["bin"] == [250.0, 300.0]


@pytest.mark.parametrize(
    "text, message",
    [
        ("impact.speed=gauss:1:2", "expected KEY=DIST with DIST one of normal:MEAN:SD"),
        ("impact.speed=normal:300", "expected normal:MEAN:SD"),
        ("impact.speed=uniform:1:2:3", "expected uniform:LO:HI"),
        ("impact.speed=normal:300:0", "need SD > 0"),
        ("impact.speed=truncnormal:300:10:320:280", "need LO < HI"),
        ("impact.speed=uniform:5:5", "need LO < HI"),
        ("impact.speed=lognormal:-1:0.1", "need MEDIAN > 0"),
        ("impact.attack_angle=halfnormal:0", "need SCALE > 0"),
        ("impact.attack_angle=halfnormal:1:2", "expected halfnormal:SCALE"),
        ("impact.speed=normal:fast:10", "the parameters must be numbers"),
        ("impact.speed=normal:inf:10", "must be finite numbers"),
        ("impact.speed=choice:", "expected choice:V1,V2,..."),
        ("impact.speed=choice:1,,2", "expected choice:V1,V2,..."),
        ("impact.speed", "expected KEY=DIST"),
        ("target.law=choice:1,2", "target.law is not a numeric key of the scene"),
        ("impact.sped=normal:1:1", "impact.sped is not a numeric key of the scene"),
        ("numerics.quadrature_order=uniform:1:4", "is a whole number; sample it with choice"),
        ("numerics.quadrature_order=choice:2,2.5", "must be whole numbers"),
        ("impact..speed=normal:1:1", "the key must be a dotted path"),
    ],
)
def test_bad_samples_are_one_line_naming_the_option(base, text, message):
    with pytest.raises(InputError) as caught:
        parse_sample(text, base)
    assert str(caught.value).startswith(f"--sample {text!r}") and message in str(caught.value)
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize(
    "text, message",
    [
        ("impact.attack_angle=0:1:0.5", "KEY one of the sampled keys"),
        ("impact.speed=200:300", "three finite numbers"),
        ("impact.speed=300:200:10", "need STEP > 0 and STOP > START"),
        ("impact.speed=200:300:0", "need STEP > 0"),
    ],
)
def test_bad_bins(text, message):
    with pytest.raises(InputError, match=message):
        parse_bins(text, ["impact.speed"])


def test_bad_design_size_and_seed():
    with pytest.raises(InputError, match="--design 'halton'"):
        unit_points("halton", 4, 1, 0)
    with pytest.raises(InputError, match="-n"):
        unit_points("random", 0, 1, 0)
    with pytest.raises(InputError, match="--seed -1: must be a whole number >= 0"):
        unit_points("sobol", 4, 1, -1)


CHEAP = ["--set", "numerics.mesh_size=0.04", "--set", "numerics.quadrature_order=2"]


def _ensemble(tmp_path, count, *extra):
    from cases.cli import main

    return main(
        [
            "ensemble",
            str(scene_path("forrestal_luk_test2")),
            *CHEAP,
            "--sample",
            "impact.speed=uniform:250:310",
            "-n",
            str(count),
            "--seed",
            "4",
            "--workers",
            "1",
            "--no-progress",
            "--store",
            str(tmp_path / "store"),
            "--out",
            str(tmp_path / "out"),
            *extra,
        ]
    )


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_ensemble_command_on_test_2(tmp_path, capsys):
    """A few runs of test 2 (280 m/s +- 30): every run stops; the outputs' structure; -n raised runs only the new."""
    assert _ensemble(tmp_path, 5, "--by", "impact.speed=250:310:30", "--json") == 0
    record = json.loads(capsys.readouterr().out)
    assert record["runs"] == 5 and record["probability"]["stopped"] == 1.0
    assert record["probability"]["unstable"] == 0.0 and record["interval"]["stopped"][1] == 1.0
    assert [b["bin"] for b in record["curve"]] == [[250.0, 280.0], [280.0, 310.0]]
    assert sum(b["runs"] for b in record["curve"]) == 5
    assert all(b["stopped"] == 1.0 and len(b["interval"]["stopped"]) == 2 for b in record["curve"] if b["runs"])
    out = tmp_path / "out"
    assert {p.name for p in out.iterdir()} == {
        "ensemble.md",
        "ensemble.csv",
        "ensemble.json",
        "ensemble_curve.png",
        "ensemble_histograms.png",
    }
    assert json.loads((out / "ensemble.json").read_text()) == record
    first = pd.read_csv(out / "ensemble.csv")
    assert list(first.columns[:6]) == ["sample", "impact.speed", "unstable", "exited", "stopped", "failed"]
    assert first["stopped"].all() and first["impact.speed"].between(250, 310).all()
    assert "| stopped | 1 |" in (out / "ensemble.md").read_text()
    # the distributions: numpy's quantiles of the CSV's columns (no run of test 2 converges from a peak)
    for name in ("depth", "path_length", "axis_angle_change"):
        quantiles = record["distributions"][name]["quantiles"]
        assert quantiles["0.5"] == pytest.approx(first[name].median(), rel=1e-12)
        assert quantiles["0.05"] <= quantiles["0.25"] <= quantiles["0.5"] <= quantiles["0.75"] <= quantiles["0.95"]
    assert record["distributions"]["convergence_speed"]["runs"] == first["convergence_speed"].notna().sum() == 0
    assert "| depth (m) | 5 |" in (out / "ensemble.md").read_text()
    # bins beside the samples hold no run: the report says which, and the --by that bins the samples
    samples = ", ".join(f"{v:.4g}" for v in (first["impact.speed"].min(), first["impact.speed"].max()))
    assert _ensemble(tmp_path, 5, "--by", "impact.speed=400:500:50") == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last.startswith(
        "No sample fell in 2 of 2 bins (400 - 450, 450 - 500): bin where the samples lie"
        f" ({samples.replace(', ', ' to ')}), e.g. --by impact.speed="
    )
    start, stop, step = map(float, last.rsplit("=", 1)[1].rstrip(".").split(":"))
    assert step == 50 and start <= first["impact.speed"].min() and first["impact.speed"].max() <= stop
    assert _ensemble(tmp_path, 7) == 0
    assert len(list((tmp_path / "store" / "run").glob("*.json"))) == 7  # two new runs, five found again
    second = pd.read_csv(out / "ensemble.csv")
    assert second["key"][:5].tolist() == first["key"].tolist()


def test_empty_bins_inside_the_samples_ask_for_more_runs():
    """Bins between the samples (too few runs to fill them) call for more runs, not other bins."""
    from cases.studies.ensemble.study import _empty_bins

    speeds = np.array([251.0, 252.0, 309.0])
    table = pd.DataFrame({"impact.speed": speeds, "unstable": False, "exited": False, "stopped": True, "failed": False})
    record = {"runs": 3, "by": "impact.speed", "curve": curve(speeds, table, np.array([250.0, 270.0, 290.0, 310.0]))}
    assert _empty_bins(record, table) == (
        "No sample fell in 1 of 3 bins (270 - 290): give more runs (-n 6) or widen the distribution of"
        " impact.speed (--sample) over them."
    )
    record["curve"] = curve(speeds, table, np.array([250.0, 280.0, 310.0]))
    assert _empty_bins(record, table) == ""


def test_ensemble_command_bad_input(tmp_path, capsys):
    from cases.cli import main

    code = main(
        [
            "ensemble",
            str(scene_path("forrestal_luk_test2")),
            "--sample",
            "impact.speed=gauss:1:2",
            "-n",
            "3",
            "--out",
            str(tmp_path / "out"),
            "--store",
            str(tmp_path / "store"),
        ]
    )
    error = capsys.readouterr().err
    assert code == 2 and "--sample 'impact.speed=gauss:1:2'" in error and len(error.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()
    code = main(
        [
            "ensemble",
            str(scene_path("forrestal_luk_test2")),
            "--sample",
            "impact.speed=normal:10:100",
            "-n",
            "20",
            "--out",
            str(tmp_path / "out"),
            "--store",
            str(tmp_path / "store"),
        ]
    )
    assert code == 2 and "keep the samples in range" in capsys.readouterr().err


@pytest.mark.slow
def test_the_same_seed_writes_the_same_csv_on_one_two_workers_and_a_dask_cluster(tmp_path):
    """Same seed, 1 local worker, 2 local workers, and a ``dask scheduler`` with ``dask worker --nworkers 2``
    started from the command line (the workers import the project themselves): byte-identical ``ensemble.csv``
    and ``ensemble.json``, each from an empty run store."""
    from cases.cli import main

    def ensemble(name, *where):
        assert (
            main(
                [
                    "ensemble",
                    str(scene_path("forrestal_luk_test2")),
                    *CHEAP,
                    "--sample",
                    "impact.speed=uniform:250:310",
                    "--sample",
                    "impact.attack_angle=normal:0:1",
                    "-n",
                    "6",
                    "--seed",
                    "11",
                    "--no-progress",
                    "--store",
                    str(tmp_path / f"store-{name}"),
                    "--out",
                    str(tmp_path / name),
                    *where,
                ]
            )
            == 0
        )
        return [(tmp_path / name / f"ensemble.{kind}").read_bytes() for kind in ("csv", "json")]

    one, two = ensemble("one", "--workers", "1"), ensemble("two", "--workers", "2")
    with dask_cluster(tmp_path) as address:
        cluster = ensemble("cluster", "--scheduler", address)
    assert one == two == cluster
    assert b"wall_time" not in one[0] and b"integration_time" not in one[0]


@pytest.mark.slow
def test_a_dask_worker_killed_mid_ensemble_loses_no_run_and_changes_nothing(tmp_path):
    """A ``dask worker`` process SIGKILLed while the ensemble runs: Dask reruns its task elsewhere (its
    nanny starts a new worker), every finished run stays in the store, and the CSV is byte-identical to
    an uninterrupted ensemble's."""
    import os
    import signal
    import threading
    import time

    import psutil

    from cases.cli import main

    def ensemble(name, *where):
        return main(
            [
                "ensemble",
                str(scene_path("paper_p3")),
                *CHEAP,
                "--sample",
                "impact.speed=uniform:700:1100",
                "-n",
                "16",
                "--seed",
                "5",
                "--no-progress",
                "--store",
                str(tmp_path / f"store-{name}"),
                "--out",
                str(tmp_path / name),
                *where,
            ]
        )

    assert ensemble("quiet", "--workers", "2") == 0
    records = tmp_path / "store-killed" / "run"
    with dask_cluster(tmp_path) as address:
        outcome = {}
        thread = threading.Thread(target=lambda: outcome.setdefault("code", ensemble("killed", "--scheduler", address)))
        thread.start()
        deadline = time.monotonic() + 300
        while not (records.is_dir() and list(records.glob("*.json"))) and time.monotonic() < deadline:
            time.sleep(0.05)
        finished_before = {p.name: p.read_bytes() for p in records.glob("*.json")}
        cli = [
            p
            for p in psutil.process_iter(["cmdline"])
            if "worker" in " ".join(p.info["cmdline"] or []) and address in " ".join(p.info["cmdline"] or [])
        ]
        workers = [child for process in cli for child in process.children(recursive=True)]
        assert workers, "no dask worker process found"
        os.kill(workers[0].pid, signal.SIGKILL)
        thread.join(timeout=600)
    assert outcome.get("code") == 0
    assert 0 < len(finished_before) < 16, "the kill came before any run or after the last"
    for name, content in finished_before.items():  # no finished run lost or rewritten
        assert (records / name).read_bytes() == content
    assert len(list(records.glob("*.json"))) == 16
    for kind in ("csv", "json"):
        assert (tmp_path / "killed" / f"ensemble.{kind}").read_bytes() == (
            tmp_path / "quiet" / f"ensemble.{kind}"
        ).read_bytes()


@pytest.mark.slow
def test_the_probability_of_instability_has_a_known_answer(tmp_path):
    """#3 at 1 degree with the speed uniform over 850-1000 m/s: P(unstable) is the fraction of that range
    above the critical speed that ``penetrate critical`` finds with the same numerics (a range, the search's
    bracket); it must lie inside the ensemble's 95 % interval."""
    from cases.run import RunStore
    from cases.studies import Sweep, find_critical_velocity
    from cases.studies.ensemble.study import run_ensemble

    overrides = [("numerics.mesh_size", 0.04)]
    store = RunStore(tmp_path / "store")
    search = find_critical_velocity(Sweep.from_file(scene_path("paper_p3"), overrides), store, (850.0, 1000.0), 1.0)
    low, high = search.bracket
    exact = ((1000.0 - high) / 150.0, (1000.0 - low) / 150.0)
    record = run_ensemble(
        scene_path("paper_p3"),
        overrides,
        ["impact.speed=uniform:850:1000"],
        64,
        store,
        tmp_path / "out",
        seed=2,
        design="sobol",
    )
    interval = record["interval"]["unstable"]
    assert interval[0] <= exact[0] and exact[1] <= interval[1], (record["probability"]["unstable"], interval, exact)
    assert record["probability"]["failed"] == 0.0
