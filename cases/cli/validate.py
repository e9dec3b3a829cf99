"""``penetrate validate SERIES``: every shot of a test series run, predicted against measured."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .options import SET_HELP, Parser, overrides, print_json, study, study_parser

__all__ = ["register", "SERIES_HELP"]

SERIES_HELP = (
    "a test series: a CSV file of shots, one a row (scene, scene keys, measured.QUANTITY, sigma.QUANTITY, label,"
    " group; docs/series.md), or a shipped series' name"
)


def register(commands: argparse._SubParsersAction[Parser]) -> None:
    parser = study_parser(
        commands,
        "validate",
        "run every shot of a test series: predicted against measured",
        "validate.md, .csv, .json and .png",
        _series_options,
    )
    parser.add_argument(
        "--curve-points",
        type=int,
        default=12,
        metavar="N",
        help="impact speeds of each group's predicted curve (0: none; default %(default)s)",
    )
    parser.add_argument(
        "--formulas",
        action="store_true",
        help="predict each measured depth by the empirical formulas too (penetrate formulas), beside the model",
    )
    parser.set_defaults(handler=validate)


def _series_options(parser: Parser) -> None:
    """What a series is given by: the series itself and the ``--set`` overrides of every shot."""
    parser.add_argument("series", help=SERIES_HELP)
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help=f"{SET_HELP}; on every shot (a column of the series beats it for its own shot)",
    )


def validate(args: argparse.Namespace) -> int:
    from ..run import RunStore
    from ..scene import InputError
    from ..studies.measured.series import read_series
    from ..studies.measured.validate import validate as run_validation
    from ..studies.measured.validate import write_validation

    if not 0 <= args.curve_points <= 1000:
        raise InputError(f"--curve-points {args.curve_points}: must lie in 0..1000")
    series = read_series(args.series)
    with study(args) as pool:
        validation = run_validation(
            series, overrides(args), RunStore(args.store), pool, args.curve_points, args.formulas
        )
    write_validation(validation, args.out)
    if args.json:
        print_json(validation.record())
    else:
        print((Path(args.out) / "validate.md").read_text(), end="")
    return report_failures("validate", validation.failed)


def report_failures(command: str, failed: list[str]) -> int:
    """Exit code 1 and one line naming the shots whose run failed (the table's end column says why); else 0."""
    if not failed:
        return 0
    shown = ", ".join(failed[:5]) + (f" and {len(failed) - 5} more" if len(failed) > 5 else "")
    print(f"penetrate {command}: the runs of {shown} failed (their warnings say why)", file=sys.stderr)
    return 1
