"""A/B timing of this checkout against another commit, alternating, through the command line.

Usage (from the repository root)::

    .venv/bin/python tests/benchmarks/ab.py --against REV [--repeats N] [--skip-sweep]

Each workload runs ``N`` times with each code, alternating (A B A B ...), so that a change of the
machine's speed during the measurement falls on both alike; it prints the medians, the spreads and
the ratio of the medians (this checkout / REV).  Both sides use the same interpreter, each its own
warm mesh cache (filled before timing); the other side's code is imported from a ``git worktree``.

Workloads: ``penetrate run`` of the shipped test 2 (the whole process: start-up, imports, the run),
#3 at 900 m/s on a 20 mm mesh with RK4 (the whole process, and the integration time the run reports),
#3 at 1120 m/s on a 20 mm mesh as the scene integrates it (the whole process: mostly start-up), and
the 72-run family sweep of docs/performance.md (study numerics, every core, a fresh run store each
time).  Workloads go through the command line because it is the interface both versions share.

``--pair NAME::REV_ARGS::THIS_ARGS`` (repeatable) adds a ``penetrate run ... --json`` workload whose
arguments differ between the sides (say, the numerics each needs for the same accuracy); it reports
the integration time the runs report.  ``--process-pair NAME::REV_ARGS::THIS_ARGS`` adds a whole
``penetrate`` command (its arguments, the command first) timed as a process; a study command gets a
fresh ``--store`` each time (from an empty run store).  ``--only-pairs`` skips the fixed workloads.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CLI = "import sys; from cases.cli import main; sys.exit(main(sys.argv[1:]))"
# RK4 named explicitly, so that both sides do the same work whatever their scenes' default integrator
P3_900 = [
    "run",
    "cases/paper_p3.toml",
    "--set",
    "numerics.mesh_size=0.02",
    "--set",
    "numerics.integrator=rk4",
    "--set",
    "impact.speed=900",
    "--json",
]
P3_1120 = ["run", "cases/paper_p3.toml", "--set", "impact.speed=1120", "--set", "numerics.mesh_size=0.02", "--json"]
TEST2 = ["run", "cases/forrestal_luk_test2.toml", "--json"]
FAMILY = [
    "sweep",
    "cases/paper_p3.toml",
    "--set",
    "numerics.mesh_size=0.02",
    "--set",
    "numerics.integrator=rk4",
    "--set",
    "numerics.time_step=2e-5",
    "--list",
    "docs/performance/disturbances.toml",
    "--grid",
    "projectile.centre_of_mass_ratio=0.4448,0.5042,0.5636,0.6230",
    "--grid",
    "impact.speed=700:1200:100",
    "--no-progress",
]


def _study_commands() -> set[str]:
    """The commands that keep their runs in a store (those that take ``--store``), from this checkout's parser:
    each gets a fresh store, so that a study is timed from an empty one."""
    from cases.cli import build_parser

    commands = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    return {name for name, sub in commands.items() if any("--store" in a.option_strings for a in sub._actions)}


STUDIES = _study_commands()


def _timed(checkout: Path, cache: Path, args: list[str]) -> tuple[float, dict | None]:
    env = dict(os.environ, PYTHONPATH=str(checkout), PENETRATE_CACHE_DIR=str(cache))
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", CLI, *args], cwd=checkout, env=env, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(args)} in {checkout} failed:\n{done.stderr}")
    try:
        return seconds, json.loads(done.stdout)
    except ValueError:
        return seconds, None


def _row(name: str, a: list[float], b: list[float]) -> str:
    ma, mb = statistics.median(a), statistics.median(b)
    return f"| {name} | {mb:.3f} ({min(b):.3f}-{max(b):.3f}) | {ma:.3f} ({min(a):.3f}-{max(a):.3f}) | {ma / mb:.3f} |"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--against", required=True, metavar="REV")
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--skip-sweep", action="store_true")
    parser.add_argument(
        "--pair",
        action="append",
        default=[],
        metavar="NAME::REV_ARGS::THIS_ARGS",
        help="a run whose arguments differ between the sides (integration time compared)",
    )
    parser.add_argument(
        "--process-pair",
        action="append",
        default=[],
        metavar="NAME::REV_ARGS::THIS_ARGS",
        help="a whole penetrate command whose arguments differ between the sides (process time"
        " compared; a study command gets a fresh --store each time)",
    )
    parser.add_argument("--only-pairs", action="store_true", help="only the --pair and --process-pair workloads")
    args = parser.parse_args(argv)
    commit = subprocess.run(
        ["git", "rev-parse", args.against], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout.strip()
    work = Path(tempfile.mkdtemp(prefix="ab-"))
    other = work / commit[:12]
    subprocess.run(
        ["git", "worktree", "add", "--detach", str(other), commit], cwd=ROOT, check=True, capture_output=True
    )
    sides = {"this": (ROOT, work / "cache-this"), "rev": (other, work / "cache-rev")}
    try:
        workloads = (
            {}
            if args.only_pairs
            else {
                "penetrate run test 2 (process, s)": TEST2,
                "penetrate run #3 900 m/s 20 mm (process, s)": P3_900,
                "penetrate run #3 1120 m/s 20 mm (process, s)": P3_1120,
            }
        )
        pairs = {}
        for text in args.pair:
            name, rev_args, this_args = text.split("::")
            pairs[f"{name} (integration, s)"] = {
                "rev": ["run", *rev_args.split(), "--json"],
                "this": ["run", *this_args.split(), "--json"],
            }
        processes = {}
        for text in args.process_pair:
            name, rev_args, this_args = text.split("::")
            processes[f"{name} (process, s)"] = {"rev": rev_args.split(), "this": this_args.split()}
        stores = iter(range(1_000_000))

        def fresh_store(command: list[str]) -> list[str]:
            if command[0] in STUDIES:
                return [*command, "--store", str(work / f"store-{next(stores)}")]
            return command

        for side, (checkout, cache) in sides.items():  # warm the caches
            for command in [*workloads.values(), *(pair[side] for pair in [*pairs.values(), *processes.values()])]:
                _timed(checkout, cache, fresh_store(command))
        times = {name: {"this": [], "rev": []} for name in [*workloads, *pairs, *processes]}
        if not args.only_pairs:
            times["#3 900 m/s: integration (s)"] = {"this": [], "rev": []}
        for _ in range(args.repeats):
            for side, (checkout, cache) in sides.items():
                for name, command in workloads.items():
                    seconds, record = _timed(checkout, cache, command)
                    times[name][side].append(seconds)
                    if command is P3_900:
                        times["#3 900 m/s: integration (s)"][side].append(record["integration_time"])
                for name, pair in pairs.items():
                    times[name][side].append(_timed(checkout, cache, pair[side])[1]["integration_time"])
                for name, pair in processes.items():
                    times[name][side].append(_timed(checkout, cache, fresh_store(pair[side]))[0])
        if not args.skip_sweep and not args.only_pairs:
            name = "72-run family sweep (s)"
            times[name] = {"this": [], "rev": []}
            for _ in range(max(3, args.repeats // 2)):
                for side, (checkout, cache) in sides.items():
                    store = work / f"store-{side}-{len(times[name][side])}"
                    times[name][side].append(_timed(checkout, cache, [*FAMILY, "--store", str(store)])[0])
        print(f"this checkout against {commit[:12]}, {args.repeats} alternating repeats (medians, spread):")
        print(f"| workload | {commit[:12]} | this checkout | ratio |")
        print("|---|---|---|---|")
        for name, result in times.items():
            print(_row(name, result["this"], result["rev"]))
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(other)], cwd=ROOT, capture_output=True)
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
