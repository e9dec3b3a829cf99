"""``penetrate fit``: numeric scene keys fitted to observed quantities (bounded least squares)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from .options import (
    Parser,
    add_pool_options,
    add_scene_options,
    out_folder,
    overrides,
    positive_float,
    positive_int,
    study,
)

__all__ = ["register"]


def register(commands: argparse._SubParsersAction[Parser]) -> None:
    parser = commands.add_parser("fit", help="fit numeric scene keys to observed quantities (least squares)")
    add_scene_options(parser)
    add_pool_options(parser, "runs/store")
    parser.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="KEY=LO:HI",
        help="a numeric scene key to fit within its bounds, e.g. target.law.B=0.3:3 (repeatable)",
    )
    parser.late_help(
        parser.add_argument(
            "--observe",
            action="append",
            default=[],
            metavar="[SCENE:]QUANTITY=VALUE[+-SIGMA]",
            help="an observed quantity of a run or a study, of this scene or of SCENE (repeatable)",
        ),
        observe_help,
    )
    parser.add_argument(
        "--resolution",
        type=positive_float,
        default=5.0,
        metavar="M/S",
        help="resolution of a critical-speed search (default 5 m/s)",
    )
    parser.add_argument(
        "--step",
        type=positive_float,
        metavar="FRACTION",
        help="forward-difference step as a fraction of each range (default 1e-3; 0.05 when a"
        " characteristic speed is observed)",
    )
    parser.add_argument(
        "--max-evaluations", type=positive_int, default=30, metavar="N", help="model evaluations at most (default 30)"
    )
    parser.add_argument(
        "--out",
        type=out_folder,
        default="runs/fit",
        metavar="DIR",
        help="where to write fit.md, fit.json and fit.png (default runs/fit)",
    )
    parser.add_argument("--json", action="store_true", help="print the result as one JSON object")
    parser.set_defaults(handler=run_fit)


def observe_help() -> str:
    """``--observe``'s help: every quantity the fit takes, from its own tables."""
    from ..studies.fit import RUN_QUANTITIES, STUDY_QUANTITIES

    return (
        f"an observed quantity of a run ({', '.join(RUN_QUANTITIES)}) or a study ({', '.join(STUDY_QUANTITIES)}),"
        " of this scene or of SCENE (repeatable); with +-SIGMA its standard deviation"
    )


def run_fit(args: argparse.Namespace) -> int:
    import sys

    from ..run import RunStore
    from ..scene import one_line
    from ..studies.fit import NotIdentifiable, fit, write_report

    if args.step is not None and not args.step < 1:
        from ..scene import InputError

        raise InputError(f"--step {args.step:g}: must be below 1 (a fraction of each parameter's range)")
    try:
        with study(args) as pool:
            result = fit(
                args.scene,
                overrides(args),
                args.param,
                args.observe,
                RunStore(args.store),
                pool,
                resolution=args.resolution,
                step=args.step,
                max_evaluations=args.max_evaluations,
            )
    except NotIdentifiable as exc:
        print(f"penetrate fit: {one_line(exc)}", file=sys.stderr)
        return 1
    write_report(result, Path(args.out), args.scene)
    if args.json:
        print(json.dumps(result.record()))
    else:
        print((Path(args.out) / "fit.md").read_text(), end="")
    return 0
