"""The ``penetrate`` command: a thin layer over :mod:`cases`."""

from __future__ import annotations

import argparse
import json
import os
import sys
import warnings
from pathlib import Path

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
    lines += [f"warning        {text}" for text in record.get("warnings", [])]
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


def _sweep(args: argparse.Namespace) -> int:
    from .sweep import RunStore, Sweep, Variation, grid, parse_grid, read_variations, run_sweep

    parameters = dict(parse_grid(text) for text in args.grid)
    variations = grid(parameters) if parameters else [Variation({})]
    if args.list:
        # a list and a grid combine as their product
        listed = read_variations(args.list)
        variations = [Variation({**g.values, **v.values}) for g in variations for v in listed]
        for v in listed:
            parameters.update(dict.fromkeys(v.values))
    sweep = Sweep.from_file(args.scene, args.set, variations)
    table = run_sweep(sweep, RunStore(args.store), workers=args.workers, scheduler=args.scheduler,
                      progress=not args.no_progress)
    if args.out:
        from .results import atomic_write_text

        atomic_write_text(Path(args.out), table.to_csv(index=False))
    shown = [c for c in (*parameters, "end_reason", "depth", "path_length", "max_attack_angle",
                         "axis_angle_change", "final_speed", "error") if c in table]
    if args.json:
        print(table.to_json(orient="records"))
    else:
        print(table[shown].to_string(index=False))
    failed = int(table["error"].notna().sum()) if "error" in table else 0
    return 1 if failed else 0


def _study_inputs(args: argparse.Namespace):
    from .sweep import RunStore, Sweep

    return Sweep.from_file(args.scene, args.set), RunStore(args.store)


def _critical(args: argparse.Namespace) -> int:
    from .studies import find_critical_velocity
    from .sweep import parse_grid

    sweep, store = _study_inputs(args)
    _, speeds = parse_grid(f"impact.speed={args.speeds}")
    search = find_critical_velocity(sweep, store, speeds, args.resolution, args.workers, args.scheduler,
                                    progress=not args.no_progress)
    if args.json:
        print(json.dumps(search.as_dict()))
    else:
        for row in search.indicator:
            print(f"{row['speed']:8.1f} m/s   max attack angle {row['max_attack_angle']:8.3f} deg"
                  f"   axis angle change {row['axis_angle_change']:9.3f} deg   {row['end_reason']}")
        if search.critical_velocity is None:
            print(search.message)
        else:
            low, high = search.bracket
            print(f"critical impact velocity {search.critical_velocity:.1f} m/s (between {low:g} and {high:g} m/s)")
    return 0 if search.critical_velocity is not None else 1


def _convergent(args: argparse.Namespace) -> int:
    from .studies import measure_convergent_velocity

    sweep, store = _study_inputs(args)
    result = measure_convergent_velocity(sweep, store, args.threshold, workers=args.workers,
                                         scheduler=args.scheduler, progress=not args.no_progress)
    if args.json:
        print(json.dumps(result.as_dict()))
    else:
        for run in result.runs:
            converged = run["convergence_speed"]
            print(f"{run['speed']:8.1f} m/s   {'unstable' if run['unstable'] else 'stable  '}"
                  f"   max attack angle {run['max_attack_angle']:7.3f} deg   attack angle below"
                  f" {args.threshold} deg at " + (f"{converged:.1f} m/s" if converged is not None else "never"))
        if result.message:
            print(result.message)
        if result.characteristic_convergent_velocity is not None:
            print(f"characteristic convergent velocity {result.characteristic_convergent_velocity:.1f} m/s")
    return 0 if result.characteristic_convergent_velocity is not None else 1


def _paper(args: argparse.Namespace) -> int:
    from .paper import reproduce, reproduce_variants
    from .sweep import RunStore

    if args.variants:
        record = reproduce_variants(args.out, RunStore(args.store), args.workers, args.scheduler,
                                    not args.no_progress)
        print(f"wrote {args.out}/variants.md, variants.json and variants.png in {record['wall_time']:.0f} s")
        return 0
    record = reproduce(args.out, RunStore(args.store), args.workers, args.scheduler, not args.no_progress)
    print(f"wrote {args.out}/results.md, results.json and the figures in {record['wall_time']:.0f} s")
    return 0


def _compare(args: argparse.Namespace) -> int:
    from .compare import compare_laws
    from .scene import SceneError as SceneError_
    from .sweep import RunStore

    laws = [name.strip() for name in args.laws.split(",") if name.strip()]
    if len(laws) < 1:
        raise SceneError_("--laws: give one or more law names, e.g. soil,softer_soil")
    try:
        table = compare_laws(args.scene, args.set, laws, RunStore(args.store), args.out, args.workers,
                             args.scheduler, not args.no_progress)
    except ValueError as exc:
        if "law =" in str(exc):
            raise SceneError_(f"--laws: {exc}") from None
        raise
    if args.json:
        print(table.to_json(orient="records"))
    else:
        print((Path(args.out) / "compare.md").read_text())
    return 0


def _accuracy(args: argparse.Namespace) -> int:
    from .accuracy import accuracy_study
    from .scene import SceneError as SceneError_
    from .sweep import RunStore

    def numbers(text: str) -> list[float]:
        try:
            values = [float(v) for v in text.split(",")]
        except ValueError:
            values = []
        if not values or not all(v > 0 and v < float("inf") for v in values):
            raise SceneError_(f"{text!r}: expected comma-separated numbers > 0")
        return values

    orders = numbers(args.quadrature_orders)
    if not all(q == int(q) and 1 <= q <= 10 for q in orders):
        raise SceneError_(f"--quadrature-orders {args.quadrature_orders!r}: expected integers from 1 to 10")
    table, reference = accuracy_study(args.scene, args.set, RunStore(args.store), args.out,
                                      numbers(args.sizes), numbers(args.steps), numbers(args.rtols),
                                      args.workers, args.scheduler, not args.no_progress,
                                      [int(q) for q in orders])
    if args.json:
        print(json.dumps({"reference": {k: (None if isinstance(v, float) and v != v else v)
                                        for k, v in reference.items()},
                          "settings": json.loads(table.to_json(orient="records"))}))
    else:
        print((Path(args.out) / "accuracy.md").read_text())
    return 0


def _render(args: argparse.Namespace) -> int:
    from .render import INSTANT_NAMES, render_all
    from .runner import run_scene
    from .scene import SceneError as SceneError_
    from .scene import load_scene

    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        width = height = 0
    if not (64 <= width <= 8192 and 64 <= height <= 8192):
        raise SceneError_(f"--size {args.size!r}: expected WIDTHxHEIGHT in pixels, each 64..8192")
    try:
        steps = None if args.steps == "all" else _positive_int(args.steps)
    except argparse.ArgumentTypeError as exc:
        raise SceneError_(f"--steps {exc}") from None
    times = [t.strip() for t in args.times.split(",") if t.strip()] if args.times else None
    for text in times or ():
        try:
            float(text)
        except ValueError:
            if text not in INSTANT_NAMES:
                raise SceneError_(f"--times {text!r}: expected a time in seconds or one of"
                                  f" {', '.join(INSTANT_NAMES)}") from None
    scene = load_scene(args.scene, args.set)
    result = run_scene(scene)
    try:
        record = render_all(result, args.out, times, animation=args.animation, paraview=args.paraview,
                            frames=args.frames, steps=steps, station=args.station, size=(width, height))
    except ValueError as exc:
        if str(exc).startswith(("--times", "station")):
            raise SceneError_(str(exc)) from None
        raise
    if args.json:
        print(json.dumps(record))
    else:
        for item in record["instants"]:
            print(f"instant        {item['label'] or 'chosen'} at t = {item['time'] * 1e3:.3f} ms")
        for path in record["files"]:
            print(f"written        {path}")
        print("seconds        " + ", ".join(f"{k} {v:.2f}" for k, v in record["seconds"].items()))
    return 0


def _add_pool_options(parser: argparse.ArgumentParser, store: str) -> None:
    """The run store and where the runs go: shared by every command that runs many scenes."""
    parser.add_argument("--store", default=store, metavar="DIR",
                        help=f"where finished runs are kept and found again (default {store})")
    parser.add_argument("--workers", type=_positive_int, metavar="N", help="local processes (default: every core)")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="run on this Dask distributed scheduler")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def _add_study_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", help="a scene TOML file")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override a scene key by its dotted path (repeatable)")
    _add_pool_options(parser, "runs/store")
    parser.add_argument("--json", action="store_true", help="print the result as one JSON object")


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: must be a whole number >= 1")
    return value


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"{text!r}: must be a finite number > 0")
    return value


def _out_folder(text: str) -> str:
    """``--out DIR``: refused at once when it names a file, not after the run."""
    if Path(text).exists() and not Path(text).is_dir():
        raise argparse.ArgumentTypeError(f"{text!r}: is a file; give a folder (it is made when missing)")
    return text


def _out_file(text: str) -> str:
    """``--out FILE``: refused at once when it names a folder."""
    if Path(text).is_dir():
        raise argparse.ArgumentTypeError(f"{text!r}: is a folder; give a file name")
    return text


class _Parser(argparse.ArgumentParser):
    """Usage errors in one line, like every other error (subcommands inherit this class)."""

    def error(self, message: str):
        from .scene import one_line

        self.exit(2, f"{self.prog}: error: {one_line(message)} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="penetrate",
        description="Rigid projectile penetration with the differential area force law.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of failures")
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="run one scene")
    run.add_argument("scene", help="a scene TOML file")
    run.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene key by its dotted path, e.g. impact.speed=1120 (repeatable)")
    run.add_argument("--out", type=_out_folder, metavar="DIR", help="write summary.json and history.csv here")
    run.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    run.set_defaults(handler=_run)

    sweep = commands.add_parser("sweep", help="run variations of a scene in parallel (resumable)")
    sweep.add_argument("scene", help="the base scene TOML file")
    sweep.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                       help="override a key of the base scene (repeatable)")
    sweep.add_argument("--grid", action="append", default=[], metavar="KEY=VALUES",
                       help="vary a key over V1,V2,... or START:STOP:STEP (inclusive); several --grid"
                            " options make a cartesian product")
    sweep.add_argument("--list", metavar="FILE",
                       help="a TOML file of [[run]] tables of dotted keys, one run each (with --grid: their product)")
    _add_pool_options(sweep, "runs/store")
    sweep.add_argument("--out", type=_out_file, metavar="FILE", help="write the results table as CSV")
    sweep.add_argument("--json", action="store_true", help="print the table as JSON records")
    sweep.set_defaults(handler=_sweep)

    critical = commands.add_parser("critical", help="find the critical impact velocity of a scene's disturbance")
    _add_study_options(critical)
    critical.add_argument("--speeds", default="200:1600:100", metavar="START:STOP:STEP",
                          help="the coarse scan of impact speeds, m/s (default 200:1600:100)")
    critical.add_argument("--resolution", type=_positive_float, default=5.0, metavar="M/S",
                          help="bisect until the bracket is this narrow (default 5 m/s)")
    critical.set_defaults(handler=_critical)

    convergent = commands.add_parser("convergent", help="measure the characteristic convergent velocity")
    _add_study_options(convergent)
    convergent.add_argument("--threshold", type=_positive_float, default=0.1, metavar="DEG",
                            help="the attack angle counts as converged below this (default 0.1 deg)")
    convergent.set_defaults(handler=_convergent)

    compare = commands.add_parser("compare", help="run a scene under several resistance laws, side by side")
    _add_study_options(compare)
    compare.add_argument("--laws", required=True, metavar="A,B,...",
                         help="comma-separated law names (see docs/effects.md)")
    compare.add_argument("--out", default="runs/compare", type=_out_folder, metavar="DIR",
                         help="where to write compare.md, compare.csv and compare.png (default runs/compare)")
    compare.set_defaults(handler=_compare)

    accuracy = commands.add_parser("accuracy", help="what accuracy costs in time, for a scene")
    _add_study_options(accuracy)
    accuracy.add_argument("--sizes", default="0.04,0.02,0.01,0.005", metavar="M,M,...",
                          help="mesh sizes of the mesh axis (default 0.04,0.02,0.01,0.005 m)")
    accuracy.add_argument("--steps", default="8e-5,4e-5,2e-5,1e-5,5e-6", metavar="S,S,...",
                          help="RK4 steps of the time axis (default 8e-5,...,5e-6 s)")
    accuracy.add_argument("--rtols", default="1e-4,1e-6", metavar="R,R,...",
                          help="Dormand-Prince tolerances of the time axis (default 1e-4,1e-6)")
    accuracy.add_argument("--quadrature-orders", default="4,6", metavar="Q,Q,...",
                          help="facet quadrature degrees beside the default 2, on the mesh-size axis (default 4,6)")
    accuracy.add_argument("--out", default="runs/accuracy", type=_out_folder, metavar="DIR",
                          help="where to write accuracy.md, .csv and .png (default runs/accuracy)")
    accuracy.set_defaults(handler=_accuracy)

    paper = commands.add_parser("paper", help="regenerate the paper's study: tables and figures")
    paper.add_argument("--out", default="docs/paper", type=_out_folder, metavar="DIR",
                       help="where to write (default docs/paper)")
    _add_pool_options(paper, "runs/paper-store")
    paper.add_argument("--variants", action="store_true",
                       help="the paper's variants instead: friction, conical nose, other soil laws")
    paper.set_defaults(handler=_paper)

    render = commands.add_parser("render", help="off-screen images, an animation and ParaView files of the"
                                                " resistance field")
    render.add_argument("scene", help="a scene TOML file")
    render.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override a scene key by its dotted path (repeatable)")
    render.add_argument("--times", metavar="T,...",
                        help="instants: times in seconds or embedded, peak, converged, end"
                             " (default: those four)")
    render.add_argument("--out", default="runs/render", metavar="DIR", help="where to write (default runs/render)")
    render.add_argument("--animation", action="store_true", help="also write animation.gif")
    render.add_argument("--frames", type=_positive_int, default=60, metavar="N",
                        help="frames of the animation, evenly spaced in time (default 60)")
    render.add_argument("--paraview", action="store_true",
                        help="also write paraview/run.pvd: the surface field over time and the path")
    render.add_argument("--steps", default="100", metavar="N|all",
                        help="steps in the ParaView output, evenly spaced in time, or all (default 100)")
    render.add_argument("--station", type=_positive_float, metavar="M",
                        help="distance behind the tip of the polar plot's ring (default: one calibre behind the nose)")
    render.add_argument("--size", default="1280x640", metavar="WxH", help="image size in pixels (default 1280x640)")
    render.add_argument("--json", action="store_true", help="print the written files and timings as JSON")
    render.set_defaults(handler=_render)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command; every failure ends in one line on stderr and a non-zero exit code.

    2: bad input (scene, options); 1: a run or study that failed; 130: interrupted.
    """
    from .scene import SceneError, one_line

    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with warnings.catch_warnings():
            if not args.debug:
                # numpy's floating-point warnings of a diverging run would spill over several lines;
                # the run's end reason (non_finite) or its error says what happened
                warnings.filterwarnings("ignore", category=RuntimeWarning)
            return args.handler(args)
    except SceneError as exc:
        print(f"penetrate: error: {one_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("penetrate: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader of our output went away (e.g. `| head`): nothing left to say
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except Exception as exc:  # one line for the user; --debug shows the traceback
        if args.debug:
            raise
        print(f"penetrate: error: {type(exc).__name__}: {one_line(exc)}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
