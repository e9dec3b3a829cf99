"""What the commands share: the one-line parser, option types, the scene and pool options, a quick start."""

from __future__ import annotations

import argparse
import contextlib
import gc
import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

from ..scene import one_line

if TYPE_CHECKING:
    import pandas as pd

    from ..studies import Pool

__all__ = [
    "Parser",
    "SET_HELP",
    "positive_int",
    "positive_float",
    "out_folder",
    "add_scene_options",
    "add_pool_options",
    "study_parser",
    "renamed",
    "overrides",
    "pool",
    "study",
    "quiet_start",
    "environment_defaults",
    "print_json",
    "table_records",
]


class Parser(argparse.ArgumentParser):
    """Usage errors in one line, like every other error (subcommands inherit this class); help texts drawn
    from the code's registries (:meth:`late_help`)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._late_help: list[tuple[argparse.Action, Callable[[], str]]] = []

    def late_help(self, action: argparse.Action, build: Callable[[], str]) -> argparse.Action:
        """Give ``action`` the help text ``build()`` makes from a registry (the distributions, the named laws),
        so that the help lists what the code accepts and cannot drift from it.  It is built when the help is
        shown: the registries live in modules that import numpy and scipy, which parsing must not."""
        self._late_help.append((action, build))
        return action

    def format_help(self) -> str:
        for action, build in self._late_help:
            action.help = build()
        return super().format_help()

    def error(self, message: str) -> NoReturn:
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
    """``--out DIR``: refused at once when it names a file, or a new path with a file's suffix (a former
    ``sweep --out table.csv``), not after the run."""
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r}: is a file; give a folder (it is made when missing)")
    if not path.exists() and path.suffix.lower() in (".csv", ".json", ".md", ".txt"):
        raise argparse.ArgumentTypeError(
            f"{text!r}: a file name; give a folder (it is made when missing): the command writes its files into it"
        )
    return text


SET_HELP = (
    "override a scene key by its dotted path, e.g. impact.speed=1120 (repeatable); the"
    " value replaces what the scene gives, and its alternatives (target.layers replaces"
    " target.law)"
)


def law_names() -> str:
    """The named resistance laws a scene's ``target.law`` (and ``penetrate compare --laws``) takes."""
    from fem_loads.resistance import NAMED_LAWS

    return ", ".join(NAMED_LAWS)


def add_scene_options(parser: Parser, what: str = "a scene TOML file", optional: bool = False) -> None:
    if optional:
        parser.add_argument("scene", help=what, nargs="?")
    else:
        parser.add_argument("scene", help=what)
    parser.late_help(
        parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help=SET_HELP),
        lambda: f"{SET_HELP}; a named target.law is one of {law_names()}",
    )


def overrides(args: argparse.Namespace) -> list[tuple[str, object]]:
    """The ``--set`` options as (dotted key, value) pairs, in order; the only place their text is read."""
    from ..scene import parse_override

    return [parse_override(text) for text in args.set]


def add_pool_options(parser: argparse.ArgumentParser, store: str) -> None:
    """The run store and where the runs go: shared by every command that runs many scenes."""
    parser.add_argument(
        "--store", default=store, metavar="DIR", help=f"where finished runs are kept and found again (default {store})"
    )
    parser.add_argument("--workers", type=positive_int, metavar="N", help="local processes (default: every core)")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="run on this Dask distributed scheduler")
    # both default to None (a bar when stderr is a terminal): store_false's own default, True, would force it
    shown = parser.add_mutually_exclusive_group()
    shown.add_argument(
        "--progress",
        dest="progress",
        action="store_true",
        default=None,
        help="show the progress bar even when stderr is not a terminal (default: only when it is)",
    )
    shown.add_argument("--no-progress", dest="progress", action="store_false", default=None, help="no progress bar")


def study_parser(
    commands: argparse._SubParsersAction[Parser],
    name: str,
    help: str,
    writes: str | None,
    subject: Callable[[Parser], None] = add_scene_options,
    out: str | None = None,
    store: str = "runs/store",
    full_runs: bool = True,
) -> Parser:
    """A study's command with what every study takes, in one order: its ``subject`` (the scene and its ``--set``
    overrides by default), where the runs go (:func:`add_pool_options`, the run store ``store``; not for a study
    that makes no ``full_runs``), ``--out`` (default
    ``out``, else ``runs/NAME``; ``writes`` names what is written there; ``None``: the study writes no file) and
    ``--json`` (the result as one JSON object)."""
    parser = commands.add_parser(name, help=help)
    subject(parser)
    if full_runs:
        add_pool_options(parser, store)
    if writes is not None:
        out = out or f"runs/{name}"
        parser.add_argument(
            "--out", default=out, type=out_folder, metavar="DIR", help=f"where to write {writes} (default {out})"
        )
    parser.add_argument("--json", action="store_true", help="print the result as one JSON object")
    return parser


class _Renamed(argparse.Action):
    """An option's old spelling: refused in one line that names the new one (:func:`renamed`)."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: Any, values: Any, option: Any = None) -> None:
        parser.error(f"{option}: a former spelling; give {self.const}")


def renamed(parser: Parser, old: str, new: str) -> None:
    """Refuse ``old``, an option's former spelling, naming ``new`` (e.g. ``"--grid KEY=VALUES"``): hidden from the
    help, it takes a value if one follows so that the refusal, not the value, is what the user reads."""
    parser.add_argument(old, action=_Renamed, nargs="?", const=new, help=argparse.SUPPRESS)


def pool(args: argparse.Namespace) -> Pool:
    """The :class:`~cases.studies.Pool` the pool options describe."""
    from ..studies import Pool

    return Pool(args.workers, args.scheduler, args.progress)


@contextlib.contextmanager
def study(args: argparse.Namespace) -> Iterator[Pool]:
    """The pool the options describe, with one progress bar named after the command for every run the block
    makes; the bar closes when the block ends, before the command prints its result beside it."""
    from ..studies.engine.pool import study_progress

    with study_progress(args.command):
        yield pool(args)


@contextlib.contextmanager
def quiet_start() -> Iterator[Callable[[], None]]:
    """Python's cyclic garbage collector at rest while a command starts; yields the call that ends the start.

    Starting a run makes about 60 000 objects that live as long as the process (modules, classes,
    pydantic's validators, the scene) and next to no garbage: the collector would traverse them in some
    80 passes as they are made, for nothing (about 15 ms of test 2's process).  Here it rests until the
    command calls ``started()``, which
    freezes what exists (:func:`gc.freeze`: out of the collector's reach) and wakes the collector for
    what the command makes afterwards.  When the block ends the frozen objects go back to the oldest
    generation, so a caller of :func:`cases.cli.main` in a longer process keeps its collector as it was.
    Nothing changes when the collector was off or objects were frozen already (someone else's choice).
    """
    if not gc.isenabled() or gc.get_freeze_count():
        yield lambda: None
        return
    frozen = False

    def started() -> None:
        nonlocal frozen
        if not frozen:
            gc.freeze()
            frozen = True
            gc.enable()

    gc.disable()
    try:
        yield started
    finally:
        if frozen:
            gc.unfreeze()
        gc.enable()


@contextlib.contextmanager
def environment_defaults(**values: str) -> Iterator[None]:
    """Environment variables set for the block where the user has not set them (their value stands),
    removed again after it; processes started in the block inherit them."""
    added = {name: value for name, value in values.items() if name not in os.environ}
    os.environ.update(added)
    try:
        yield
    finally:
        for name in added:
            os.environ.pop(name, None)


def print_json(record: Any) -> None:
    """Print ``record`` as one JSON object: NaN and infinities as null, never as the bare ``NaN`` strict readers
    refuse (the run store's rule, :func:`~cases.run.persistence.json_safe`)."""
    from ..run.persistence import json_text

    print(json_text(record, indent=None))


def table_records(table: pd.DataFrame) -> list[dict]:
    """A table's rows as the records of a ``--json`` object (NaN as null, as JSON gives them)."""
    import json

    return json.loads(table.to_json(orient="records"))
