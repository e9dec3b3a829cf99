"""``penetrate run SCENE``: one run, its summary, and with ``--out`` its files."""

from __future__ import annotations

import argparse
import os
from typing import TYPE_CHECKING

from .options import Parser, add_scene_options, environment_defaults, out_folder, overrides, print_json, quiet_start

if TYPE_CHECKING:
    from ..run import RunSummary
    from ..scene import Scene

__all__ = ["register", "human_summary"]


def register(commands: argparse._SubParsersAction[Parser]) -> None:
    parser = commands.add_parser("run", help="run one scene")
    add_scene_options(parser)
    parser.add_argument("--out", type=out_folder, metavar="DIR", help="write summary.json and history.csv here")
    parser.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    # start-up is most of a short run (docs/performance.md, "Start-up"): the collector rests until the scene
    # is read, and OpenBLAS starts no thread pool (its worker spins 60 ms of CPU after numpy's import), since
    # a run holds BLAS at one thread anyway (cases.run.run_scene) and reads a cached projectile without BLAS
    with quiet_start() as started, environment_defaults(OPENBLAS_NUM_THREADS="1"):
        from ..run import history_columns, run_scene, summarise, write_outputs
        from ..scene import load_scene

        scene = load_scene(args.scene, overrides(args))
        started()
        result = run_scene(scene)
        history = history_columns(result)
        summary = summarise(result, history)
        if args.out:
            write_outputs(result, args.out, scene.outputs.history_every, history)
    if args.json:
        print_json(summary.record())
        return 0
    print(human_summary(summary, scene))
    if args.out:
        print(
            f"written        {os.path.join(args.out, 'summary.json')}"
            + (f", {os.path.join(args.out, 'history.csv')}" if scene.outputs.history else "")
        )
    return 0


def _exit_line(s: RunSummary) -> list[str]:
    """How the body left the target, if it did: through the rear face, or back out through the front face."""
    if s.end_reason == "perforated":
        return [
            f"perforated     residual velocity {s.residual_velocity:.4g} m/s at t = {s.exit_time:.6g} s; axis"
            f" {s.exit_axis_angle:.4g} deg from the rear face's normal, attack angle {s.exit_attack_angle:.4g} deg"
        ]
    if s.end_reason in ("exited", "ricocheted"):
        return [
            f"{s.end_reason:15s}out of the front face at {s.final_speed:.4g} m/s, t = {s.exit_time:.6g} s; velocity"
            f" {s.exit_velocity_angle:.4g} deg from its normal, attack angle {s.exit_attack_angle:.4g} deg"
        ]
    return []


def human_summary(s: RunSummary, scene: Scene) -> str:
    """The summary of a run for a person: a line each for the projectile, the end, depth, path, angles, time."""
    lines = [
        f"scene          {scene.name or '(unnamed)'}" + (f": {scene.description}" if scene.description else ""),
        f"projectile     {s.mass:.4g} kg, centre of mass {s.centre_of_mass_from_tip:.4g} m behind the tip,"
        f" transverse inertia {s.transverse_inertia:.4g} kg m^2, {s.surface_points} surface points",
        f"end            {s.end_reason} at t = {s.final_time:.6g} s, speed {s.final_speed:.4g} m/s",
        f"depth          {s.depth:.4f} m (nose tip below the front face)",
        *_exit_line(s),
        f"path length    {s.path_length:.4f} m (centre of mass)",
        f"attack angle   max {s.max_attack_angle:.4g} deg, final {s.final_attack_angle:.4g} deg;"
        f" axis angle change {s.axis_angle_change:.4g} deg",
        f"wall time      {s.wall_time:.3g} s (integration {s.integration_time:.3g} s,"
        f" {s.steps} steps, {s.load_evaluations} load evaluations)",
    ]
    lines += [f"warning        {text}" for text in s.warnings]
    return "\n".join(lines)
