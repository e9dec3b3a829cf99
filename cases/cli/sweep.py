"""``penetrate sweep SCENE --grid KEY=VALUES ...``: variations of a scene in parallel, resumable."""

from __future__ import annotations

import argparse

from .options import add_pool_options, add_scene_options, out_file, overrides, pool

__all__ = ["register"]

SHOWN = ("end_reason", "depth", "path_length", "max_attack_angle", "axis_angle_change", "final_speed", "error")


def register(commands) -> None:
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
    parser.add_argument("--json", action="store_true", help="print the table as JSON records")
    parser.set_defaults(handler=sweep)


def sweep(args: argparse.Namespace) -> int:
    from ..run import RunStore, atomic_write_text
    from ..studies import Sweep, Variation, grid, parse_grid, read_variations, run_sweep

    parameters = dict(parse_grid(text) for text in args.grid)
    variations = grid(parameters) if parameters else [Variation({})]
    if args.list:
        # a list and a grid combine as their product
        listed = read_variations(args.list)
        variations = [Variation({**g.values, **v.values}) for g in variations for v in listed]
        for v in listed:
            parameters.update(dict.fromkeys(v.values))
    result = run_sweep(Sweep.from_file(args.scene, overrides(args), variations), RunStore(args.store), pool(args))
    table = result.table()
    if args.out:
        atomic_write_text(args.out, table.to_csv(index=False))
    if args.json:
        print(table.to_json(orient="records"))
    else:
        print(table[[c for c in (*parameters, *SHOWN) if c in table]].to_string(index=False))
    return 1 if any(run.failed for run in result.runs) else 0
