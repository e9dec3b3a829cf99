"""The table of the rooms, printed from its one source: ``[tool.penetrate.rooms]`` in pyproject.toml.

``python -m docs.rooms`` prints each room's job and what it may import (docs/architecture.md);
``python -m docs.rooms --jobs`` the jobs alone (the README's layout); ``python -m docs.rooms --studies`` the
packages of ``cases/studies/``, each with what its ``__init__`` says it holds and its modules.
"""

from __future__ import annotations

import argparse
import ast
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


def studies() -> list[tuple[str, str, list[str]]]:
    """Each package of ``cases/studies/``: its folder, the first sentence of its ``__init__``'s docstring, its
    modules."""
    found = []
    for init in sorted((ROOT / "cases" / "studies").glob("*/__init__.py")):
        text = " ".join((ast.get_docstring(ast.parse(init.read_text())) or "").split()).replace("``", "`")
        modules = sorted(p.name for p in init.parent.glob("*.py") if p.name != "__init__.py")
        found.append((init.parent.name, text.split(". ")[0].rstrip("."), modules))
    return found


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m docs.rooms", description=(__doc__ or "").split("\n")[0])
    parser.add_argument("--jobs", action="store_true", help="the jobs alone (no imports column)")
    parser.add_argument("--studies", action="store_true", help="the packages of cases/studies/ and their modules")
    options = parser.parse_args(argv)
    if options.studies:
        print("| package | what it holds | modules |\n|---|---|---|")
        for name, text, modules in studies():
            print(f"| `cases/studies/{name}/` | {text} | {', '.join(f'`{m}`' for m in modules)} |")
        return
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
