"""The ``penetrate`` command: a thin layer that reads options, calls ``cases`` and prints.

Each command's parser and handler sit side by side in its module (:mod:`.run`, :mod:`.sweep`,
:mod:`.speeds`, :mod:`.studies`, :mod:`.render`).  Errors are told apart by type: an
:class:`~cases.scene.InputError` (a scene, an option, a file) is bad input, exit code 2; any
other failure of a run or study is exit code 1.  Nothing imports this room.
"""

from __future__ import annotations

import os
import sys
import warnings

from . import render, run, speeds, studies, sweep
from .options import Parser

__all__ = ["main", "build_parser"]

COMMANDS = (run, sweep, speeds, studies, render)


def build_parser() -> Parser:
    parser = Parser(prog="penetrate", description="Rigid projectile penetration with the differential area force law.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of failures")
    commands = parser.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        command.register(commands)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command; every failure ends in one line on stderr and a non-zero exit code.

    2: bad input (scene, options); 1: a run or study that failed; 130: interrupted.
    """
    from ..scene import InputError, one_line

    args = build_parser().parse_args(argv)
    try:
        with warnings.catch_warnings():
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
