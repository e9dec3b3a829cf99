"""What the commands share: the one-line parser, option types, the scene and pool options."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..scene import one_line, parse_override

__all__ = ["Parser", "positive_int", "positive_float", "out_folder", "out_file", "add_scene_options",
           "add_pool_options", "overrides", "pool"]


class Parser(argparse.ArgumentParser):
    """Usage errors in one line, like every other error (subcommands inherit this class)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {one_line(message)} (see {self.prog} --help)\n")


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: must be a whole number >= 1")
    return value


def positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"{text!r}: must be a finite number > 0")
    return value


def out_folder(text: str) -> str:
    """``--out DIR``: refused at once when it names a file, not after the run."""
    if Path(text).exists() and not Path(text).is_dir():
        raise argparse.ArgumentTypeError(f"{text!r}: is a file; give a folder (it is made when missing)")
    return text


def out_file(text: str) -> str:
    """``--out FILE``: refused at once when it names a folder."""
    if Path(text).is_dir():
        raise argparse.ArgumentTypeError(f"{text!r}: is a folder; give a file name")
    return text


def add_scene_options(parser: argparse.ArgumentParser, what: str = "a scene TOML file") -> None:
    parser.add_argument("scene", help=what)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override a scene key by its dotted path, e.g. impact.speed=1120 (repeatable); the"
                             " value replaces what the scene gives, and its alternatives (target.layers replaces"
                             " target.law)")


def overrides(args: argparse.Namespace) -> list[tuple[str, object]]:
    """The ``--set`` options as (dotted key, value) pairs, in order; the only place their text is read."""
    return [parse_override(text) for text in args.set]


def add_pool_options(parser: argparse.ArgumentParser, store: str) -> None:
    """The run store and where the runs go: shared by every command that runs many scenes."""
    parser.add_argument("--store", default=store, metavar="DIR",
                        help=f"where finished runs are kept and found again (default {store})")
    parser.add_argument("--workers", type=positive_int, metavar="N", help="local processes (default: every core)")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="run on this Dask distributed scheduler")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def pool(args: argparse.Namespace):
    """The :class:`~cases.studies.Pool` the pool options describe."""
    from ..studies import Pool

    return Pool(args.workers, args.scheduler, not args.no_progress)
