"""Run command lines that must fail and print what they print, for the docs to quote.

Run from the repository root, one quoted command line per argument::

    python -m docs.errors "penetrate run cases/paper_p3.toml --set impact.attack_angle=120"

Prints a markdown table: the command, its exit code and its error output (one line each, as
the command prints it), so a page quotes only messages the code really prints.
"""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main(commands: list[str]) -> None:
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}", COLUMNS="200")
    print("| command | exit code | what it prints (standard error) |")
    print("|---|---|---|")
    for line in commands:
        done = subprocess.run(shlex.split(line), cwd=ROOT, env=env, capture_output=True, text=True)
        message = " / ".join(done.stderr.strip().splitlines()) or "(nothing)"
        cell = message.replace("|", "\\|")
        print(f"| `{line}` | {done.returncode} | `{cell}` |")


if __name__ == "__main__":
    main(sys.argv[1:])
