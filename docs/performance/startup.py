"""Where the start of a `penetrate run` goes: import time by group, from ``python -X importtime``.

Usage (from the repository root; a few seconds)::

    .venv/bin/python -m docs.performance.startup [--repeats 7]

Runs ``penetrate run cases/forrestal_luk_test2.toml`` (its projectile cached) ``--repeats`` times
under ``-X importtime`` and sums each module's own import time by group; prints the medians as a
markdown table with the whole process's median wall time, and the stamp line.
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

from docs.measure import stamp

ROOT = Path(__file__).resolve().parents[2]

GROUPS = (  # (label, module prefixes); the first that matches takes the module
    ("numpy (all its modules)", ("numpy",)),
    (
        "pydantic and its typing helpers",
        ("pydantic", "pydantic_core", "typing_extensions", "annotated_types", "typing_inspection"),
    ),
    ("mesh, fem_loads, dynamics", ("mesh", "fem_loads", "dynamics")),
    ("cases.scene (the scene models)", ("cases.scene",)),
    ("cases.run (the summary model)", ("cases.run",)),
    ("cases.cli and the rest of cases", ("cases",)),
    ("importlib.metadata and what it imports", ("importlib.metadata", "email", "zipfile", "csv", "socket")),
)
LINE = re.compile(r"import time:\s+(\d+) \|\s+\d+ \|(\s*)(\S+)")


def one_run() -> tuple[dict[str, float], float]:
    """Self import time (ms) by group, and the process's wall time (s)."""
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "cases.cli", "run", "cases/forrestal_luk_test2.toml"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    wall = time.perf_counter() - start
    totals = dict.fromkeys([label for label, _ in GROUPS] + ["the rest of the standard library and site"], 0.0)
    for line in done.stderr.splitlines():
        match = LINE.match(line)
        if match is None:
            continue
        self_us, module = int(match.group(1)), match.group(3)
        label = next(
            (label for label, prefixes in GROUPS if any(module == p or module.startswith(p + ".") for p in prefixes)),
            "the rest of the standard library and site",
        )
        totals[label] += self_us / 1e3
    return totals, wall


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args(argv)
    one_run()  # the projectile prepared and cached, the disk warm
    runs = [one_run() for _ in range(args.repeats)]
    print(f"| import group (test 2's `penetrate run`, medians of {args.repeats}) | self time |")
    print("|---|---|")
    labels = list(runs[0][0])
    for label in labels:
        print(f"| {label} | {statistics.median(r[0][label] for r in runs):.1f} ms |")
    print(f"| **all imports** | **{statistics.median(sum(r[0].values()) for r in runs):.1f} ms** |")
    print()
    print(f"The whole process takes a median {statistics.median(r[1] for r in runs):.2f} s.")
    print()
    print(stamp())


if __name__ == "__main__":
    main()
