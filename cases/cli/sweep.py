"""``penetrate sweep SCENE --grid KEY=VALUES ...``: variations of a scene in parallel, resumable."""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from typing import TYPE_CHECKING, Any

from .options import Parser, add_scene_options, overrides, print_json, study, study_parser, table_records

if TYPE_CHECKING:
    import pandas as pd

    from ..studies import SweepResult

__all__ = ["register"]

SHOWN = ("end_reason", "depth", "path_length", "max_attack_angle", "axis_angle_change", "final_speed", "error")


def register(commands: argparse._SubParsersAction[Parser]) -> None:
    parser = study_parser(
        commands,
        "sweep",
        "run variations of a scene in parallel (resumable)",
        "sweep.csv (a row per run) and sweep.md",
        subject=_subject,
    )
    parser.set_defaults(handler=sweep)


def _subject(parser: Parser) -> None:
    """The base scene and the variations: a grid over scene keys and a list of override sets."""
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


def sweep(args: argparse.Namespace) -> int:
    from ..run import RunStore
    from ..studies import Sweep, Variation, grid, parse_grid, read_variations, run_sweep
    from ..studies.engine.report import Report, write_report

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
    shown, notes = _shown(table, result, columns)
    write_report(args.out, Report("sweep", _markdown(args.scene, shown, notes), table))
    if args.json:
        print_json({"rows": table_records(table)})
    else:
        print("\n".join([shown.to_string(index=False), *notes]))
    failed = [i for i, run in enumerate(result.runs) if run.failed]
    if failed:
        print(
            _failure_line(args, result.sweep.variations[failed[0]].values, len(failed), len(result.runs)),
            file=sys.stderr,
        )
        return 1
    return 0


def _shown(table: pd.DataFrame, result: SweepResult, columns: dict) -> tuple[pd.DataFrame, list[str]]:
    """The shown table: the varied keys, the headline figures, and each run's end with its warnings marked; and
    the warnings' notes the marks point to (sweep.csv and ``--json`` hold the warnings' texts per run)."""
    from ..studies import end_cells

    ends, notes = end_cells(
        [(run.summary.end_reason, run.summary.warnings) if run.summary else ("failed", []) for run in result.runs]
    )
    shown = table[[c for c in (*columns, *SHOWN) if c in table]].copy()
    shown["end_reason"] = ends
    return shown, [f"[{i}] {note}" for i, note in enumerate(notes, 1)]


def _markdown(scene: str, shown: pd.DataFrame, notes: list[str]) -> str:
    """sweep.md: the shown table in Markdown, its notes below."""
    from ..studies.engine.report import markdown_table, number_cell

    rows = [[number_cell(v) for v in row] for row in shown.itertuples(index=False)]
    lines = [f"# penetrate sweep {scene}", "", *markdown_table(list(shown.columns), rows), "", *notes]
    return "\n".join(lines) + "\n"


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
