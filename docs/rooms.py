"""The table of the rooms, printed from its one source: ``[tool.penetrate.rooms]`` in pyproject.toml.

``python -m docs.rooms`` prints each room's job and what it may import (docs/architecture.md);
``python -m docs.rooms --jobs`` the jobs alone (the README's layout).
"""

from __future__ import annotations

import argparse
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PHYSICS = ("mesh", "fem_loads", "dynamics")


def rooms() -> dict[str, dict]:
    """The table, in the order pyproject.toml gives it."""
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["penetrate"]["rooms"]


def folder(name: str) -> str:
    return "`" + name.replace(".", "/") + "/`"


def may_import(imports: list[str]) -> str:
    """What a room may import, in words: "the physics" for all three physics packages."""
    if not imports:
        return "nothing of the project"
    names = [f"`{name}`" for name in imports if name not in PHYSICS]
    physics = [name for name in PHYSICS if name in imports]
    if len(physics) == len(PHYSICS):
        names.append("the physics")
    else:
        names += [f"`{name}`" for name in physics]
    return ", ".join(names)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m docs.rooms", description=(__doc__ or "").split("\n")[0])
    parser.add_argument("--jobs", action="store_true", help="the jobs alone (no imports column)")
    options = parser.parse_args(argv)
    table = rooms()
    if options.jobs:
        print("| room | one job |\n|---|---|")
        for name, spec in table.items():
            print(f"| {folder(name)} | {spec['job']} |")
        return
    print("| room | one job | may import |\n|---|---|---|")
    for name, spec in table.items():
        print(f"| {folder(name)} | {spec['job']} | {may_import(spec['imports'])} |")


if __name__ == "__main__":
    main()
