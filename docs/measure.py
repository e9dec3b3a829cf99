"""Measure the timings, memory and counts the documentation quotes.

Each subcommand prints one markdown paragraph (or table) ending in a stamp
line that names the machine and the date; ``docs/regenerate.py`` puts the
output in the page's generated block.  Run from the repository root::

    python -m docs.measure process cases/forrestal_luk_test2.toml --repeat 5
    python -m docs.measure load cases/forrestal_luk_test2.toml
    python -m docs.measure tests
    python -m docs.measure command -- python -m docs.core_checks
    python -m docs.measure command -- penetrate critical cases/paper_p3.toml --store EMPTY_DIR

Wall times are medians over the repeats, memory the peak resident set of the
measured process (``ru_maxrss`` of the child, which counts its whole life).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import re
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
import timeit
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PYTHON = sys.executable


def penetrate_output(arguments: list[str]) -> str:
    """What ``penetrate ARGUMENTS`` prints, run in this process; a command that fails stops the page's script."""
    import contextlib
    import io

    from cases.cli import main

    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        status = main(arguments)
    if status:
        raise SystemExit(f"penetrate {' '.join(arguments)} ended with {status}")
    return printed.getvalue()


def stamp() -> str:
    """The line that says where and when a figure was measured."""
    model, flags = platform.processor() or platform.machine(), set()
    try:
        info = dict(line.split(":", 1) for line in Path("/proc/cpuinfo").read_text().split("\n\n")[0].splitlines())
        info = {key.strip(): value.strip() for key, value in info.items()}
        model, flags = info.get("model name", model), set(info.get("flags", "").split())
    except (OSError, ValueError):
        pass
    # the widest vector instructions: numpy and numba sum in another order with another width, and a run near a
    # threshold can move a printed digit between two processors that share a name (AMD EPYC with and without them)
    vectors = next((name for flag, name in (("avx512f", "AVX-512"), ("avx2", "AVX2")) if flag in flags), "")
    if vectors:
        model = f"{model}, {vectors}"
    today = datetime.date.today().isoformat()
    return f"_measured {today} on {os.cpu_count()} cores ({model}), Python {platform.python_version()}_"


def timed_process(arguments: list[str]) -> tuple[float, float, str]:
    """Wall seconds, peak resident memory (MB) and standard output of one child process."""
    start = time.perf_counter()
    child = subprocess.Popen(arguments, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    output = child.stdout.read()
    _, status, usage = os.wait4(child.pid, 0)
    seconds = time.perf_counter() - start
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"measure: {' '.join(arguments)} failed")
    return seconds, usage.ru_maxrss / 1024.0, output


def process(scene: str, repeat: int, overrides: list[str]) -> None:
    """The whole `penetrate run` process: median wall time and peak memory, mesh cached."""
    import json

    command = [str(Path(PYTHON).with_name("penetrate")), "run", scene, "--json"]
    for text in overrides:
        command += ["--set", text]
    timed_process(command)  # warm: meshes and compiled kernels cached, as a user's second run
    walls, peaks, summary = [], [], {}
    for _ in range(repeat):
        wall, peak, output = timed_process(command)
        walls.append(wall)
        peaks.append(peak)
        summary = json.loads(output)
    shown = " ".join(["penetrate run", scene, *[f"--set {o}" for o in overrides]])
    print(
        f"`{shown}` takes a median {statistics.median(walls):.2f} s wall for the whole process "
        f"({repeat} runs, {min(walls):.2f}-{max(walls):.2f} s; peak memory {statistics.median(peaks):.0f} MB) "
        f"once the mesh is cached; of that, the integration takes {summary['integration_time']:.3f} s "
        f"({summary['steps']} steps, {summary['load_evaluations']} load evaluations) and the rest is Python "
        "start-up, imports and preparing the projectile from its cached mesh."
    )
    print()
    print(stamp())


def load(scene: str) -> None:
    """One load evaluation of the scene's projectile, fully embedded at 3 degrees of attack."""
    import numpy as np

    from cases import load_scene, prepare_projectile
    from cases.run import initial_state
    from dynamics.quaternion import rotation_matrix

    loaded = load_scene(ROOT / scene)
    prepared = prepare_projectile(loaded)
    state = initial_state(loaded, prepared)
    loads = loaded.loads(prepared.quadrature)
    attack = np.radians(3.0)
    velocity = np.linalg.norm(state.velocity) * np.array([np.sin(attack), 0.0, -np.cos(attack)])
    position = state.position + np.array([0.0, 0.0, -(prepared.length + 1.0)])
    args = (position, velocity, rotation_matrix(state.attitude), np.array([0.0, 2.0, 0.0]))
    loads(*args)
    times = np.array(timeit.repeat(lambda: loads(*args), number=200, repeat=9)) / 200 * 1e6
    points = len(prepared.quadrature.weights)
    print(
        f"One load evaluation of `{scene}` over its {format(points, ',').replace(',', ' ')} surface points "
        f"(fully embedded, 3 degrees "
        f"of attack, pitching) takes a median {np.median(times):.0f} us (9 repeats of 200, "
        f"{times.min():.0f}-{times.max():.0f} us)."
    )
    print()
    print(stamp())


def tests() -> None:
    """How many tests the default run and the slow run collect."""
    counts = {}
    for marker in ("not slow", "slow"):
        done = subprocess.run(
            [PYTHON, "-m", "pytest", "--collect-only", "-q", "-m", marker, "-p", "no:cacheprovider"],
            cwd=ROOT,
            capture_output=True,
            text=True,
        )
        match = re.search(r"(\d+)(?:/\d+)? tests? (?:collected|selected)", done.stdout)
        if match is None:
            raise SystemExit(f"measure: pytest collected nothing for -m '{marker}': {done.stdout[-300:]}")
        counts[marker] = int(match.group(1))
    print(
        f"`./dev test` runs the default suite of {counts['not slow']} tests; CI then runs the "
        f"{counts['slow']} slow ones with `./dev test -m slow`."
    )


#: an argument of ``command`` replaced by a fresh empty directory, shown as a
#: user would type it (a temporary path in the page would change on every run)
EMPTY_DIR = "EMPTY_DIR"


def environment() -> None:
    """The disk size of the Python environment ``.venv``, and of VTK in it."""

    def megabytes(path: Path) -> float:
        return sum(f.stat().st_size for f in path.rglob("*") if f.is_file() and not f.is_symlink()) / 1e6

    venv = (ROOT / ".venv").resolve()  # the docs check links it into its copy
    site = next((venv / "lib").glob("python3*/site-packages"))
    vtk = sum(megabytes(site / name) for name in ("vtkmodules", "vtk.libs") if (site / name).exists())
    print(f"Set up, the Python environment `.venv` takes {megabytes(venv):.0f} MB on disk, VTK alone {vtk:.0f} MB.")


def command(arguments: list[str]) -> None:
    """Wall time and peak memory of any command (run once)."""
    with tempfile.TemporaryDirectory(prefix="measure-") as empty:
        wall, peak, _ = timed_process([empty if a == EMPTY_DIR else a for a in arguments])
    # quoted as a shell would need it, so the shown command can be pasted (``-k 'not slow'``)
    shown = " ".join("$(mktemp -d)" if a == EMPTY_DIR else shlex.quote(a) for a in arguments)
    print(f"`{shown}` takes {wall:.0f} s wall and peaks at {peak:.0f} MB resident.")
    print()
    print(stamp())


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="what", required=True)
    p = sub.add_parser("process", help="the whole `penetrate run` process")
    p.add_argument("scene")
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--set", action="append", default=[], dest="overrides")
    p = sub.add_parser("load", help="one load evaluation")
    p.add_argument("scene")
    sub.add_parser("tests", help="the test counts")
    sub.add_parser("environment", help="the disk size of .venv and of VTK in it")
    p = sub.add_parser("command", help="any command's wall time and memory")
    p.add_argument("arguments", nargs=argparse.REMAINDER)
    options = parser.parse_args(argv)
    if options.what == "process":
        process(options.scene, options.repeat, options.overrides)
    elif options.what == "load":
        load(options.scene)
    elif options.what == "tests":
        tests()
    elif options.what == "environment":
        environment()
    else:
        arguments = options.arguments[1:] if options.arguments[:1] == ["--"] else options.arguments
        command(arguments)


if __name__ == "__main__":
    main()
