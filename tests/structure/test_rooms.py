"""The shape of the code: imports flow one way, no circles, small modules and functions, rooms that say their job.

The rules:

* every import between rooms is one the table of the rooms allows: ``[tool.penetrate.rooms]`` in
  pyproject.toml, the one place the rooms, their jobs and what each may import are written
  (docs/architecture.md prints it); every room is in the table and every room in the
  table exists; nothing imports the command line;
* no import circle between modules (imports inside functions count too);
* no module over 500 lines, no function over 80 logical lines of code (statements and clause headers,
  however the formatter wraps them; docstrings, comments and blank lines not counted);
* every package's ``__init__`` says its job in its docstring, and a room's points to the table for what
  it may import rather than repeating it;
* no issue numbers in the repository (they mean nothing to a reader of it).
"""

from __future__ import annotations

import ast
import functools
import io
import re
import tokenize
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("mesh", "fem_loads", "dynamics", "cases")
MAX_MODULE_LINES, MAX_FUNCTION_LINES = 500, 80

# room -> the rooms it may import (its own always allowed), read from the one table of the rooms in
# pyproject.toml; an entry that is a module of a room, not a room (``cases.viz.figures``), allows that
# module of the room only
ROOMS = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["penetrate"]["rooms"]


def _allowed() -> tuple[dict[str, set[str]], dict[tuple[str, str], set[str]]]:
    allowed: dict[str, set[str]] = {name: set() for name in ROOMS}
    narrow: dict[tuple[str, str], set[str]] = {}
    for name, spec in ROOMS.items():
        for entry in spec["imports"]:
            other = entry if entry in ROOMS else entry.rpartition(".")[0]
            assert other in ROOMS, f"pyproject.toml: room {name} may import {entry}, which is no room nor its module"
            allowed[name].add(other)
            if other != entry:
                narrow.setdefault((name, other), set()).add(entry)
    return allowed, narrow


ALLOWED, NARROW = _allowed()


def _modules() -> dict[str, Path]:
    out = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            out[name] = path
    return out


MODULES = _modules()


def _is_package(name: str) -> bool:
    return MODULES[name].name == "__init__.py"


def _imports(name: str) -> set[str]:
    """The project modules ``name`` imports, anywhere in it (resolved: ``from .x import y`` -> ``pkg.x`` or
    ``pkg.x.y`` when that is a module)."""
    tree = ast.parse(MODULES[name].read_text())
    package = name if _is_package(name) else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            targets = [
                f"{module}.{alias.name}" if f"{module}.{alias.name}" in MODULES else module for alias in node.names
            ]
        else:
            continue
        for target in targets:
            while target and target not in MODULES:
                target = target.rpartition(".")[0]
            if target and target.split(".")[0] in PACKAGES:
                found.add(target)
    return found - {name}


GRAPH = {name: _imports(name) for name in MODULES}


def room(module: str) -> str:
    """The room a module belongs to: a physics package, ``cases`` (its root) or a sub-package of ``cases``."""
    parts = module.split(".")
    if parts[0] != "cases":
        return parts[0]
    if len(parts) >= 2 and (ROOT / "cases" / parts[1]).is_dir():
        return f"cases.{parts[1]}"
    return "cases"


def test_the_import_graph_is_read():
    """The reader sees relative, absolute and function-level imports (a check that could not fail otherwise)."""
    assert "dynamics.simulate" in GRAPH["cases.run.runner"]
    assert "cases.scene" in GRAPH["cases.run.prepare"]
    assert "fem_loads" in {room(t) for t in GRAPH["cases.scene.schema"]}
    assert "cases.run" in {room(t) for t in GRAPH["cases.cli.run"]}  # imported inside the handler


def test_imports_flow_one_way():
    wrong = []
    for module, targets in GRAPH.items():
        own = room(module)
        for target in targets:
            other = room(target)
            if other == own:
                continue
            if other not in ALLOWED[own]:
                wrong.append(f"{module} imports {target} ({own} may import {sorted(ALLOWED[own]) or 'nothing'})")
            elif (own, other) in NARROW and not any(target.startswith(t) for t in NARROW[(own, other)]):
                wrong.append(f"{module} imports {target} ({own} may use {other} only for {NARROW[(own, other)]})")
    assert not wrong, "\n".join(wrong)


def test_nothing_imports_the_command_line():
    users = [
        m for m, targets in GRAPH.items() if room(m) != "cases.cli" and any(room(t) == "cases.cli" for t in targets)
    ]
    assert not users


def test_no_import_circle():
    state: dict[str, int] = {}
    circles = []

    def visit(module: str, path: list[str]) -> None:
        state[module] = 1
        for target in sorted(GRAPH[module]):
            if state.get(target) == 1:
                circles.append(" -> ".join(path[path.index(target) :] + [target]))
            elif target not in state:
                visit(target, path + [target])
        state[module] = 2

    for module in sorted(GRAPH):
        if module not in state:
            visit(module, [module])
    assert not circles, "\n".join(circles)


def _code_lines(source: str, node: ast.AST) -> int:
    """Logical lines of code in a function: statements and clause headers, however the formatter wraps them
    (a call split over five lines is one line), not comments, blank lines or its docstring."""
    lines = set(range(node.lineno, node.end_lineno + 1))
    body = node.body
    if (
        body
        and isinstance(body[0], ast.Expr)
        and isinstance(body[0].value, ast.Constant)
        and isinstance(body[0].value.value, str)
    ):
        lines -= set(range(body[0].lineno, body[0].end_lineno + 1))
    return len(lines & _statement_ends(source))


@functools.lru_cache(maxsize=8)
def _statement_ends(source: str) -> frozenset[int]:
    """The lines on which the statements of ``source`` end (tokenised once a module, not once a function)."""
    tokens = tokenize.generate_tokens(io.StringIO(source).readline)
    return frozenset(tok.end[0] for tok in tokens if tok.type == tokenize.NEWLINE)


@pytest.mark.parametrize("module", sorted(MODULES))
def test_small_modules_and_functions(module):
    source = MODULES[module].read_text()
    assert len(source.splitlines()) <= MAX_MODULE_LINES, f"{module}: {len(source.splitlines())} lines"
    long = [
        f"{node.name}: {n} lines"
        for node in ast.walk(ast.parse(source))
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
        and (n := _code_lines(source, node)) > MAX_FUNCTION_LINES
    ]
    assert not long, f"{module}: {long}"


def test_the_length_rule_counts_code_only():
    source = "def f():\n    '''doc\n    more'''\n    # why\n\n    x = 1\n    return x  # done\n"
    assert _code_lines(source, ast.parse(source).body[0]) == 3
    wrapped = (
        "def f():\n    x = g(\n        1,\n        2,\n    )\n    if x:\n        return [\n            x\n        ]\n"
    )
    assert _code_lines(wrapped, ast.parse(wrapped).body[0]) == 4  # def, x = g(...), if, return


@pytest.mark.parametrize("package", sorted(m for m in MODULES if _is_package(m)))
def test_every_room_says_its_job_and_points_to_the_table(package):
    doc = ast.get_docstring(ast.parse(MODULES[package].read_text())) or ""
    assert len(doc) > 40, f"{package}: no docstring saying its job"
    if package in ROOMS:
        assert "[tool.penetrate.rooms]" in doc, f"{package}: the docstring does not point to the table of the rooms"


ISSUE_NUMBER = re.compile(r"(?i)\bissues?\s*#?\d+")


def test_no_issue_numbers_in_the_repository():
    found = []
    for path in sorted(ROOT.rglob("*")):
        parts = path.relative_to(ROOT).parts
        if (
            not path.is_file()
            or parts[0] in (".git", ".venv", "runs", "build", "dist")
            or "__pycache__" in parts
            or path.suffix not in (".py", ".md", ".toml", ".txt", ".cfg", "")
        ):
            continue
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            if ISSUE_NUMBER.search(line):
                found.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()[:80]}")
    assert not found, "\n".join(found)


def test_every_room_is_declared():
    """A new sub-package of ``cases`` must be given its row in the table of the rooms (pyproject.toml)."""
    rooms = {room(module) for module in MODULES}
    assert rooms == set(ALLOWED), rooms ^ set(ALLOWED)


def test_the_tests_of_cases_are_split_by_room():
    """``tests/cases`` holds one folder per room of ``cases`` (and no test module of its own), so a room's
    tests are found where the room is."""
    folder = ROOT / "tests" / "cases"
    assert not list(folder.glob("test_*.py")), "a test module directly in tests/cases: move it to its room's folder"
    rooms = {name.split(".", 1)[1] for name in ROOMS if name.startswith("cases.") and name != "cases.bodies"}
    present = {p.name for p in folder.iterdir() if p.is_dir() and p.name != "__pycache__"}
    assert present <= rooms, present - rooms
    assert rooms <= present, f"rooms with no tests: {rooms - present}"
