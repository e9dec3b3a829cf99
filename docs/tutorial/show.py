"""Print what a ``penetrate`` command prints, as a fenced block of docs/tutorial.md, with the machine's stamp.

Usage (from the repository root)::

    python -m docs.tutorial.show run docs/tutorial/my_projectile.toml
"""

from __future__ import annotations

import contextlib
import io
import sys

from cases.cli import main as penetrate
from docs.measure import stamp


def show(arguments: list[str]) -> str:
    """The command's standard output in a ``text`` block, then the stamp (its step counts hang on round-off)."""
    output = io.StringIO()
    with contextlib.redirect_stdout(output):
        status = penetrate(arguments)
    if status:
        raise SystemExit(f"penetrate {' '.join(arguments)} ended with {status}")
    return f"```text\n{output.getvalue().rstrip()}\n```\n\n{stamp()}"


if __name__ == "__main__":
    print(show(sys.argv[1:]))
