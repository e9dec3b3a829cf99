"""What a generated block's command depends on: the repository's files it reads, and a digest of each.

A regeneration runs each command traced: every Python process the command starts loads ``docs/trace/sitecustomize.py``
(that folder comes first on its ``PYTHONPATH``), whose audit hook lists each file the process opens under the
repository's root.  The files it read and did not write (a module read from its cached byte code counts as its
source), less the pages themselves and what git ignores (run stores), are the block's inputs; each one's digest is
kept in ``docs/inputs.json``.  Python source is digested as its syntax tree, so a comment or a
re-wrapped line changes nothing, while any change of code or data does.

The digest check (``./dev docs --check``, CI's first step) recomputes the digests of every block's files: a block
whose inputs changed since it was generated fails, so the change that could move a block's result fails its own CI,
whatever the day.  ``./dev docs --stale`` regenerates those blocks and nothing else.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import json
import os
from collections.abc import Callable
from pathlib import Path

HOOK_FOLDER = Path(__file__).resolve().with_name("trace")


def environment(root: Path, trace_file: Path) -> dict[str, str]:
    """The environment variables that make a command's Python processes list what they open under ``root``."""
    path = os.environ.get("PYTHONPATH", "")
    return {
        "PYTHONPATH": f"{HOOK_FOLDER}{os.pathsep}{path}" if path else str(HOOK_FOLDER),
        "PENETRATE_TRACE_ROOT": str(root),
        "PENETRATE_TRACE_FILE": str(trace_file),
    }


def _source(path: Path) -> Path:
    """A cached module's source: ``pkg/__pycache__/name.cpython-311.pyc`` is ``pkg/name.py``."""
    if path.suffix == ".pyc" and path.parent.name == "__pycache__":
        return path.parent.parent / (path.name.split(".")[0] + ".py")
    return path


def traced_inputs(trace_file: Path, root: Path, ignored: Callable[[Path], bool]) -> list[str]:
    """The files (relative to ``root``, sorted) that a traced command read and did not write, less the markdown
    pages, the hook itself and what ``ignored`` says git ignores."""
    read, written = set(), set()
    lines = trace_file.read_text().splitlines() if trace_file.exists() else []
    for line in lines:
        kind, _, name = line.partition(" ")
        path = _source(Path(name))
        (written if kind == "w" else read).add(path)
    kept = []
    for path in read - written:
        relative = path.relative_to(root)
        if path.suffix == ".md" or HOOK_FOLDER in path.parents or ignored(relative) or not path.is_file():
            continue
        kept.append(relative.as_posix())
    return sorted(kept)


def _content(path: Path) -> bytes:
    """What of a file counts: Python source as its syntax tree (comments and layout do not count), else its bytes."""
    if not path.exists():
        return b"(missing)"
    raw = path.read_bytes()
    return _syntax_tree(raw) if path.suffix == ".py" else raw


@functools.lru_cache(maxsize=512)
def _syntax_tree(source: bytes) -> bytes:
    """Python ``source``'s syntax tree, dumped (its bytes when it does not parse): once per source text in a
    process, since one check reads the same modules for most of its 91 blocks."""
    try:
        return ast.dump(ast.parse(source.decode())).encode()
    except (SyntaxError, UnicodeDecodeError):
        return source


def digest(files: list[str], root: Path) -> str:
    """16 hex digits of SHA-256 over the files' names and contents."""
    sha = hashlib.sha256()
    for name in files:
        sha.update(name.encode() + b"\0" + _content(root / name) + b"\0")
    return sha.hexdigest()[:16]


def load(path: Path) -> dict[str, dict]:
    """The recorded inputs, by block key: ``{"digests": {file: digest}}``."""
    return json.loads(path.read_text()) if path.exists() else {}


def save(path: Path, records: dict[str, dict]) -> None:
    path.write_text(json.dumps(dict(sorted(records.items())), indent=1) + "\n")


def changed(record: dict, root: Path) -> list[str]:
    """The files of a block's record whose contents changed since it was made (empty: its inputs hold)."""
    return [name for name, recorded in record["digests"].items() if digest([name], root) != recorded]


def record(files: list[str], root: Path) -> dict:
    """A block's record: the digest of each file it read, by name."""
    return {"digests": {name: digest([name], root) for name in files}}
