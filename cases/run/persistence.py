"""Everything written to disk: one atomic write, and one content-addressed cache.

Atomic writes
-------------
:func:`atomic_path` yields a hidden temporary path beside the target
(``.NAME.PID.RANDOM.tmp``); what the caller writes there is synced and renamed
into place, so a reader, or a process killed at any moment, sees the old file
or the new one, never a part.  A kill can leave the temporary file; a later
write into the same folder by another process removes those of processes that
no longer run.  :func:`atomic_write` writes bytes that way.  Every file this
project writes goes through it: meshes, prepared arrays, runs, tables,
figures, ParaView files.

The cache
---------
:class:`ContentCache` names each entry by the digest of what it was computed
from *and of the code that computed it* (:func:`code_version`: the source of
the packages involved and the versions of the libraries they call).  A change
of that code therefore never serves a stale entry: it computes a new one.
Three kinds of entries use it: meshes (``mesh/``), prepared arrays
(``prepared/``: mass properties and surface quadrature) under
``$PENETRATE_CACHE_DIR``, and finished runs in a run store (:class:`RunStore`).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib.metadata
import importlib.util
import io
import json
import math
import os
import re
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # imported where used (slow to import)
    import pandas as pd
    from matplotlib.figure import Figure

__all__ = [
    "atomic_path",
    "atomic_write",
    "atomic_write_text",
    "remove_stale_temporaries",
    "json_safe",
    "write_json",
    "json_text",
    "code_version",
    "installed_version",
    "ContentCache",
    "cache_dir",
    "save_figure_bytes",
    "RunStore",
]

# the code each kind of cache entry is computed by: packages (or modules) and the libraries they call
CODE = {
    "mesh": (("mesh",), ("gmsh", "meshio", "numpy")),
    "prepared": (("mesh", "fem_loads", "cases.scene", "cases.run.prepare"), ("gmsh", "meshio", "numpy", "scikit-fem")),
    "run": (
        ("mesh", "fem_loads", "dynamics", "cases.scene", "cases.run"),
        ("gmsh", "meshio", "numpy", "scikit-fem", "scipy"),
    ),
}


@functools.cache
def _umask() -> int:
    """The process's umask, read without changing it where the system tells it (Linux); once per process (this
    project never changes it; reading it at every write cost the 1 024 full runs of an ensemble about 1.6 s)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary path to write ``path``'s new content to; renamed into place when the block ends.

    The file is synced before the rename and the folder after it; it gets the usual permissions
    (``0666`` less the umask), not a temporary file's ``0600``.  If the block raises, the
    temporary file is removed and ``path`` is left as it was.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp")
    os.close(fd)
    try:
        yield Path(tmp)
        with open(tmp, "rb+") as f:
            os.fchmod(f.fileno(), 0o666 & ~_umask())
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    try:  # make the rename itself durable
        directory = os.open(path.parent, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(directory)
    except OSError:
        pass
    finally:
        os.close(directory)


def atomic_write(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (:func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def atomic_write_text(path: str | os.PathLike, text: str) -> Path:
    """:func:`atomic_write` of UTF-8 text."""
    return atomic_write(path, text.encode("utf-8"))


def save_figure_bytes(figure: Figure, path: str | os.PathLike, dpi: int = 110) -> Path:
    """A matplotlib figure saved as PNG through :func:`atomic_write`."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=dpi)
    return atomic_write(path, buffer.getvalue())


def _running(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # exists, owned by someone else
        return True
    return True


# the temporaries of dead writers in each folder this process has written into, by the name they
# were for: a folder is listed once per process, not at every write (a run store holds thousands
# of files, and listing it cost 19 ms per write at 20 000)
_STALE_TEMPORARIES: dict[Path, dict[str, list[Path]]] = {}
_TEMPORARY_NAME = re.compile(r"^\.(?P<name>.+)\.(?P<pid>\d+)\.[^.]+\.tmp$")


def _dead_writers_temporaries(folder: Path) -> dict[str, list[Path]]:
    stale: dict[str, list[Path]] = {}
    with contextlib.suppress(OSError):
        for entry in os.scandir(folder):
            match = _TEMPORARY_NAME.match(entry.name)
            if match and not _running(int(match["pid"])):
                stale.setdefault(match["name"], []).append(Path(entry.path))
    return stale


def remove_stale_temporaries(path: str | os.PathLike) -> list[Path]:
    """Remove the temporary files of :func:`atomic_path` for ``path`` left by killed processes.

    Only files named ``.NAME.PID.*.tmp`` whose process no longer runs are removed
    (a live writer's file is left alone).  The folder is listed at this process's
    first write into it; temporaries left later by other killed processes wait for
    the next process.  Returns the removed paths.
    """
    path = Path(path)
    folder = Path(os.path.abspath(path.parent))  # one entry per folder however it is named
    if folder not in _STALE_TEMPORARIES:
        _STALE_TEMPORARIES[folder] = _dead_writers_temporaries(folder)
    removed = _STALE_TEMPORARIES[folder].pop(path.name, [])
    for tmp in removed:
        tmp.unlink(missing_ok=True)
    return removed


def json_safe(value: Any) -> Any:
    """``value`` with every non-finite float replaced by None (JSON ``null``), through lists and dicts."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    return value


def json_text(record: Any, indent: int | None = 1) -> str:
    """``record`` as JSON text: every non-finite number as ``null`` (:func:`json_safe`), so that strict readers
    take it, and anything else JSON cannot hold refused (``TypeError``), never written as its ``str``.  The one
    way penetrate writes JSON, to a file (:func:`write_json`, a run's summary) or to the screen (``--json``)."""
    return json.dumps(json_safe(record), indent=indent, allow_nan=False)


def write_json(path: str | os.PathLike, record: Any, indent: int = 1) -> Path:
    """Write ``record`` to ``path`` as :func:`json_text`, atomically: the one way a run or a study writes its
    record."""
    return atomic_write_text(path, json_text(record, indent) + "\n")


def _source_files(module: str) -> tuple[Path, list[Path]]:
    """The folder holding the top-level package, and the ``.py`` files of a package (recursively) or module."""
    spec = importlib.util.find_spec(module)
    if spec is None or spec.origin is None:
        raise ImportError(f"{module}: not found")
    origin = Path(spec.origin)
    depth = module.count(".")
    if spec.submodule_search_locations:  # origin is the package's __init__.py
        return origin.parents[depth + 1], sorted(p for p in origin.parent.rglob("*.py") if "__pycache__" not in p.parts)
    return origin.parents[depth], [origin]


def installed_version(library: str) -> str:
    """``importlib.metadata.version(library)``, read off the ``Version:`` line of the distribution's metadata.

    The same text, found the same way: ``importlib.metadata`` parses the whole file as an e-mail
    message, after importing the e-mail parser (2 ms more for the four libraries of a prepared
    projectile), where the header's first lines say it.  A file without that line falls back to it.
    """
    distribution = importlib.metadata.distribution(library)
    text = distribution.read_text("METADATA") or distribution.read_text("PKG-INFO") or ""
    for line in text.splitlines():
        if not line.strip():  # the end of the header
            break
        name, colon, value = line.partition(":")
        if colon and name == "Version":
            return value.strip()
    return distribution.version


@functools.cache
def code_version(kind: str) -> str:
    """Digest of the code that computes a cache entry of ``kind`` (``mesh``, ``prepared``, ``run``).

    The bytes of every source file of the packages in :data:`CODE` (docstrings and
    comments too: any edit counts) and the installed versions of the libraries they
    call (:func:`installed_version`).  Computed once per process (about 2 ms).
    """
    modules, libraries = CODE[kind]
    digest = hashlib.sha256()
    for module in modules:
        root, files = _source_files(module)
        for path in files:
            digest.update(f"{path.relative_to(root).as_posix()}\0".encode())
            digest.update(path.read_bytes())
    for library in libraries:
        digest.update(f"{library}=={installed_version(library)}\0".encode())
    return digest.hexdigest()[:16]


def cache_dir() -> Path:
    """The cache folder of meshes and prepared arrays: ``$PENETRATE_CACHE_DIR`` or ``~/.cache/penetrate``."""
    root = os.environ.get("PENETRATE_CACHE_DIR")
    return Path(root) if root else Path.home() / ".cache" / "penetrate"


class ContentCache:
    """Files named by the digest of their inputs and of the code that computes them.

    Parameters
    ----------
    root : path
        The folder; entries of each kind go in a sub-folder named after the kind.
    """

    def __init__(self, root: str | os.PathLike) -> None:
        self.root = Path(root)

    @staticmethod
    def key(kind: str, inputs: Any) -> str:
        """The digest of ``inputs`` (anything JSON can write) and of :func:`code_version` of ``kind``."""
        record = {"kind": kind, "inputs": inputs, "code": code_version(kind)}
        text = json.dumps(record, sort_keys=True, default=repr)
        return hashlib.sha256(text.encode()).hexdigest()[:24]

    def path(self, kind: str, inputs: Any, suffix: str) -> Path:
        """Where the entry of ``kind`` computed from ``inputs`` is (or goes)."""
        return self.root / kind / f"{self.key(kind, inputs)}{suffix}"


class RunStore:
    """A folder of finished runs: ``run/<digest>.json`` (the record) and ``run/<digest>.csv.gz`` (the history).

    A run is found by its scene key (:func:`~cases.scene.scene_key` of the resolved scene); its
    files are named by :meth:`ContentCache.key` of that key and of the code of runs, so runs made
    by other code are never served.  The history is written first and the record last, each
    atomically: a store holds each run complete or not at all.  The folder is made at the first
    save, so a command that fails on bad input leaves nothing behind.
    """

    def __init__(self, root: str | os.PathLike) -> None:
        self.root = Path(root)
        if self.root.exists() and not self.root.is_dir():
            from ..scene import InputError

            raise InputError(f"{self.root}: the run store must be a folder, and this is a file")
        self._cache = ContentCache(self.root)

    def record_path(self, key: str) -> Path:
        return self._cache.path("run", key, ".json")

    def history_path(self, key: str) -> Path:
        return self._cache.path("run", key, ".csv.gz")

    def load(self, key: str) -> dict | None:
        """The stored record of a run (its summary and resolved scene, or its error), or None."""
        try:
            return json.loads(self.record_path(key).read_text())
        except (OSError, ValueError):
            return None

    def records(self) -> set[str]:
        """The file names of the records in the store (finished and failed runs), to count what a study adds."""
        folder = self.root / "run"
        return {path.name for path in folder.glob("*.json")} if folder.is_dir() else set()

    def finished(self, key: str) -> bool:
        record = self.load(key)
        return record is not None and "error" not in record

    def history(self, key: str) -> pd.DataFrame:
        """The stored (thinned) time history of a finished run, as a pandas DataFrame."""
        import pandas as pd

        return pd.read_csv(self.history_path(key))

    def save(self, key: str, record: dict, history_csv_gz: bytes | None) -> None:
        """Store a run: the history first, then the record that marks it finished."""
        text = json_text(record) + "\n"  # null, never NaN; a record JSON cannot hold stores nothing
        if history_csv_gz is not None:
            atomic_write(self.history_path(key), history_csv_gz)
        atomic_write(self.record_path(key), text.encode())
