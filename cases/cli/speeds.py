"""``penetrate critical`` and ``penetrate convergent``: the paper's characteristic speeds of a scene, measured on
trajectories; ``penetrate predict``: the same two from the reduced pitch-plane model, without a full trajectory."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TYPE_CHECKING

from .options import Parser, add_scene_options, positive_float, print_json, renamed, study, study_parser

if TYPE_CHECKING:
    from ..run import RunStore
    from ..studies import CriticalSearch, Sweep

__all__ = ["register"]


def _speed_options(
    parser: Parser,
    speeds: tuple[float, float] = (200.0, 1600.0),
    resolution: float = 5.0,
    pair: str = "a stable and an unstable run",
) -> None:
    parser.add_argument(
        "--speeds",
        type=speed_range,
        default=speeds,
        metavar="LOW:HIGH",
        help=f"the range of impact speeds searched, m/s (default {speeds[0]:g}:{speeds[1]:g}; a list or a grid is"
        " refused)",
    )
    parser.add_argument(
        "--resolution",
        type=positive_float,
        default=resolution,
        metavar="M/S",
        help=f"search until {pair} are this close (default {resolution:g} m/s)",
    )


def _guide_option(parser: Parser) -> None:
    parser.add_argument(
        "--guide",
        choices=("auto", "reduced", "none"),
        default="auto",
        help="where the first full runs go: auto (default) the reduced model's prediction where it applies"
        " (bodies of revolution in homogeneous targets, docs/studies.md), else unguided; reduced: refuse a"
        " scene it does not apply to; none: unguided",
    )


def register(commands: argparse._SubParsersAction[Parser]) -> None:
    critical = study_parser(
        commands, "critical", "find the critical impact velocity of a scene's disturbance", writes=None
    )
    _guide_option(critical)
    critical.add_argument(
        "--guess",
        type=speed_range,
        metavar="LOW:HIGH",
        help="a first bracket inside the range, m/s (e.g. a neighbour's critical speed): runs"
        " confirm its ends, and the search widens to the range if they do not hold",
    )
    _speed_options(critical)
    critical.set_defaults(handler=critical_speed)
    convergent = study_parser(commands, "convergent", "measure the characteristic convergent velocity", writes=None)
    _guide_option(convergent)
    convergent.add_argument(
        "--threshold",
        type=positive_float,
        default=0.1,
        metavar="DEG",
        help="the attack angle counts as converged below this (default 0.1 deg)",
    )
    convergent.set_defaults(handler=convergent_speed)
    stability = study_parser(
        commands,
        "map",
        "the critical impact velocity over a grid of one or two inputs (guided searches, resumable)",
        "map.csv, .json, .md and map.png",
        lambda parser: add_scene_options(parser, "the base scene TOML file"),
    )
    stability.add_argument(
        "--grid",
        action="append",
        default=[],
        required=True,
        metavar="KEY=VALUES",
        help="an axis of the map: START:STOP:STEP (inclusive) or V1,V2,... (as sweep's --grid); one or two --grid"
        " options",
    )
    renamed(stability, "--over", "--grid KEY=VALUES (one axis syntax wherever one is taken)")
    _speed_options(stability)
    _guide_option(stability)
    stability.add_argument(
        "--quantity",
        choices=("critical_velocity", "ballistic_limit"),
        default="critical_velocity",
        help="what each point searches: the critical impact velocity (default) or the ballistic limit of a"
        " target with a rear face (then --guide auto is the 1-D model's guide, --resolution its, default 5 m/s)",
    )
    stability.set_defaults(handler=stability_map)
    limit = study_parser(
        commands,
        "ballistic-limit",
        "find the lowest impact speed that perforates a target with a rear face (guided, resumable)",
        writes=None,
    )
    _speed_options(limit, (10.0, 2000.0), 1.0, "a run that perforates and one that does not")
    limit.add_argument(
        "--guide",
        choices=("auto", "none"),
        default="auto",
        help="auto (default): the first bracket around the 1-D model's limit where it applies (a normal impact"
        " of a body of revolution without friction, docs/targets.md); none: split the range",
    )
    limit.set_defaults(handler=ballistic_limit)
    predict = study_parser(
        commands,
        "predict",
        "predict both characteristic speeds without a full trajectory (reduced pitch-plane model, docs/theory.md)",
        writes=None,
        full_runs=False,
    )
    predict.add_argument(
        "--speeds",
        type=speed_range,
        default=(200.0, 1600.0),
        metavar="LOW:HIGH",
        help="the range the critical impact velocity is sought in, m/s (default 200:1600; a list or a grid is refused)",
    )
    predict.add_argument(
        "--resolution",
        type=positive_float,
        default=5.0,
        metavar="M/S",
        help="search until a stable and an unstable reduced run are this close (default 5 m/s)",
    )
    predict.set_defaults(handler=predict_speeds)


def speed_range(text: str) -> tuple[float, float]:
    """``LOW:HIGH`` in m/s.  A list (``V1,V2,...``) or a grid (``START:STOP:STEP``) is refused: a search runs the
    speeds it chooses inside a range, not those given, and reducing a list to its ends would hide that."""
    parts = text.split(":")
    if len(parts) != 2 or "," in text:
        raise argparse.ArgumentTypeError(
            f"{text!r}: a range of speeds is LOW:HIGH in m/s (e.g. 200:1600), not a list or a grid"
        )
    try:
        low, high = float(parts[0]), float(parts[1])
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected LOW:HIGH in m/s") from None
    if not 0 < low < high < math.inf:
        raise argparse.ArgumentTypeError(f"{text!r}: need 0 < LOW < HIGH, finite (m/s)")
    return low, high


def _inputs(args: argparse.Namespace) -> tuple[Sweep, RunStore]:
    from ..run import RunStore
    from ..studies import Sweep
    from .options import overrides

    return Sweep.from_file(args.scene, overrides(args)), RunStore(args.store)


def critical_speed(args: argparse.Namespace) -> int:
    from ..scene import InputError
    from ..studies import find_critical_velocity

    if args.guess and not args.speeds[0] <= args.guess[0] < args.guess[1] <= args.speeds[1]:
        raise InputError(
            f"--guess {args.guess[0]:g}:{args.guess[1]:g}: must lie inside --speeds"
            f" {args.speeds[0]:g}:{args.speeds[1]:g} (m/s)"
        )
    sweep, store = _inputs(args)
    with study(args) as pool:
        search = find_critical_velocity(sweep, store, args.speeds, args.resolution, pool, args.guess, args.guide)
    if args.json:
        print_json(search.as_dict())
        return 0 if search.critical_velocity is not None else 1
    print(f"guide: {search.guide.text}")
    for run in search.indicator:
        print(
            f"{run.speed:8.1f} m/s   max attack angle {run.max_attack_angle:8.3f} deg"
            f"   axis angle change {run.axis_angle_change:9.3f} deg   {run.end_reason}"
        )
    if search.critical_velocity is None:
        # the line ends with what to change: the options that would find the change
        print(f"{search.message} ({_runs(search)}): {search.fix}")
        return 1
    assert search.bracket is not None  # a critical velocity is found with its bracket
    low, high = search.bracket
    print(
        f"critical impact velocity {search.critical_velocity:.1f} m/s (between {low:g} and {high:g} m/s;"
        f" {_runs(search)})"
    )
    return 0


def _runs(search: CriticalSearch) -> str:
    rounds = f"{search.rounds} round" + ("s" if search.rounds != 1 else "")
    return f"{len(search.indicator)} full runs in {rounds}"


def convergent_speed(args: argparse.Namespace) -> int:
    from ..studies import measure_convergent_velocity

    sweep, store = _inputs(args)
    with study(args) as pool:
        result = measure_convergent_velocity(sweep, store, args.threshold, pool=pool, guide=args.guide)
    if args.json:
        print_json(result.as_dict())
        return 0 if result.characteristic_convergent_velocity is not None else 1
    print(f"guide: {result.guide.text}")
    for run in result.runs:
        converged = f"{run.convergence_speed:.1f} m/s" if run.convergence_speed is not None else "never"
        print(
            f"{run.speed:8.1f} m/s   {'unstable' if run.unstable else 'stable  '}"
            f"   max attack angle {run.max_attack_angle:7.3f} deg   attack angle below"
            f" {args.threshold} deg at {converged}"
        )
    if result.message:
        print(result.message)
    if result.characteristic_convergent_velocity is None:
        return 1
    print(f"characteristic convergent velocity {result.characteristic_convergent_velocity:.1f} m/s")
    return 0


def ballistic_limit(args: argparse.Namespace) -> int:
    from ..studies.speeds.ballistic import find_ballistic_limit

    sweep, store = _inputs(args)
    with study(args) as pool:
        result = find_ballistic_limit(sweep, store, args.speeds, args.resolution, pool, args.guide == "auto")
    if args.json:
        print_json(result.as_dict())
        return 0 if result.ballistic_limit is not None else 1
    print(f"guide: {result.guide}")
    for run in result.runs:
        residual = f"residual velocity {run.residual_velocity:8.2f} m/s" if run.perforated else ""
        print(f"{run.speed:10.3f} m/s   {run.end_reason:11s} {residual}")
    runs = f"{len(result.runs)} full runs in {result.rounds} round" + ("s" if result.rounds != 1 else "")
    if result.ballistic_limit is None:
        print(f"{result.message} ({runs}): widen --speeds")
        return 1
    assert result.bracket is not None  # a limit is found with its bracket
    print(
        f"ballistic limit {result.ballistic_limit:.2f} m/s (between {result.bracket[0]:g} and"
        f" {result.bracket[1]:g} m/s; {runs})"
    )
    return 0


def predict_speeds(args: argparse.Namespace) -> int:
    from ..scene import load_scene
    from ..studies.reduced.pitch_plane import predict
    from .options import overrides

    result = predict(load_scene(args.scene, overrides(args)), args.speeds, args.resolution)
    found = result.characteristic_convergent_velocity is not None and result.critical_velocity is not None
    if args.json:
        print_json(result.as_dict())
        return 0 if found else 1

    def speed(value: float | None) -> str:
        return f"{value:.1f} m/s" if value is not None else "none"

    bracket = (
        f" (between {result.critical_bracket[0]:.1f} and {result.critical_bracket[1]:.1f} m/s)"
        if result.critical_bracket
        else ""
    )
    print(f"characteristic convergent velocity {speed(result.characteristic_convergent_velocity)}")
    print(f"critical impact velocity {speed(result.critical_velocity)}{bracket}")
    print(
        f"{result.model}; {len(result.runs)} reduced runs in {1e3 * result.prediction_time:.1f} ms"
        f" ({result.wall_time:.2f} s with the projectile's preparation)"
    )
    print("assumptions: " + "; ".join(result.assumptions))
    for message in result.messages:  # last: a speed not found ends the output with the option that finds it
        print(message)
    return 0 if found else 1


def stability_map(args: argparse.Namespace) -> int:
    from ..run import RunStore
    from ..studies.speeds.stability_map import stability_map as build
    from .options import overrides

    with study(args) as pool:
        record = build(
            args.scene,
            overrides(args),
            args.grid,
            RunStore(args.store),
            args.out,
            args.speeds,
            args.resolution,
            pool,
            args.guide,
            args.quantity,
        )
    if args.json:
        print_json(record)
    else:
        print((Path(args.out) / "map.md").read_text())
    return 0
