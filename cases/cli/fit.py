"""``penetrate fit``: numeric scene keys fitted to observed quantities (bounded least squares)."""

from __future__ import annotations

import argparse
from pathlib import Path

from .options import (
    Parser,
    add_scene_options,
    overrides,
    positive_float,
    positive_int,
    print_json,
    renamed,
    study,
    study_parser,
)
from .validate import SERIES_HELP

__all__ = ["register"]


def register(commands: argparse._SubParsersAction[Parser]) -> None:
    parser = study_parser(
        commands,
        "fit",
        "fit numeric scene keys to observed quantities (least squares)",
        "fit.md, fit.json and fit.png",
        lambda parser: add_scene_options(parser, "a scene TOML file (or --series)", optional=True),
    )
    parser.add_argument(
        "--series",
        metavar="SERIES",
        help=f"fit to every measured shot of {SERIES_HELP[2:]} (instead of a scene and --observe)",
    )
    parser.add_argument(
        "--holdout",
        metavar="label=A,B|group=G|fraction=F",
        help="with --series: shots kept out of the fit and predicted with its values, reported apart",
    )
    parser.add_argument(
        "--folds",
        type=int,
        default=0,
        metavar="K",
        help="with --series: also a K-fold cross-validation of the shots fitted (default: none)",
    )
    parser.add_argument(
        "--seed", type=int, default=0, metavar="N", help="draws --holdout fraction= and the folds (default 0)"
    )
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
    renamed(parser, "--step", "--difference-step FRACTION (--step is a Runge-Kutta step wherever it is taken)")
    parser.add_argument(
        "--difference-step",
        type=positive_float,
        metavar="FRACTION",
        help="forward-difference step as a fraction of each range (default 1e-3; 0.05 when a"
        " characteristic speed is observed)",
    )
    parser.add_argument(
        "--max-evaluations", type=positive_int, default=30, metavar="N", help="model evaluations at most (default 30)"
    )
    parser.set_defaults(handler=run_fit)


def observe_help() -> str:
    """``--observe``'s help: every quantity the fit takes, from its own tables."""
    from ..studies.measured.fit import RUN_QUANTITIES, STUDY_QUANTITIES

    return (
        f"an observed quantity of a run ({', '.join(RUN_QUANTITIES)}) or a study ({', '.join(STUDY_QUANTITIES)}),"
        " of this scene or of SCENE (repeatable); with +-SIGMA its standard deviation"
    )


def run_fit(args: argparse.Namespace) -> int:
    import sys

    from ..run import RunStore
    from ..scene import InputError, one_line
    from ..studies.measured.fit import NotIdentifiable, fit, write_fit
    from ..studies.measured.fit_series import fit_series, parse_holdout

    if args.difference_step is not None and not args.difference_step < 1:
        raise InputError(
            f"--difference-step {args.difference_step:g}: must be below 1 (a fraction of each parameter's range)"
        )
    if (args.scene is None) == (args.series is None):
        raise InputError("fit: give a scene file (with --observe) or --series SERIES (one of them)")
    if args.series is None:
        for flag, given in (("--holdout", args.holdout), ("--folds", args.folds)):
            if given:
                raise InputError(f"{flag}: holds shots of a series out; it needs --series")
    elif args.observe:
        raise InputError("--observe: a series gives the observations (its measured columns); drop --observe")
    if args.series is not None and not args.param:
        return _validation_only(args)
    try:
        with study(args) as pool:
            if args.series is not None:
                from ..studies.measured.series import read_series

                holdout = parse_holdout(args.holdout) if args.holdout else None
                series = read_series(args.series)
                result = fit_series(
                    series,
                    overrides(args),
                    args.param,
                    RunStore(args.store),
                    pool,
                    holdout=holdout,
                    folds=args.folds,
                    seed=args.seed,
                    step=args.difference_step,
                    max_evaluations=args.max_evaluations,
                )
                title = Path(series.source).name
            else:
                result = fit(
                    args.scene,
                    overrides(args),
                    args.param,
                    args.observe,
                    RunStore(args.store),
                    pool,
                    resolution=args.resolution,
                    step=args.difference_step,
                    max_evaluations=args.max_evaluations,
                )
                title = args.scene
    except NotIdentifiable as exc:
        print(f"penetrate fit: {one_line(exc)}", file=sys.stderr)
        return 1
    write_fit(result, Path(args.out), title)
    if args.json:
        print_json(result.record())
    else:
        print((Path(args.out) / "fit.md").read_text(), end="")
    if not result.converged:
        print(
            f"penetrate fit: not converged in {args.max_evaluations} evaluations of the model (raise"
            " --max-evaluations); the report shows where it stopped",
            file=sys.stderr,
        )
        return 1
    return 0


def _validation_only(args: argparse.Namespace) -> int:
    """``fit --series`` without ``--param``: nothing to fit, so the series is validated, and the output says so."""
    import sys

    from .validate import validate

    for flag, given in (("--holdout", args.holdout), ("--folds", args.folds)):
        if given:
            from ..scene import InputError

            raise InputError(f"{flag}: without --param nothing is fitted, so nothing is held out (give --param)")
    print(
        "penetrate fit: no --param, so nothing is fitted: this is penetrate validate's report (predictions at the"
        " scenes' own values)",
        file=sys.stderr,
    )
    args.curve_points, args.formulas = 0, False
    return validate(args)
