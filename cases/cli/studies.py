"""``penetrate compare``, ``accuracy``, ``contact``, ``entry`` and ``paper``: studies that write reports."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TYPE_CHECKING

from ..scene import InputError
from .options import (
    Parser,
    add_scene_options,
    law_names,
    overrides,
    positive_float,
    print_json,
    renamed,
    study,
    study_parser,
    table_records,
)
from .speeds import speed_range
from .validate import SERIES_HELP

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["register"]


def register(commands: argparse._SubParsersAction[Parser]) -> None:
    compare = study_parser(
        commands,
        "compare",
        "run a scene, or a test series, under several resistance laws, side by side",
        "compare.md, compare.csv and compare.png (and compare.json with --series)",
        lambda parser: add_scene_options(parser, "a scene TOML file (or --series)", optional=True),
    )
    compare.add_argument("--series", metavar="SERIES", help=f"instead of a scene, {SERIES_HELP}; ranks the laws")
    compare.late_help(
        compare.add_argument("--laws", default="", metavar="A,B,...", help="comma-separated law names"),
        lambda: f"comma-separated law names, of {law_names()}, and scene for the scene's own law (docs/laws.md)",
    )
    compare.add_argument(
        "--law",
        action="append",
        default=[],
        metavar="LABEL=LAW",
        help="a law as target.law takes it, labelled, e.g. 'poly={model=\"polynomial\", c0=1.2e7, c1=3e4, c2=1500}'"
        " or a user's function 'mine={function=\"laws.py:f\", parameters={c0=1e7}}' (repeatable; docs/laws.md)",
    )
    compare.add_argument(
        "--depths-at", metavar="V1,V2,...", help="also measure each law's depth at these impact speeds (m/s)"
    )
    renamed(compare, "--speeds", "--depths-at V1,V2,... (--speeds is a LOW:HIGH search range wherever it is taken)")
    compare.add_argument(
        "--critical", type=speed_range, metavar="LOW:HIGH", help="also seek each law's critical speed in this range"
    )
    compare.add_argument(
        "--resolution", type=positive_float, default=5.0, help="of --critical (m/s, default %(default)s)"
    )
    compare.add_argument("--convergent", action="store_true", help="also measure each law's convergent speed")
    compare.add_argument(
        "--formulas",
        action="store_true",
        help="with --series: rank the empirical formulas' depths with the laws (penetrate formulas)",
    )
    compare.set_defaults(handler=compare_laws)

    accuracy = study_parser(
        commands, "accuracy", "what accuracy costs in time, for a scene", "accuracy.md, .csv and .png"
    )
    accuracy.add_argument(
        "--sizes",
        metavar="M,M,...",
        help="mesh sizes of the mesh axis (default: four halvings from 0.42 diameters, to one significant digit;"
        " 0.04,0.02,0.01,0.005 m for the 95.2 mm Forrestal-Luk projectile)",
    )
    accuracy.add_argument(
        "--steps",
        metavar="S,S,...",
        help="RK4 steps of the time axis (default: six halvings from a 25th of the time the body takes to"
        " travel its own length at the impact speed, to one significant digit; 2e-4,...,6.25e-6 s for test 2)",
    )
    accuracy.add_argument(
        "--rtols",
        default="1e-3,1e-4,1e-5,1e-6",
        metavar="R,R,...",
        help="Dormand-Prince tolerances of the time axis (default 1e-3,1e-4,1e-5,1e-6)",
    )
    accuracy.add_argument(
        "--quadrature-orders",
        default="4,6",
        metavar="Q,Q,...",
        help="facet quadrature degrees beside the default 2, on the mesh-size axis (default 4,6)",
    )
    accuracy.set_defaults(handler=accuracy_study)

    contact = study_parser(
        commands,
        "contact",
        "what the contact incidence changes: a scene down to the sharp law",
        "contact.md and contact.csv",
    )
    contact.late_help(
        contact.add_argument(
            "--incidences",
            default="0.02,0.01,0.005,0.0025,0.00125",
            metavar="D,D,...",
            help="contact incidences beside the sharp law's 0",
        ),
        incidences_help,
    )
    contact.add_argument(
        "--step", type=positive_float, default=2.5e-6, metavar="S", help="the RK4 step of every run (default 2.5e-6 s)"
    )
    contact.set_defaults(handler=contact_incidence_study)

    entry = study_parser(
        commands, "entry", "what the entry smoothing changes, and RK4's time error with it", "entry.md and entry.csv"
    )
    entry.add_argument(
        "--smoothings",
        default="1,2,4,8",
        metavar="E,E,...",
        help="entry smoothings (units of a point's own size; default 1,2,4,8)",
    )
    entry.add_argument(
        "--steps",
        default="1e-4,5e-5,2.5e-5,1.25e-5,6.25e-6,3.125e-6",
        metavar="S,S,...",
        help="RK4 steps; the finest is each smoothing's reference (default 1e-4 ... 3.125e-6 s)",
    )
    entry.set_defaults(handler=entry_smoothing_study)

    paper = study_parser(
        commands,
        "paper",
        "regenerate the paper's study: tables and figures",
        "results.md, results.json and the figures (variants.md, .json and .png with --variants)",
        lambda parser: None,
        out="docs/paper",
        store="runs/paper-store",
    )
    paper.add_argument(
        "--variants", action="store_true", help="the paper's variants instead: friction, conical nose, other soil laws"
    )
    paper.set_defaults(handler=paper_study)


def incidences_help() -> str:
    """``contact --incidences``' help, with every contact option of a scene (from its schema)."""
    from ..scene.target import Effects

    options = ", ".join(f"effects.{name}" for name in Effects().contact_ramp)
    return (
        "values of effects.contact_incidence beside the sharp law's 0, every run with effects.contact_width = 0"
        f" (a scene's contact options: {options}; default %(default)s)"
    )


def compare_laws(args: argparse.Namespace) -> int:
    from ..run import RunStore
    from ..scene import parse_override
    from ..studies.measured.compare import SCENE_LAW
    from ..studies.measured.compare import compare_laws as compare

    if (args.scene is None) == (args.series is None):
        raise InputError("compare: give a scene file or --series SERIES (one of them)")
    laws: list[tuple[str, object]] = [
        (name, None if name == SCENE_LAW else name) for name in (n.strip() for n in args.laws.split(",")) if name
    ]
    for text in args.law:
        label, separator, value = text.partition("=")
        if not separator or not label.strip():
            raise InputError(f"--law {text!r}: expected LABEL=LAW, e.g. 'poly={{model=\"polynomial\", c0=1e7}}'")
        laws.append((label.strip(), parse_override(f"target.law={value}")[1]))
    if not laws:
        raise InputError(f"--laws, --law: give one or more laws, e.g. --laws {SCENE_LAW},soil,softer_soil")
    if len({label for label, _ in laws}) < len(laws):
        raise InputError("--laws, --law: each law needs a label of its own (allowed: distinct names)")
    if args.series is not None:
        return _compare_series(args, laws)
    if args.formulas:
        raise InputError(
            "compare --formulas: ranks the formulas on a test series (--series); for one scene, run penetrate formulas"
        )
    speeds = _numbers("--depths-at", args.depths_at) if args.depths_at else None
    with study(args) as pool:
        comparison = compare(
            args.scene,
            overrides(args),
            laws,
            RunStore(args.store),
            args.out,
            pool,
            speeds=speeds,
            critical=args.critical,
            resolution=args.resolution,
            convergent=args.convergent,
        )
    if args.json:
        record = {"rows": table_records(comparison.table)}
        if comparison.depth_by_speed is not None:
            record["depths_at"] = table_records(comparison.depth_by_speed)
        print_json(record)
        return 0
    out = Path(args.out)
    print((out / "compare.md").read_text())
    print("written        " + ", ".join(str(out / name) for name in ("compare.md", "compare.csv", "compare.png")))
    return 0


def _compare_series(args: argparse.Namespace, laws: list[tuple[str, object]]) -> int:
    from ..run import RunStore
    from ..studies.measured.compare import compare_series
    from ..studies.measured.series import read_series
    from .validate import report_failures

    ignored = [flag for flag, given in (("--depths-at", args.depths_at), ("--critical", args.critical)) if given]
    if args.convergent:
        ignored.append("--convergent")
    if ignored:
        raise InputError(f"compare --series: {', '.join(ignored)} apply to a scene, not to a series (drop them)")
    series = read_series(args.series)
    with study(args) as pool:
        comparison = compare_series(
            series, overrides(args), laws, RunStore(args.store), args.out, pool, with_formulas=args.formulas
        )
    if args.json:
        print_json(comparison.record())
    else:
        out = Path(args.out)
        print((out / "compare.md").read_text())
        print("written        " + ", ".join(str(out / f"compare.{ext}") for ext in ("md", "csv", "json", "png")))
    failed = list(
        dict.fromkeys(f"{row['label']} ({row['law']})" for row in comparison.rows if row["end_reason"] == "failed")
    )
    return report_failures("compare", failed)


def _numbers(option: str, text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if not values or not all(0 < v < math.inf for v in values):
        raise InputError(f"{option} {text!r}: expected comma-separated numbers > 0")
    return values


def accuracy_study(args: argparse.Namespace) -> int:
    from ..run import RunStore
    from ..studies.numerics.accuracy import accuracy_study as accuracy

    orders = _numbers("--quadrature-orders", args.quadrature_orders)
    if not all(q == int(q) and 1 <= q <= 10 for q in orders):
        raise InputError(f"--quadrature-orders {args.quadrature_orders!r}: expected integers from 1 to 10")
    sizes, steps = (
        _numbers(f"--{name}", getattr(args, name)) if getattr(args, name) else None for name in ("sizes", "steps")
    )
    rtols = _numbers("--rtols", args.rtols)
    with study(args) as pool:
        table, reference = accuracy(
            args.scene,
            overrides(args),
            RunStore(args.store),
            args.out,
            sizes,
            steps,
            rtols,
            pool,
            [int(q) for q in orders],
        )
    if args.json:
        print_json({"reference": reference, "settings": table_records(table)})
    else:
        print((Path(args.out) / "accuracy.md").read_text())
    return 0


def contact_incidence_study(args: argparse.Namespace) -> int:
    from ..run import RunStore
    from ..studies.numerics.contact import contact_study

    incidences = _numbers("--incidences", args.incidences)
    with study(args) as pool:
        table = contact_study(args.scene, overrides(args), RunStore(args.store), args.out, incidences, args.step, pool)
    return _show(args, table, "contact.md")


def entry_smoothing_study(args: argparse.Namespace) -> int:
    from ..run import RunStore
    from ..studies.numerics.contact import entry_study

    steps = _numbers("--steps", args.steps)
    if len(set(steps)) < 2:
        raise InputError(f"--steps {args.steps!r}: expected two or more different steps")
    smoothings = _numbers("--smoothings", args.smoothings)
    with study(args) as pool:
        table = entry_study(args.scene, overrides(args), RunStore(args.store), args.out, smoothings, steps, pool)
    return _show(args, table, "entry.md")


def _show(args: argparse.Namespace, table: pd.DataFrame, report: str) -> int:
    """A study's table as one JSON object, ``{"rows": [...]}``, with ``--json``; else its markdown report from
    ``--out``."""
    if args.json:
        print_json({"rows": table_records(table)})
    else:
        print((Path(args.out) / report).read_text())
    return 0


def paper_study(args: argparse.Namespace) -> int:
    from ..run import RunStore
    from ..studies.paper import reproduce, reproduce_variants

    with study(args) as pool:
        record = (reproduce_variants if args.variants else reproduce)(args.out, RunStore(args.store), pool)
    if args.json:
        print_json(record)
        return 0
    written = "results.md, results.json and the figures"
    if args.variants:
        written = "variants.md, variants.json and variants.png"
    print(f"wrote {args.out}/{written} in {record['wall_time']:.0f} s")
    return 0
