"""Nothing lost, nothing run: killed runs leave complete files or none, results do not depend on the
number of workers or BLAS threads, scene files are data, outputs stay in the folder given.

See docs/robustness.md.
"""

from __future__ import annotations

import ast
import csv
import gzip
import json
import math
import os
import random
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from cases import scene_path
from cases.run import HISTORY_UNITS, RunStore, atomic_write_text, run_scene, write_outputs
from cases.scene import InputError, SceneError, parse_override
from cases.scene import load_scene as _load_scene
from cases.studies import Pool, Sweep, grid, run_sweep

ROOT = Path(__file__).resolve().parents[1]
TEST2 = str(scene_path("forrestal_luk_test2"))
TINY = ["numerics.mesh_size=0.04"]
TEMPORARY = re.compile(r"^\.(summary\.json|history\.csv)\..+\.tmp$")
VOLATILE = ("wall_time", "integration_time")


def load_scene(path, texts=()):
    """A scene with ``KEY=VALUE`` overrides, as typed after ``--set``."""
    return _load_scene(path, [parse_override(text) for text in texts])


def _sweep(texts, variations):
    return Sweep.from_file(TEST2, [parse_override(text) for text in texts], variations)


def _cli(*args: str) -> list[str]:
    # the installed command, not ``-m cases.cli``: a module run with -m is looked up from the working directory
    # first, which another test of the same worker may have left elsewhere
    return [str(Path(sys.executable).with_name("penetrate")), *args]


def _sets(items) -> list[str]:
    return [word for item in items for word in ("--set", item)]


def check_outputs(out: Path) -> str:
    """Every file in a run's --out folder is complete or absent, and a summary belongs with its history.

    Returns what is there: "nothing", "history only" or "complete".
    """
    names = {p.name for p in out.iterdir()} if out.exists() else set()
    finals = names - {n for n in names if TEMPORARY.match(n)}
    assert finals <= {"summary.json", "history.csv"}, names
    history = None
    if "history.csv" in finals:
        with open(out / "history.csv", newline="") as f:
            rows = list(csv.reader(f))
        assert rows[0] == list(HISTORY_UNITS) and len(rows) > 1
        assert all(len(row) == len(HISTORY_UNITS) for row in rows)  # no torn last line
        history = pd.read_csv(out / "history.csv")
    if "summary.json" in finals:
        summary = json.loads((out / "summary.json").read_text())  # complete JSON
        assert summary["history_units"] == HISTORY_UNITS
        if summary["scene_resolved"]["outputs"]["history"]:
            assert history is not None, "a summary without its history"
            # the summary and the history are of the same run
            assert history["time"].iloc[-1] == pytest.approx(summary["final_time"], rel=1e-9)
            assert history["speed"].iloc[0] == pytest.approx(summary["scene_resolved"]["impact"]["speed"])
        return "complete"
    return "history only" if history is not None else "nothing"


# ---------------------------------------------------------------------------
# killed at any moment


@pytest.mark.slow
def test_killed_runs_leave_complete_files_or_none(tmp_path):
    """SIGKILL ``penetrate run --out`` at random moments, half of them into a folder holding an older run."""
    args = _cli("run", TEST2, *_sets(TINY), "--out")
    start = time.perf_counter()
    done = subprocess.run([*args, str(tmp_path / "timing")], capture_output=True, text=True, timeout=300)
    whole = time.perf_counter() - start
    assert done.returncode == 0 and check_outputs(tmp_path / "timing") == "complete", done.stderr
    older = _sets(["impact.speed=250"])  # an older run, different in every number
    subprocess.run(
        [*_cli("run", TEST2, *_sets(TINY), *older, "--out"), str(tmp_path / "older")],
        check=True,
        capture_output=True,
        timeout=300,
    )
    rng = random.Random(20240607)
    seen: dict[str, int] = {}
    for i in range(8):
        out = tmp_path / f"kill{i}"
        out.mkdir()
        if i % 2:
            for name in ("summary.json", "history.csv"):
                (out / name).write_bytes((tmp_path / "older" / name).read_bytes())
        before = {p.name for p in out.iterdir()}
        proc = subprocess.Popen([*args, str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        if i < 3:  # at a random moment of the run
            time.sleep(rng.uniform(0.1, 0.9) * whole)
        else:  # as the writing starts (the first new name in the folder), plus 0-20 ms
            deadline = time.perf_counter() + 10 * whole
            while proc.poll() is None and time.perf_counter() < deadline and {p.name for p in out.iterdir()} == before:
                time.sleep(0.0005)
            time.sleep(rng.uniform(0.0, 0.02))
        proc.send_signal(signal.SIGKILL)
        code = proc.wait()
        state = check_outputs(out)
        if state == "complete":
            speed = json.loads((out / "summary.json").read_text())["scene_resolved"]["impact"]["speed"]
            state = "older run" if speed == 250 else "this run"
        key = f"{'older run present' if i % 2 else 'empty folder'} -> {state}" + (", exit 0" if code == 0 else "")
        seen[key] = seen.get(key, 0) + 1
    print("kills:", seen)
    # running again into a killed run's folder completes it and removes the killed writers' temporaries
    for i in range(8):
        out = tmp_path / f"kill{i}"
        subprocess.run([*args, str(out)], check=True, capture_output=True, timeout=300)
        assert check_outputs(out) == "complete"
        assert {p.name for p in out.iterdir()} == {"summary.json", "history.csv"}


def test_stale_temporaries_of_dead_writers_are_removed(tmp_path):
    """A temporary named for a process that no longer runs is removed by the next write of that file;
    one of a running process (a concurrent writer) and other files are left alone."""
    finished = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True, check=True
    )
    dead = int(finished.stdout)
    stale = tmp_path / f".summary.json.{dead}.abc123.tmp"
    live = tmp_path / f".summary.json.{os.getppid()}.def456.tmp"
    other = tmp_path / f".history.csv.{dead}.abc123.tmp"
    for path in (stale, live, other):
        path.write_text("partial")
    atomic_write_text(tmp_path / "summary.json", "{}")
    assert not stale.exists() and live.exists() and other.exists()
    assert (tmp_path / "summary.json").read_text() == "{}"


def test_writes_interrupted_at_every_step(tmp_path):
    """Kill a child process at each unlink, fsync and rename of write_outputs, over an older run's files."""
    result = run_scene(load_scene(TEST2, TINY + ["numerics.time_limit=0.003"]))
    older = tmp_path / "older"
    write_outputs(run_scene(load_scene(TEST2, TINY + ["numerics.time_limit=0.002", "impact.speed=250"])), older)
    states = []
    for point in range(1, 50):
        out = tmp_path / f"point{point}"
        out.mkdir()
        for name in ("summary.json", "history.csv"):
            (out / name).write_bytes((older / name).read_bytes())
        pid = os.fork()
        if pid == 0:  # the child: die at the point-th unlink, fsync or rename
            code = 3
            try:
                calls = 0

                def dying(real, stop):
                    def call(*a, **k):
                        nonlocal calls
                        calls += 1
                        if calls == stop:
                            os.kill(os.getpid(), signal.SIGKILL)
                        return real(*a, **k)

                    return call

                os.unlink, os.fsync, os.replace = (dying(f, point) for f in (os.unlink, os.fsync, os.replace))
                write_outputs(result, out)
                code = 0
            finally:
                os._exit(code)
        _, status = os.waitpid(pid, 0)
        state = check_outputs(out)
        if state == "complete":
            speed = json.loads((out / "summary.json").read_text())["scene_resolved"]["impact"]["speed"]
            state = "older run" if speed == 250 else "this run"
        states.append(state)
        if os.WIFEXITED(status):  # no more points: the writer finished
            assert os.WEXITSTATUS(status) == 0 and state == "this run"
            break
        # killed before the summary's rename: the older run or this run's history alone; after it: this run
        assert state in ("older run", "nothing", "history only", "this run"), states
        assert "this run" not in states[:-1] or state == "this run", states
    else:
        pytest.fail("write_outputs did not finish within 50 interruption points")
    assert len(states) >= 7, states
    print("interruption points:", len(states) - 1, states)


# ---------------------------------------------------------------------------
# the same bits whatever the workers and threads


def test_one_or_two_workers_give_identical_bits(tmp_path):
    sweep = _sweep(
        TINY + ["numerics.time_limit=0.004", "impact.attack_angle=3"], grid({"impact.speed": [250, 300, 350]})
    )
    stores = {n: RunStore(tmp_path / f"w{n}") for n in (1, 2)}
    one, two = (run_sweep(sweep, stores[n], Pool(workers=n, progress=False)).table() for n in (1, 2))
    pd.testing.assert_frame_equal(one.drop(columns=list(VOLATILE)), two.drop(columns=list(VOLATILE)), check_exact=True)
    for key in one["key"]:
        assert stores[1].history_path(key).read_bytes() == stores[2].history_path(key).read_bytes()
        a, b = (store.load(key) for store in stores.values())
        assert {k: v for k, v in a.items() if k not in VOLATILE} == {k: v for k, v in b.items() if k not in VOLATILE}


def test_blas_threads_do_not_change_the_bits(tmp_path):
    outputs = []
    for threads in ("1", "2"):
        env = dict(os.environ, OMP_NUM_THREADS=threads, OPENBLAS_NUM_THREADS=threads, MKL_NUM_THREADS=threads)
        out = tmp_path / f"threads{threads}"
        done = subprocess.run(
            _cli("run", TEST2, *_sets(TINY + ["impact.attack_angle=3", "numerics.time_limit=0.01"]), "--out", str(out)),
            capture_output=True,
            text=True,
            timeout=300,
            env=env,
        )
        assert done.returncode == 0, done.stderr
        summary = json.loads((out / "summary.json").read_text())
        outputs.append(((out / "history.csv").read_bytes(), {k: v for k, v in summary.items() if k not in VOLATILE}))
    assert outputs[0] == outputs[1]


# ---------------------------------------------------------------------------
# scene files are data


PAYLOAD = "__import__('os').system('touch PWNED')"


def test_expressions_in_a_scene_are_text_or_rejected(tmp_path):
    text = scene_path("forrestal_luk_test2").read_text()
    as_number = tmp_path / "number.toml"
    as_number.write_text(text.replace("speed = 280.0", f'speed = "{PAYLOAD}"'))
    os.chdir(tmp_path)
    try:
        with pytest.raises(SceneError, match="impact.speed = .*input should be a valid number"):
            load_scene(as_number)
        with pytest.raises(SceneError, match="target.law: unknown law"):
            load_scene(TEST2, [f'target.law="{PAYLOAD}"'])
        with pytest.raises(SceneError, match="target.law: unknown law"):
            _load_scene(TEST2, {"target.law": PAYLOAD})  # a typed value is used as it is: a name, not code
        # in a label it is just text: the run goes ahead and writes it back verbatim
        labelled = tmp_path / "label.toml"
        labelled.write_text(
            text.replace('name = "forrestal_luk_test2"', f'name = "{PAYLOAD}"').replace(
                'description = "', 'description = "$(touch PWNED) `touch PWNED` '
            )
        )
        done = subprocess.run(
            _cli("run", str(labelled), *_sets(TINY + ["numerics.time_limit=0.002"]), "--out", "out", "--json"),
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert done.returncode == 0, done.stderr
        assert json.loads((tmp_path / "out" / "summary.json").read_text())["scene"] == PAYLOAD
    finally:
        os.chdir(ROOT)
    assert not list(tmp_path.rglob("PWNED"))


def test_nothing_evaluates_or_unpickles_data():
    """No eval, exec, compile, __import__, pickle, marshal, yaml.load, os.system or shell=True in the package."""
    forbidden_calls = {"eval", "exec", "compile", "__import__"}
    forbidden_modules = {"pickle", "marshal", "shelve", "dill", "cloudpickle", "yaml"}
    found = []
    for folder in ("cases", "mesh", "fem_loads", "dynamics"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            tree = ast.parse(path.read_text(), str(path))
            for node in ast.walk(tree):
                where = f"{path.relative_to(ROOT)}:{getattr(node, 'lineno', 0)}"
                if isinstance(node, ast.Call):
                    func = node.func
                    if isinstance(func, ast.Name) and func.id in forbidden_calls:
                        found.append(f"{where} {func.id}()")
                    if (
                        isinstance(func, ast.Attribute)
                        and func.attr in ("system", "popen")
                        and isinstance(func.value, ast.Name)
                        and func.value.id == "os"
                    ):
                        found.append(f"{where} os.{func.attr}()")
                    if any(
                        k.arg == "shell" and not (isinstance(k.value, ast.Constant) and k.value.value is False)
                        for k in node.keywords
                    ):
                        found.append(f"{where} shell=")
                if isinstance(node, (ast.Import, ast.ImportFrom)):
                    names = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
                    found += [f"{where} import {n}" for n in names if n.split(".")[0] in forbidden_modules]
    assert not found, found


# ---------------------------------------------------------------------------
# outputs stay inside the folder given


def test_names_in_a_scene_never_become_paths(tmp_path):
    text = scene_path("forrestal_luk_test2").read_text()
    for i, name in enumerate(["../../escape", "/tmp/escape", "..", "a/b", "C:\\\\x"]):
        scene = tmp_path / f"s{i}" / "scene.toml"
        scene.parent.mkdir()
        scene.write_text(
            text.replace('name = "forrestal_luk_test2"', f'name = "{name}"').replace(
                'name = "Forrestal-Luk 95.2 mm, CRH 3.0"', f'name = "{name}"'
            )
        )
        out = scene.parent / "out"
        write_outputs(run_scene(load_scene(scene, TINY + ["numerics.time_limit=0.001"])), out)
        assert sorted(p.name for p in scene.parent.rglob("*")) == ["history.csv", "out", "scene.toml", "summary.json"]
        assert sorted(p.name for p in out.iterdir()) == ["history.csv", "summary.json"]
    assert not (tmp_path.parent / "escape").exists() and not Path("/tmp/escape").exists()


def test_run_store_files_are_named_by_digest_only(tmp_path):
    store = RunStore(tmp_path / "store")
    assert not store.root.exists()  # made by the first save, not by a failing command
    sweep = _sweep(TINY + ["numerics.time_limit=0.001", 'name="../../x"'], grid({"impact.speed": [250, 260]}))
    run_sweep(sweep, store, Pool(workers=1, progress=False))
    files = sorted(p for p in tmp_path.rglob("*") if p.is_file())
    names = [p.name for p in files]
    assert len(names) == 4 and all(re.fullmatch(r"[0-9a-f]{24}\.(json|csv\.gz)", n) for n in names), names
    assert all(p.parent == tmp_path / "store" / "run" for p in files)
    for path in (tmp_path / "store" / "run").glob("*.csv.gz"):  # undefined cells empty, as in history.csv
        text = gzip.decompress(path.read_bytes()).decode()
        assert not re.search(r"(?i)\b(nan|inf)\b", text) and ",\n" in text
    for key in ["../x", "/etc/passwd", "a/b", "a\\b", ".hidden", "", "a\x00b", "a\nb"]:  # any key: a digest
        for path in (store.record_path(key), store.history_path(key)):
            assert path.parent == tmp_path / "store" / "run" and re.fullmatch(
                r"[0-9a-f]{24}\.(json|csv\.gz)", path.name
            )
    with pytest.raises(InputError, match="must be a folder"):
        RunStore(files[0])


def test_output_files_get_the_usual_permissions(tmp_path):
    old = os.umask(0o022)
    try:
        write_outputs(run_scene(load_scene(TEST2, TINY + ["numerics.time_limit=0.001"])), tmp_path)
    finally:
        os.umask(old)
    for name in ("summary.json", "history.csv"):
        assert (tmp_path / name).stat().st_mode & 0o777 == 0o644


def test_json_outputs_hold_no_nan(tmp_path):
    """``history.csv`` leaves undefined cells empty; summary.json and the store have null, never NaN."""
    write_outputs(run_scene(load_scene(TEST2, TINY + ["numerics.time_limit=0.001"])), tmp_path)

    def refuse(name):
        raise AssertionError(name)

    summary = json.loads((tmp_path / "summary.json").read_text(), parse_constant=refuse)
    assert all(math.isfinite(v) for v in summary.values() if isinstance(v, float))
    assert "nan" not in (tmp_path / "history.csv").read_text().lower()
