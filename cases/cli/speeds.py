"""``penetrate critical`` and ``penetrate convergent``: the paper's characteristic speeds of a scene."""

from __future__ import annotations

import argparse
import json

from .options import add_pool_options, add_scene_options, pool, positive_float

__all__ = ["register"]


def _study_options(parser: argparse.ArgumentParser) -> None:
    add_scene_options(parser)
    add_pool_options(parser, "runs/store")
    parser.add_argument("--json", action="store_true", help="print the result as one JSON object")


def register(commands) -> None:
    critical = commands.add_parser("critical", help="find the critical impact velocity of a scene's disturbance")
    _study_options(critical)
    critical.add_argument("--speeds", default="200:1600:100", metavar="START:STOP:STEP",
                          help="the coarse scan of impact speeds, m/s (default 200:1600:100)")
    critical.add_argument("--resolution", type=positive_float, default=5.0, metavar="M/S",
                          help="bisect until the bracket is this narrow (default 5 m/s)")
    critical.set_defaults(handler=critical_speed)
    convergent = commands.add_parser("convergent", help="measure the characteristic convergent velocity")
    _study_options(convergent)
    convergent.add_argument("--threshold", type=positive_float, default=0.1, metavar="DEG",
                            help="the attack angle counts as converged below this (default 0.1 deg)")
    convergent.set_defaults(handler=convergent_speed)


def _inputs(args: argparse.Namespace):
    from ..run import RunStore
    from ..studies import Sweep

    from .options import overrides

    return Sweep.from_file(args.scene, overrides(args)), RunStore(args.store)


def critical_speed(args: argparse.Namespace) -> int:
    from ..studies import find_critical_velocity, parse_grid

    sweep, store = _inputs(args)
    _, speeds = parse_grid(f"impact.speed={args.speeds}")
    search = find_critical_velocity(sweep, store, speeds, args.resolution, pool(args))
    if args.json:
        print(json.dumps(search.as_dict()))
        return 0 if search.critical_velocity is not None else 1
    for run in search.indicator:
        print(f"{run.speed:8.1f} m/s   max attack angle {run.max_attack_angle:8.3f} deg"
              f"   axis angle change {run.axis_angle_change:9.3f} deg   {run.end_reason}")
    if search.critical_velocity is None:
        print(search.message)
        return 1
    low, high = search.bracket
    print(f"critical impact velocity {search.critical_velocity:.1f} m/s (between {low:g} and {high:g} m/s)")
    return 0


def convergent_speed(args: argparse.Namespace) -> int:
    from ..studies import measure_convergent_velocity

    sweep, store = _inputs(args)
    result = measure_convergent_velocity(sweep, store, args.threshold, pool=pool(args))
    if args.json:
        print(json.dumps(result.as_dict()))
        return 0 if result.characteristic_convergent_velocity is not None else 1
    for run in result.runs:
        converged = f"{run.convergence_speed:.1f} m/s" if run.convergence_speed is not None else "never"
        print(f"{run.speed:8.1f} m/s   {'unstable' if run.unstable else 'stable  '}"
              f"   max attack angle {run.max_attack_angle:7.3f} deg   attack angle below"
              f" {args.threshold} deg at {converged}")
    if result.message:
        print(result.message)
    if result.characteristic_convergent_velocity is None:
        return 1
    print(f"characteristic convergent velocity {result.characteristic_convergent_velocity:.1f} m/s")
    return 0
