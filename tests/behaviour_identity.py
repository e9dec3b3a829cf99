"""Check that a change of structure changed no result: every shipped scene and a family sweep, byte for byte.

Usage (from the repository root)::

    .venv/bin/python tests/behaviour_identity.py --against REV [--skip-sweep] [--scenes NAME,...]

Runs, in this checkout and in a ``git worktree`` of ``REV`` (a commit, branch or tag):

* every shipped scene (``cases/*.toml``) as shipped, with ``penetrate run SCENE --out DIR``,
  and compares the ``history.csv`` files byte for byte, and ``summary.json`` without its two
  timings (``wall_time``, ``integration_time``);
* the 72-run sweep of the 155 mm family (the paper's projectiles #1-#4, six impact speeds,
  the three disturbances of ``docs/performance/disturbances.toml``, the study numerics) with
  ``penetrate sweep ... --out table.csv``, and compares the tables without the timing columns.

Both sides run with the same interpreter and an empty mesh cache of their own; the other
side's code is imported from its worktree (``PYTHONPATH`` comes before the editable install).
The outputs of ``REV`` are kept under ``runs/identity/<commit>/`` and reused, so checking
again after an edit runs only this checkout.  Exit code 0 when everything is identical, 1
otherwise; the table printed says which file differs.

This is a command, not a test: it takes a few minutes (the sweep alone about 40 s a side on
two cores).  Use it for every change that should not change behaviour.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
VOLATILE = ("wall_time", "integration_time")
FAMILY_SWEEP = [
    "sweep",
    "cases/paper_p3.toml",
    "--set",
    "numerics.mesh_size=0.02",
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
CLI = "import sys; from cases.cli import main; sys.exit(main(sys.argv[1:]))"


def _git(*args: str, cwd: Path = ROOT) -> str:
    return subprocess.run(["git", *args], cwd=cwd, check=True, capture_output=True, text=True).stdout.strip()


def _penetrate(checkout: Path, cache: Path, args: list[str]) -> None:
    """``penetrate ARGS`` with the code of ``checkout``, run from inside it."""
    env = dict(os.environ, PYTHONPATH=str(checkout), PENETRATE_CACHE_DIR=str(cache))
    done = subprocess.run([sys.executable, "-c", CLI, *args], cwd=checkout, env=env, capture_output=True, text=True)
    if done.returncode not in (0, 1):
        raise SystemExit(f"penetrate {' '.join(args)} in {checkout} failed ({done.returncode}):\n{done.stderr}")


def _scenes(checkout: Path) -> list[str]:
    return sorted(p.stem for p in (checkout / "cases").glob("*.toml"))


def produce(checkout: Path, out: Path, scenes: list[str], sweep: bool) -> None:
    """Run the scenes (and the sweep) with the code of ``checkout``; outputs under ``out``."""
    with tempfile.TemporaryDirectory(prefix="identity-cache-") as cache:
        for name in scenes:
            if (out / name / "history.csv").exists():
                continue
            print(f"  {checkout.name}: {name}", file=sys.stderr, flush=True)
            _penetrate(checkout, Path(cache), ["run", f"cases/{name}.toml", "--out", str(out / name)])
        if sweep and not (out / "family_sweep.csv").exists():
            print(f"  {checkout.name}: family sweep (72 runs)", file=sys.stderr, flush=True)
            store = Path(cache) / "store"
            _penetrate(
                checkout, Path(cache), [*FAMILY_SWEEP, "--store", str(store), "--out", str(out / "family_sweep.csv")]
            )


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()[:16] if path.exists() else "missing"


def _summary(path: Path) -> dict | None:
    if not path.exists():
        return None
    record = json.loads(path.read_text())
    return {k: v for k, v in record.items() if k not in VOLATILE}


def _table(path: Path) -> list[dict] | None:
    if not path.exists():
        return None
    rows = list(csv.DictReader(io.StringIO(path.read_text())))
    return [{k: v for k, v in row.items() if k not in VOLATILE} for row in rows]


HEADLINE = ("depth", "path_length", "axis_angle_change", "max_attack_angle", "final_time")


def _relative(a, b) -> float:
    try:
        a, b = float(a), float(b)
    except (TypeError, ValueError):
        return 0.0 if a == b else float("inf")
    if a == b:
        return 0.0
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


def _worst(a: dict | None, b: dict | None) -> tuple[float, str]:
    """The largest relative change of the headline numbers of a summary or a table row, and its name."""
    if a is None or b is None:
        return float("inf"), "missing"
    return max(((_relative(a.get(k), b.get(k)), k) for k in HEADLINE if k in a), default=(0.0, ""))


def _how_different(a: dict | None, b: dict | None) -> str:
    change, name = _worst(a, b)
    if change == 0.0 and a is not None and b is not None:
        return "in " + ", ".join(sorted(k for k in a.keys() | b.keys() if a.get(k) != b.get(k)))
    return f"largest change {name} {change:.1e}"


def compare(before: Path, after: Path, scenes: list[str], sweep: bool) -> bool:
    """Print one line per compared file (how much a different one changed); True when all are identical."""
    same = True
    print(f"{'output':44} {'before':16} {'after':16} result")
    for name in scenes:
        a, b = before / name / "history.csv", after / name / "history.csv"
        identical = a.exists() and a.read_bytes() == b.read_bytes() if b.exists() else False
        same &= identical
        print(
            f"{name + '/history.csv':44} {_digest(a):16} {_digest(b):16} "
            f"{'byte-identical' if identical else 'DIFFERENT'}"
        )
        sa, sb = _summary(before / name / "summary.json"), _summary(after / name / "summary.json")
        same &= sa == sb
        print(
            f"{name + '/summary.json (no timings)':44} {'':16} {'':16} "
            f"{'identical' if sa == sb else 'DIFFERENT: ' + _how_different(sa, sb)}"
        )
    if sweep:
        a, b = _table(before / "family_sweep.csv"), _table(after / "family_sweep.csv")
        identical = a is not None and a == b
        same &= identical
        rows = len(a) if a else 0
        result = "identical"
        if not identical:
            changed = [(ra, rb) for ra, rb in zip(a or [], b or []) if ra != rb]
            change, name = max((_worst(ra, rb) for ra, rb in changed), default=(float("inf"), "missing"))
            result = f"DIFFERENT: {len(changed)} rows, largest change {name} {change:.1e}"
        print(f"{'family_sweep.csv (no timing columns)':44} {f'{rows} rows':16} {'':16} {result}")
    return same


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--against", required=True, metavar="REV", help="the commit to compare with")
    parser.add_argument("--scenes", help="comma-separated shipped scene names (default: all)")
    parser.add_argument("--skip-sweep", action="store_true", help="compare the shipped scenes only")
    args = parser.parse_args(argv)
    commit = _git("rev-parse", args.against)
    scenes = args.scenes.split(",") if args.scenes else _scenes(ROOT)
    sweep = not args.skip_sweep
    before = ROOT / "runs" / "identity" / commit
    worktree = Path(tempfile.mkdtemp(prefix="identity-worktree-")) / commit[:12]
    try:
        if not all((before / s / "history.csv").exists() for s in scenes) or (
            sweep and not (before / "family_sweep.csv").exists()
        ):
            _git("worktree", "add", "--detach", str(worktree), commit)
            produce(worktree, before, scenes, sweep)
        with tempfile.TemporaryDirectory(prefix="identity-after-") as after:
            produce(ROOT, Path(after), scenes, sweep)
            print(
                f"this checkout ({_git('rev-parse', '--short', 'HEAD')}"
                f"{' + uncommitted changes' if _git('status', '--porcelain', '--untracked-files=no') else ''})"
                f" against {commit[:12]}:"
            )
            same = compare(before, Path(after), scenes, sweep)
    finally:
        if worktree.exists():
            _git("worktree", "remove", "--force", str(worktree))
        shutil.rmtree(worktree.parent, ignore_errors=True)
    print("all identical" if same else "DIFFERENCES FOUND")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
