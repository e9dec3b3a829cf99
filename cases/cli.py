"""The ``penetrate`` command: a thin layer over :mod:`cases`."""

from __future__ import annotations

import argparse
import json
import os
import sys

__all__ = ["main"]


def _human(record: dict, scene) -> str:
    lines = [
        f"scene          {scene.name or '(unnamed)'}" + (f": {scene.description}" if scene.description else ""),
        f"projectile     {record['mass']:.4g} kg, centre of mass {record['centre_of_mass_from_tip']:.4g} m"
        f" behind the tip, transverse inertia {record['transverse_inertia']:.4g} kg m^2,"
        f" {record['surface_points']} surface points",
        f"end            {record['end_reason']} at t = {record['final_time']:.6g} s,"
        f" speed {record['final_speed']:.4g} m/s",
        f"depth          {record['depth']:.4f} m (nose tip below the surface)",
        f"path length    {record['path_length']:.4f} m (centre of mass)",
        f"attack angle   max {record['max_attack_angle']:.4g} deg, final {record['final_attack_angle']:.4g} deg;"
        f" axis angle change {record['axis_angle_change']:.4g} deg",
        f"wall time      {record['wall_time']:.3g} s (integration {record['integration_time']:.3g} s,"
        f" {record['steps']} steps, {record['load_evaluations']} load evaluations)",
    ]
    return "\n".join(lines)


def _run(args: argparse.Namespace) -> int:
    from .results import history_table, summary, write_outputs
    from .runner import run_scene
    from .scene import load_scene

    scene = load_scene(args.scene, args.set)
    result = run_scene(scene)
    history = history_table(result)
    record = summary(result, history)
    if args.out:
        write_outputs(result, args.out, scene.outputs.history_every, history)
    if args.json:
        print(json.dumps(record))
    else:
        print(_human(record, scene))
        if args.out:
            print(f"written        {os.path.join(args.out, 'summary.json')}"
                  + (f", {os.path.join(args.out, 'history.csv')}" if scene.outputs.history else ""))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="penetrate",
        description="Rigid projectile penetration with the differential area force law.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of failures")
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="run one scene")
    run.add_argument("scene", help="a scene TOML file")
    run.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene key by its dotted path, e.g. impact.speed=1120 (repeatable)")
    run.add_argument("--out", metavar="DIR", help="write summary.json and history.csv here")
    run.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    run.set_defaults(handler=_run)
    return parser


def main(argv: list[str] | None = None) -> int:
    from .scene import SceneError

    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.handler(args)
    except SceneError as exc:
        print(f"penetrate: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("penetrate: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # one line for the user; --debug shows the traceback
        if args.debug:
            raise
        print(f"penetrate: error: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
