"""``penetrate ensemble SCENE --sample KEY=DIST ... -n N``: outcome probabilities under sampled impact conditions."""

from __future__ import annotations

import argparse
from pathlib import Path

from .options import Parser, add_scene_options, overrides, positive_int, print_json, study, study_parser

__all__ = ["register"]


def register(commands: argparse._SubParsersAction[Parser]) -> None:
    parser = study_parser(
        commands,
        "ensemble",
        "Monte Carlo: the probability of each outcome under sampled impact conditions (resumable)",
        "ensemble.md, .csv, .json and the figures",
        lambda parser: add_scene_options(parser, "the base scene TOML file"),
    )
    parser.late_help(
        parser.add_argument(
            "--sample", action="append", default=[], metavar="KEY=DIST", help="sample a numeric scene key"
        ),
        sample_help,
    )
    parser.add_argument("-n", dest="count", type=positive_int, required=True, metavar="N", help="how many runs")
    parser.add_argument("--seed", type=int, default=0, help="the seed of the samples (default 0)")
    parser.add_argument(
        "--design",
        choices=("random", "sobol", "lhs"),
        default="random",
        help="independent random samples, a scrambled Sobol' sequence or a Latin hypercube"
        " (default random; lhs cannot be extended by a larger -n)",
    )
    parser.add_argument(
        "--by",
        metavar="KEY=START:STOP:STEP",
        help="the probabilities in bins of a sampled key (the last bin ends at STOP)",
    )
    parser.add_argument(
        "--fidelity",
        choices=("full", "multi"),
        default="full",
        help="full (default): a full run per sample; multi: the reduced model sorts every sample and --full-runs"
        " full runs measure each sort, near the stability boundary and an audit elsewhere (unbiased;"
        " docs/ensembles.md)",
    )
    parser.add_argument(
        "--full-runs",
        type=positive_int,
        default=1024,
        metavar="N",
        help="how many full runs a multi-fidelity ensemble makes (default 1024)",
    )
    parser.set_defaults(handler=ensemble)


def sample_help() -> str:
    """``--sample``'s help: every distribution the study takes, from its own table."""
    from ..studies.ensemble.sampling import FORMS

    forms = list(FORMS.values())
    return (
        f"sample a numeric scene key: {', '.join(forms[:-1])} or {forms[-1]} (repeatable, one per key;"
        " docs/ensembles.md)"
    )


def ensemble(args: argparse.Namespace) -> int:
    from ..run import RunStore
    from ..studies.ensemble.study import run_ensemble

    with study(args) as pool:
        record = run_ensemble(
            args.scene,
            overrides(args),
            args.sample,
            args.count,
            RunStore(args.store),
            args.out,
            seed=args.seed,
            design=args.design,
            by=args.by,
            pool=pool,
            fidelity=args.fidelity,
            full_runs=args.full_runs,
        )
    if args.json:
        print_json(record)
    else:
        print((Path(args.out) / "ensemble.md").read_text())
    return 0
