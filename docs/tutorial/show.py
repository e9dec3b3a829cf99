"""Print what a ``penetrate`` command prints, as a fenced block of docs/tutorial.md, with the machine's stamp.

Usage (from the repository root)::

    python -m docs.tutorial.show run docs/tutorial/my_projectile.toml
"""

from __future__ import annotations

import sys

from docs.measure import penetrate_output, stamp


def show(arguments: list[str]) -> str:
    """The command's standard output in a ``text`` block, then the stamp (its step counts hang on round-off)."""
    return f"```text\n{penetrate_output(arguments).rstrip()}\n```\n\n{stamp()}"


if __name__ == "__main__":
    print(show(sys.argv[1:]))
