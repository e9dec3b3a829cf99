"""Sweeps: grids, the run store, failures, interruption and resumption, Dask (a LocalCluster and a cluster of
``dask scheduler`` and ``dask worker`` processes)."""

import json
import os
import signal
import subprocess
import sys
import time

import pandas as pd
import pytest
from support import dask_cluster

from cases import InputError, SceneError, scene_path
from cases.run import RunStore
from cases.studies import Pool, Sweep, grid, parse_grid, read_variations, run_sweep

# short runs of projectile #3: coarse mesh, 4 ms of penetration
QUICK = {
    "numerics.mesh_size": 0.03,
    "numerics.integrator": "rk4",
    "numerics.time_step": 2e-5,
    "numerics.time_limit": 0.004,
}
QUICK_SET = [
    "numerics.mesh_size=0.03",
    "numerics.integrator=rk4",
    "numerics.time_step=2e-5",
    "numerics.time_limit=0.004",
]
VOLATILE = ["wall_time", "integration_time"]


def _sweep(speeds=(1000, 1100, 1200)):
    return Sweep.from_file(scene_path("paper_p3"), QUICK, grid({"impact.speed": list(speeds)}))


def _records(store):
    return sorted((store / "run").glob("*.json"))


def _stable(table: pd.DataFrame) -> pd.DataFrame:
    return table.drop(columns=[c for c in VOLATILE if c in table]).reset_index(drop=True)


@pytest.mark.parametrize(
    "text, key, values",
    [
        ("impact.speed=1000:1200:100", "impact.speed", [1000, 1100, 1200]),
        ("impact.attack_angle=0.5:1.5:0.5", "impact.attack_angle", [0.5, 1.0, 1.5]),
        ("target.law=soil,softer_soil", "target.law", ["soil", "softer_soil"]),
        ("impact.oblique_angle=10,20.5", "impact.oblique_angle", [10, 20.5]),
    ],
)
def test_parse_grid(text, key, values):
    assert parse_grid(text) == (key, values)


@pytest.mark.parametrize("bad", ["impact.speed", "impact.speed=", "impact.speed=3:1:1", "impact.speed=a:b:c"])
def test_parse_grid_errors(bad):
    with pytest.raises(InputError, match="--grid"):
        parse_grid(bad)


def test_grid_is_a_cartesian_product():
    variations = grid({"a": [1, 2], "b": ["x", "y", "z"]})
    assert [v.values for v in variations][:4] == [
        {"a": 1, "b": "x"},
        {"a": 1, "b": "y"},
        {"a": 1, "b": "z"},
        {"a": 2, "b": "x"},
    ]


def test_variation_values_reach_the_scene_as_they_are():
    """A table value in a list file stays a table (it used to go through text and come back a string)."""
    sweep = Sweep.from_file(
        scene_path("paper_p3"),
        QUICK,
        read_variations_text('[[run]]\n"effects.friction" = { model = "capped", coefficient = 0.1, cap = 1e7 }\n'),
    )
    assert sweep.scenes[0].effects.friction.cap == 1e7


def read_variations_text(text: str):
    import tempfile

    with tempfile.NamedTemporaryFile("w", suffix=".toml", delete=False) as f:
        f.write(text)
    try:
        return read_variations(f.name)
    finally:
        os.unlink(f.name)


def test_bad_variation_fails_before_anything_runs(tmp_path):
    with pytest.raises(SceneError, match="impact.speed = -5"):
        Sweep.from_file(scene_path("paper_p3"), QUICK, grid({"impact.speed": [1000, -5]}))
    assert not list(tmp_path.iterdir())


def test_sweep_stores_runs_and_skips_them_when_run_again(tmp_path):
    store = RunStore(tmp_path / "store")
    sweep = _sweep()
    result = run_sweep(sweep, store, Pool(workers=2, progress=False))
    table = result.table()
    assert list(table["impact.speed"]) == [1000, 1100, 1200]
    assert table["end_reason"].eq("time_limit").all() and "error" not in table
    assert [run.summary.end_reason for run in result.runs] == ["time_limit"] * 3  # typed, as the studies read them
    records = _records(tmp_path / "store")
    assert len(records) == 3 and len(list((tmp_path / "store" / "run").glob("*.csv.gz"))) == 3
    stamps = [p.stat().st_mtime_ns for p in records]
    again = run_sweep(sweep, store, Pool(workers=2, progress=False)).table()
    assert [p.stat().st_mtime_ns for p in records] == stamps
    pd.testing.assert_frame_equal(again, table)
    history = result.history(0)
    assert history["time"].iloc[-1] == pytest.approx(0.004)


def test_rounds_of_a_study_reuse_warm_workers(tmp_path):
    """Two rounds on two local workers (as the bisection of a critical speed runs them) go to the same
    worker processes, which keep their imports and prepared projectiles, and give the table one worker
    gives."""
    from cases.studies.engine import pool as pool_module

    first = run_sweep(_sweep(speeds=(1000,)), RunStore(tmp_path / "a"), Pool(workers=2, progress=False)).table()
    executor = pool_module._WARM[2]
    workers = set(executor._processes)  # the pids of its worker processes
    second = run_sweep(_sweep(speeds=(1100, 1200)), RunStore(tmp_path / "a"), Pool(workers=2, progress=False))
    assert pool_module._WARM[2] is executor and workers <= set(executor._processes)  # started lazily, kept
    one = run_sweep(_sweep(speeds=(1000, 1100, 1200)), RunStore(tmp_path / "b"), Pool(workers=1, progress=False))
    pd.testing.assert_frame_equal(
        _stable(pd.concat([first, second.table()], ignore_index=True)), _stable(one.table()), check_dtype=False
    )


# run in a process of its own, which has one thread (as the command line has) when it starts its workers
_FORKED_SWEEP = """
import json, sys
from cases import scene_path
from cases.run import RunStore
from cases.studies import Pool, Sweep, grid, run_sweep
from cases.studies.engine import pool
sweep = Sweep.from_file(scene_path("paper_p3"), json.loads(sys.argv[2]), grid({"impact.speed": [1000, 1100, 1200]}))
table = run_sweep(sweep, RunStore(sys.argv[1]), Pool(workers=2, progress=False)).table()
print(pool._WARM[2]._mp_context.get_start_method())
print(table.to_json())
"""


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_a_single_threaded_process_forks_its_workers_and_they_give_the_table_one_worker_gives(tmp_path):
    """Workers forked from a process with one thread (they start with its imports and loaded machine code) give
    the runs one worker gives; a process with another thread running spawns its workers instead."""
    import io
    import threading

    from cases.studies.engine import pool as pool_module

    done = subprocess.run(
        [sys.executable, "-c", _FORKED_SWEEP, str(tmp_path / "forked"), json.dumps(QUICK)],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    method, text = done.stdout.splitlines()[-2:]
    assert method == "fork"
    forked = pd.read_json(io.StringIO(text), dtype=False)  # as written: exit_time is seconds, not a date
    one = run_sweep(_sweep(), RunStore(tmp_path / "one"), Pool(workers=1, progress=False)).table()
    pd.testing.assert_frame_equal(_stable(forked), _stable(one), check_dtype=False)

    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        assert pool_module.start_method() == "spawn"
    finally:
        stop.set()
        other.join()


def test_a_failed_run_is_recorded_and_does_not_stop_the_others(tmp_path):
    store = RunStore(tmp_path)
    # a centre of mass the counterweight cannot reach fails at run time, in the worker
    sweep = Sweep.from_file(scene_path("paper_p3"), QUICK, grid({"projectile.centre_of_mass_ratio": [0.5636, 0.2]}))
    result = run_sweep(sweep, store, Pool(workers=1, progress=False))
    assert not result.runs[0].failed and result.runs[1].failed
    table = result.table()
    assert table["end_reason"].iloc[0] == "time_limit" and pd.isna(table["error"].iloc[0])
    assert "centre_of_mass" in table["error"].iloc[1]
    assert not store.finished(table["key"].iloc[1]) and store.finished(table["key"].iloc[0])


@pytest.mark.parametrize("ratios, every", [("0.2,0.19", True), ("0.5636,0.2", False)])
def test_a_sweep_with_failed_runs_ends_with_the_command_that_shows_why(tmp_path, capsys, ratios, every):
    """Exit 1 and one line on stderr: how many failed, and a command that reproduces the first failure with
    its traceback (tried here: it fails the same way)."""
    import shlex

    from cases.cli import main

    store = tmp_path / "store"
    sets = [o for item in QUICK_SET for o in ("--set", item)]
    grid_option = ["--grid", f"projectile.centre_of_mass_ratio={ratios}"]
    assert (
        main(
            [
                "sweep",
                str(scene_path("paper_p3")),
                *sets,
                *grid_option,
                "--workers",
                "1",
                "--store",
                str(store),
                "--out",
                str(tmp_path / "out"),
            ]
        )
        == 1
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(
        "penetrate sweep: every run failed" if every else "penetrate sweep: 1 of 2 runs failed"
    )
    command = err[0].split("(the error column says why): ", 1)[1].removesuffix(" shows the first one's traceback")
    words = shlex.split(command)
    assert words[:3] == ["penetrate", "--debug", "run"] and "projectile.centre_of_mass_ratio=0.2" in words
    with pytest.raises(Exception, match="centre_of_mass"):  # --debug: the failure itself, not one line
        main(words[1:])


def _cli_sweep(store, out, *extra):
    args = [
        sys.executable,
        "-m",
        "cases.cli",
        "sweep",
        str(scene_path("paper_p3")),
        "--store",
        str(store),
        "--out",
        str(out),
        "--workers",
        "1",
        "--no-progress",
        "--grid",
        "impact.speed=900:1400:100",
    ]
    for item in QUICK_SET:
        args += ["--set", item]
    return args + list(extra)


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_killed_sweep_loses_nothing_and_resumes(tmp_path):
    store, out = tmp_path / "store", tmp_path / "table"
    log = tmp_path / "stderr.txt"
    with log.open("w") as stderr:
        proc = subprocess.Popen(
            _cli_sweep(store, out), start_new_session=True, stdout=subprocess.DEVNULL, stderr=stderr
        )
    deadline = time.time() + 240
    while time.time() < deadline and len(_records(store)) < 2 and proc.poll() is None:
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    finished = {p: p.stat().st_mtime_ns for p in _records(store)}
    assert 2 <= len(finished) < 6 and not out.exists(), (len(finished), log.read_text()[-2000:])
    for path in finished:  # every stored run is complete: a record and the history beside it
        assert "error" not in json.loads(path.read_text()) and path.with_suffix(".csv.gz").exists()
    done = subprocess.run(_cli_sweep(store, out), capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert all(p.stat().st_mtime_ns == stamp for p, stamp in finished.items())  # reused, not rerun
    resumed = pd.read_csv(out / "sweep.csv")
    fresh_out = tmp_path / "fresh"
    fresh = subprocess.run(_cli_sweep(tmp_path / "fresh-store", fresh_out), capture_output=True, text=True, timeout=600)
    assert fresh.returncode == 0, fresh.stderr
    pd.testing.assert_frame_equal(_stable(resumed), _stable(pd.read_csv(fresh_out / "sweep.csv")), check_exact=True)
    assert len(resumed) == 6


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_dask_local_cluster_gives_the_same_table(tmp_path):
    distributed = pytest.importorskip("distributed")
    sweep = _sweep(speeds=(1000, 1200))
    local = run_sweep(sweep, RunStore(tmp_path / "local"), Pool(workers=2, progress=False)).table()
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        remote = run_sweep(
            sweep, RunStore(tmp_path / "dask"), Pool(scheduler=cluster.scheduler_address, progress=False)
        ).table()
    pd.testing.assert_frame_equal(_stable(remote), _stable(local), check_exact=True)


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_dask_scheduler_and_worker_processes_give_the_same_table(tmp_path):
    """A cluster of separate ``dask scheduler`` and ``dask worker`` processes, as on a real cluster: the
    workers import this project themselves (nothing is shared with this process) and report the code
    version they ran, which must be this process's."""
    pytest.importorskip("distributed")
    with dask_cluster(tmp_path) as address:
        sweep = _sweep(speeds=(1000, 1200))
        remote = run_sweep(sweep, RunStore(tmp_path / "cluster"), Pool(scheduler=address, progress=False)).table()
    local = run_sweep(sweep, RunStore(tmp_path / "local"), Pool(workers=1, progress=False)).table()
    pd.testing.assert_frame_equal(_stable(remote), _stable(local), check_exact=True)


def test_a_worker_running_other_code_is_refused(tmp_path, monkeypatch):
    from cases.studies.engine import pool

    monkeypatch.setattr(pool, "run_job", lambda text: (*pool.simulate_record(text), "other-code"))
    with pytest.raises(pool.CodeMismatch, match="code version other-code"):
        run_sweep(_sweep(speeds=(1000,)), RunStore(tmp_path), Pool(workers=1, progress=False))
    assert not (tmp_path / "run").exists()  # nothing stored under this process's version


def test_listed_variations_combine_with_a_grid(tmp_path):
    listing = tmp_path / "runs.toml"
    listing.write_text(
        '[[run]]\n"impact.speed" = 1000\n\n[[run]]\n"impact.speed" = 1100\n"impact.attack_angle" = 5.0\n'
    )
    args = [
        sys.executable,
        "-m",
        "cases.cli",
        "sweep",
        str(scene_path("paper_p3")),
        "--list",
        str(listing),
        "--grid",
        "impact.oblique_angle=0,10",
        "--store",
        str(tmp_path / "s"),
        "--out",
        str(tmp_path / "t"),
        "--no-progress",
        "--workers",
        "2",
    ]
    for item in QUICK_SET:
        args += ["--set", item]
    done = subprocess.run(args, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    table = pd.read_csv(tmp_path / "t" / "sweep.csv")
    assert list(zip(table["impact.oblique_angle"], table["impact.speed"])) == [
        (0, 1000),
        (0, 1100),
        (10, 1000),
        (10, 1100),
    ]
    assert table["impact.attack_angle"].isna().tolist() == [True, False, True, False]


def test_bad_list_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("speed = 3\n")
    with pytest.raises(InputError, match=r"\[\[run\]\]"):
        read_variations(bad)


def test_the_compiled_step_is_compiled_once_before_local_workers_start(monkeypatch):
    """With numba's cache empty, a sweep on local workers compiles (and announces) the step once, in this
    process, instead of in every worker side by side; a sweep that runs nothing compiled compiles nothing.
    Workers about to be forked find it loaded here even when the cache has it."""
    from cases import load_scene, scene_path
    from cases.run import compiled
    from cases.studies.engine import pool

    calls = []
    monkeypatch.setattr(pool, "start_method", lambda: "spawn")
    monkeypatch.setattr(compiled, "needs_compiling", lambda entry: True)
    monkeypatch.setattr(compiled, "precompile", lambda: calls.append("compiled"))
    scene = load_scene(scene_path("paper_p3"))
    pool._compile_once([scene], width=2)
    assert calls == ["compiled"]
    pool._compile_once([scene], width=1)  # one worker compiles it once anyway
    numpy_only = load_scene(scene_path("paper_p3"), {"numerics.kernel": "numpy"})
    pool._compile_once([numpy_only], width=2)
    assert calls == ["compiled"]
    monkeypatch.setattr(compiled, "needs_compiling", lambda entry: False)
    pool._compile_once([scene], width=2)
    assert calls == ["compiled"]
    monkeypatch.setattr(pool, "start_method", lambda: "fork")
    pool._compile_once([scene], width=3)  # no such workers yet: they will be forked from this process
    assert calls == ["compiled", "compiled"]
    pool._compile_once([numpy_only], width=3)
    assert calls == ["compiled", "compiled"]
