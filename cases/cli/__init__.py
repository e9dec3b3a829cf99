"""The ``penetrate`` command: a thin layer that reads options, calls ``cases`` and prints.

Each command's parser and handler sit side by side in its module (:mod:`.run`, :mod:`.sweep`,
:mod:`.speeds`, :mod:`.studies`, :mod:`.validate`, :mod:`.ensemble`, :mod:`.fit`, :mod:`.render`).  Errors are
told apart by type: an
:class:`~cases.scene.InputError` (a scene, an option, a file) is bad input, exit code 2; any
other failure of a run or study is exit code 1.  Nothing imports this room; what it may import is
written once, in pyproject.toml's [tool.penetrate.rooms].
"""

from __future__ import annotations

import atexit
import gc
import os
import sys
import warnings

from ..scene import InputError, one_line
from . import ensemble, fit, formulas, render, run, speeds, studies, sweep, validate
from .descriptions import DESCRIPTIONS
from .options import Parser, environment_defaults

__all__ = ["main", "build_parser"]

COMMANDS = (run, sweep, speeds, studies, validate, formulas, ensemble, fit, render)


def build_parser() -> Parser:
    parser = Parser(prog="penetrate", description="Rigid projectile penetration with the differential area force law.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of failures")
    commands = parser.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        command.register(commands)
    for name, subparser in commands.choices.items():
        subparser.description = DESCRIPTIONS[name]  # a command without one fails here, at its first use
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command; every failure ends in one line on stderr and a non-zero exit code.

    2: bad input (scene, options); 1: a run or study that failed; 130: interrupted.
    """
    _no_collection_at_exit()
    args = build_parser().parse_args(argv)
    try:
        # pydantic looks for plugins among the entry points of every installed distribution at its first
        # model (3 ms here, more in a larger environment); penetrate uses none: its documented switch
        with warnings.catch_warnings(), environment_defaults(PYDANTIC_DISABLE_PLUGINS="__all__"):
            if not args.debug:
                # numpy's floating-point warnings of a diverging run would spill over several lines;
                # the run's end reason (non_finite) or its error says what happened
                warnings.filterwarnings("ignore", category=RuntimeWarning)
            return args.handler(args)
    except InputError as exc:
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


def _no_collection_at_exit() -> None:
    """Leave the process's objects to the operating system at exit instead of collecting them.

    After the atexit handlers the interpreter clears every module and runs its cyclic garbage
    collector over what is left, freeing the whole heap object by object: about 30 ms after a run
    (numpy's and pydantic's modules, classes and validators), a tenth of test 2's process.
    :func:`gc.freeze` as an atexit handler moves every object out of the
    collector's reach, so the final collections find nothing to traverse; the memory goes back with
    the process.  Nothing is lost: files are closed and flushed by the code that writes them, and
    Python does not promise to finalise the objects still alive at exit.
    """
    atexit.unregister(gc.freeze)  # once, however often main() is called in one process
    atexit.register(gc.freeze)
