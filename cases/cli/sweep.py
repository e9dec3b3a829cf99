"""``penetrate sweep SCENE --grid KEY=VALUES ...``: variations of a scene in parallel, resumable."""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from typing import TYPE_CHECKING, Any

from .options import Parser, add_pool_options, add_scene_options, out_file, overrides, print_json, study, table_records

if TYPE_CHECKING:
    import pandas as pd

    from ..studies import SweepResult

__all__ = ["register"]

SHOWN = ("end_reason", "depth", "path_length", "max_attack_angle", "axis_angle_change", "final_speed", "error")


def register(commands: argparse._SubParsersAction[Parser]) -> None:
    parser = commands.add_parser("sweep", help="run variations of a scene in parallel (resumable)")
    add_scene_options(parser, "the base scene TOML file")
    parser.add_argument(
        "--grid",
        action="append",
        default=[],
        metavar="KEY=VALUES",
        help="vary a key over V1,V2,... or START:STOP:STEP (inclusive); several --grid"
        " options make a cartesian product",
    )
    parser.add_argument(
        "--list",
        metavar="FILE",
        help="a TOML file of [[run]] tables of dotted keys, one run each (with --grid: their product)",
    )
    add_pool_options(parser, "runs/store")
    parser.add_argument("--out", type=out_file, metavar="FILE", help="write the results table as CSV")
    parser.add_argument(
        "--json", action="store_true", help='print the result as one JSON object: {"rows": [one record per run]}'
    )
    parser.set_defaults(handler=sweep)


def sweep(args: argparse.Namespace) -> int:
    from ..run import RunStore, atomic_write_text
    from ..studies import Sweep, Variation, grid, parse_grid, read_variations, run_sweep

    parameters = dict(parse_grid(text) for text in args.grid)
    variations = grid(parameters) if parameters else [Variation({})]
    columns = dict.fromkeys(parameters)  # the keys varied, shown first, in order
    if args.list:
        # a list and a grid combine as their product
        listed = read_variations(args.list)
        variations = [Variation({**g.values, **v.values}) for g in variations for v in listed]
        for v in listed:
            columns.update(dict.fromkeys(v.values))
    with study(args) as pool:
        result = run_sweep(Sweep.from_file(args.scene, overrides(args), variations), RunStore(args.store), pool)
    table = result.table()
    if args.out:
        atomic_write_text(args.out, table.to_csv(index=False))
    if args.json:
        print_json({"rows": table_records(table)})
    else:
        print(_shown(table, result, columns))
    failed = [i for i, run in enumerate(result.runs) if run.failed]
    if failed:
        print(
            _failure_line(args, result.sweep.variations[failed[0]].values, len(failed), len(result.runs)),
            file=sys.stderr,
        )
        return 1
    return 0


def _shown(table: pd.DataFrame, result: SweepResult, columns: dict) -> str:
    """The printed table: the varied keys, the headline figures, and each run's end with its warnings marked
    and listed below (``--out`` and ``--json`` hold the warnings' texts per run)."""
    from ..studies import end_cells

    ends, notes = end_cells(
        [(run.summary.end_reason, run.summary.warnings) if run.summary else ("failed", []) for run in result.runs]
    )
    shown = table[[c for c in (*columns, *SHOWN) if c in table]].copy()
    shown["end_reason"] = ends
    lines = [shown.to_string(index=False)]
    lines += [f"[{i}] {note}" for i, note in enumerate(notes, 1)]
    return "\n".join(lines)


def _failure_line(args: argparse.Namespace, values: dict, failed: int, runs: int) -> str:
    """One line for a sweep with failed runs: how many, and the command that shows the first one's traceback
    (the store keeps only its error message)."""
    sets = [*args.set, *(f"{key}={_toml(value, top=True)}" for key, value in values.items())]
    command = " ".join(["penetrate --debug run", shlex.quote(args.scene), *(f"--set {shlex.quote(s)}" for s in sets)])
    every = "every run" if failed == runs else f"{failed} of {runs} runs"
    return f"penetrate sweep: {every} failed (the error column says why): {command} shows the first one's traceback"


def _toml(value: bool | float | str | dict[str, Any] | list[Any] | tuple[Any, ...], top: bool = False) -> str:
    """A value as ``--set`` reads it back (a TOML value; a bare word at the top, as the command line writes one)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return value if top and value.isidentifier() and value not in ("true", "false") else json.dumps(value)
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {_toml(v)}" for k, v in value.items()) + "}"
    return "[" + ", ".join(_toml(v) for v in value) + "]"
