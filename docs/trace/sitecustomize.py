"""Loaded by every Python process a traced docs command starts (docs.inputs puts this folder first on PYTHONPATH):
an audit hook appends each file the process opens under ``$PENETRATE_TRACE_ROOT`` to ``$PENETRATE_TRACE_FILE``, one
line ``r PATH`` (read) or ``w PATH`` (written).  A forked worker inherits the hook and the open file; a started one
loads this module again.  Lines are written whole with O_APPEND, so processes do not interleave them."""

import os
import sys

_ROOT = os.environ.get("PENETRATE_TRACE_ROOT", "")
_FILE = os.environ.get("PENETRATE_TRACE_FILE", "")
_WRITE_FLAGS = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_APPEND | os.O_TRUNC

if _ROOT and _FILE:
    _fd = os.open(_FILE, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    _seen: set[tuple[str, str]] = set()

    def _hook(event: str, args: tuple) -> None:
        if event != "open" or not isinstance(args[0], str | bytes | os.PathLike):
            return
        path = os.path.abspath(os.fsdecode(args[0]))
        if not path.startswith(_ROOT + os.sep):
            return
        mode, flags = args[1], args[2]
        written = any(c in mode for c in "wax+") if isinstance(mode, str) else bool((flags or 0) & _WRITE_FLAGS)
        key = ("w" if written else "r", path)
        if key not in _seen:
            _seen.add(key)
            os.write(_fd, f"{key[0]} {path}\n".encode())

    sys.addaudithook(_hook)
