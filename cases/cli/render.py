"""``penetrate render SCENE``: off-screen images, an animation and ParaView files of the resistance field."""

from __future__ import annotations

import argparse
import math

from ..scene import InputError
from .options import Parser, add_scene_options, out_folder, overrides, positive_float, positive_int, print_json, renamed

__all__ = ["register"]


def register(commands: argparse._SubParsersAction[Parser]) -> None:
    parser = commands.add_parser(
        "render", help="off-screen images, an animation and ParaView files of the resistance field"
    )
    add_scene_options(parser)
    parser.add_argument(
        "--times",
        metavar="T,...",
        help="instants: times in seconds or embedded, peak, converged, end (default: those four)",
    )
    parser.add_argument(
        "--out", default="runs/render", type=out_folder, metavar="DIR", help="where to write (default runs/render)"
    )
    parser.add_argument("--animation", action="store_true", help="also write animation.gif")
    parser.add_argument(
        "--frames",
        type=positive_int,
        default=60,
        metavar="N",
        help="frames of the animation, evenly spaced in time (default 60)",
    )
    parser.add_argument(
        "--paraview", action="store_true", help="also write paraview/run.pvd: the surface field over time and the path"
    )
    parser.add_argument(
        "--paraview-frames",
        default="100",
        metavar="N|all",
        help="frames of the ParaView output, evenly spaced in time, or all the run's steps (default 100)",
    )
    renamed(parser, "--steps", "--paraview-frames N|all (--steps are Runge-Kutta steps wherever they are taken)")
    parser.add_argument(
        "--station",
        type=positive_float,
        metavar="M",
        help="distance behind the tip of the polar plot's ring (default: one calibre behind the nose)",
    )
    parser.add_argument("--size", default="1280x640", metavar="WxH", help="image size in pixels (default 1280x640)")
    parser.add_argument(
        "--colour-range",
        metavar="LO:HI",
        help="colour range of sigma_n in MPa (the colour bar's unit), 0 <= LO < HI, e.g. 0:600: fixed, so"
        " renders compare; values outside take the end colours (default: one range shared by this render's"
        " pictures, the min..max over every instant they draw: the field images, trajectory.png's bodies, the"
        " animation's frames)",
    )
    parser.add_argument("--json", action="store_true", help="print the written files and timings as one JSON object")
    parser.set_defaults(handler=render)


_COLOUR_RANGE = "expected LO:HI in MPa, two finite numbers with 0 <= LO < HI, e.g. 0:600"


def _colour_range(text: str | None) -> tuple[float, float] | None:
    """``--colour-range LO:HI`` (MPa); ``sigma_n`` is a compressive stress, never negative."""
    if text is None:
        return None
    try:
        lo, hi = (float(v) for v in text.split(":"))
    except ValueError:
        lo = hi = math.nan
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 <= lo < hi):
        raise InputError(f"--colour-range {text!r}: {_COLOUR_RANGE}")
    return lo, hi


def _checked(args: argparse.Namespace) -> tuple[tuple[int, int], int | None, list[str] | None]:
    """``--size``, ``--paraview-frames`` and ``--times``, refused before the run when they cannot be used."""
    from ..viz import INSTANT_NAMES

    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        width = height = 0
    if not (64 <= width <= 8192 and 64 <= height <= 8192):
        raise InputError(f"--size {args.size!r}: expected WIDTHxHEIGHT in pixels, each 64..8192")
    try:
        steps = None if args.paraview_frames == "all" else positive_int(args.paraview_frames)
    except argparse.ArgumentTypeError as exc:
        raise InputError(f"--paraview-frames {exc}") from None
    times = [t.strip() for t in args.times.split(",") if t.strip()] if args.times else None
    for text in times or ():
        try:
            float(text)
        except ValueError:
            if text not in INSTANT_NAMES:
                raise InputError(
                    f"--times {text!r}: expected a time in seconds or one of {', '.join(INSTANT_NAMES)}"
                ) from None
    return (width, height), steps, times


def render(args: argparse.Namespace) -> int:
    from ..run import run_scene
    from ..scene import load_scene
    from ..viz import render_all

    size, steps, times = _checked(args)
    colour_range = _colour_range(args.colour_range)
    result = run_scene(load_scene(args.scene, overrides(args)))
    record = render_all(
        result,
        args.out,
        times,
        animation=args.animation,
        paraview=args.paraview,
        frames=args.frames,
        steps=steps,
        station=args.station,
        size=size,
        colour_range=colour_range,
    )
    if args.json:
        print_json(record)
        return 0
    for item in record["instants"]:
        print(f"instant        {item['label'] or 'chosen'} at t = {item['time'] * 1e3:.3f} ms")
    for name, (lo, hi) in record["colour_range"].items():
        print(f"colour range   {name} {lo:.4g} .. {hi:.4g} MPa")
    for path in record["files"]:
        print(f"written        {path}")
    print("seconds        " + ", ".join(f"{k} {v:.2f}" for k, v in record["seconds"].items()))
    return 0
