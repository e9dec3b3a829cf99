"""``penetrate formulas SCENE``: the field's empirical equations for a scene's projectile, speed and concrete."""

from __future__ import annotations

import argparse

from .options import Parser, overrides, print_json, study_parser

__all__ = ["register"]


def register(commands: argparse._SubParsersAction[Parser]) -> None:
    from ..reference.empirical import NDRC_NOSE_FACTORS

    parser = study_parser(
        commands,
        "formulas",
        "the empirical penetration equations for a scene (Young, NDRC, ACE, UKAEA, Li and Chen)",
        "formulas.md and formulas.json",
        full_runs=False,
    )
    parser.add_argument(
        "--ndrc-nose",
        choices=tuple(NDRC_NOSE_FACTORS),
        help="the NDRC's kind of nose (default: from the scene's nose; a measured nose needs it)",
    )
    parser.add_argument(
        "--reinforcement",
        type=float,
        default=0.0,
        metavar="PERCENT",
        help="volume percentage of reinforcing steel, for Young's S-number of concrete (default 0)",
    )
    parser.set_defaults(handler=formulas)


def formulas(args: argparse.Namespace) -> int:
    from ..scene import InputError, load_scene
    from ..studies.engine.report import write_report
    from ..studies.measured.formulas import formulas as evaluate
    from ..studies.measured.formulas import formulas_report

    if not 0.0 <= args.reinforcement < 11.0:
        raise InputError(f"--reinforcement = {args.reinforcement:g}: allowed 0 <= PERCENT < 11")
    scene = load_scene(args.scene, overrides(args))
    result = evaluate(scene, args.ndrc_nose, args.reinforcement)
    report = formulas_report(result, scene.name or args.scene)
    write_report(args.out, report)
    if args.json:
        print_json(result.as_dict())
    else:
        print(report.markdown, end="")
    return 0
