"""Where the runs of a study go: local worker processes or a Dask distributed cluster.

Workers only compute: each returns a run's record and history to the process
that drives the study, which alone writes the run store.  Local workers are
processes (every core by default), forked from this one where that is safe
(:func:`start_method`); with ``scheduler`` the runs go to an existing Dask
cluster, whose workers import this project from their own environment.
Every worker reports the version of the code it ran
(:func:`~cases.run.persistence.code_version`), and a run made by other code
than the driver's is refused rather than stored under the driver's version.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import sys
import threading
from collections.abc import Callable, Collection, Iterable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from contextvars import ContextVar
from dataclasses import dataclass
from multiprocessing import get_context
from typing import TYPE_CHECKING, Any, Never

from ...run import RunStore, code_version, prepare_projectile
from ...run.prepare import preparation_key
from ...run.summary import simulate_record
from ...scene import Scene

if TYPE_CHECKING:
    from tqdm import tqdm

__all__ = [
    "Pool",
    "Progress",
    "study_progress",
    "run_missing",
    "run_job",
    "map_local",
    "start_method",
    "CodeMismatch",
]


class CodeMismatch(RuntimeError):
    """A worker runs other code than the process that drives the study."""


@dataclass(frozen=True)
class Pool:
    """Where runs go.

    Parameters
    ----------
    workers : int, optional
        Local processes (default: every core).
    scheduler : str, optional
        Address of a Dask distributed scheduler to run on instead.
    progress : bool, optional
        Show a progress bar (runs done, failed, time left) on stderr: True, False, or None (the default)
        when stderr is a terminal, so that a log file or a pipe gets no bar.
    """

    workers: int | None = None
    scheduler: str | None = None
    progress: bool | None = None

    @property
    def shows_progress(self) -> bool:
        """Whether runs on this pool draw a progress bar (``progress``, or whether stderr is a terminal)."""
        return sys.stderr.isatty() if self.progress is None else bool(self.progress)

    @property
    def width(self) -> int:
        """How many runs go at once: ``workers``, else the local cores (also the default round width of a study
        on a Dask cluster, whose size this process does not ask for)."""
        return self.workers or os.cpu_count() or 1


def run_job(scene_json: str) -> tuple[dict, bytes | None, str]:
    """A worker's job: run one resolved scene; its record, gzipped history and the version of the code that ran."""
    return (*simulate_record(scene_json), code_version("run"))


def prepare_job(scene_json: str) -> None:
    """Prepare a scene's projectile into the disk cache (a worker's job); errors surface in its runs."""
    # the runs of this projectile will fail and record why
    with contextlib.suppress(Exception):
        prepare_projectile(Scene.model_validate_json(scene_json))


def _distinct_projectiles(scenes: Sequence[Scene]) -> list[str]:
    """One scene (as JSON) per distinct projectile and mesh setting."""
    seen: dict[tuple, str] = {}
    for scene in scenes:
        seen.setdefault(preparation_key(scene), scene.model_dump_json())
    return list(seen.values())


class Progress:
    """One progress bar for all the runs of a study: runs done out of the runs known so far.

    A study that runs in rounds (a critical-speed search, a fit, the paper) learns its runs round by
    round: each sweep adds its runs to the total, and those found finished in the run store count as
    done at once.  A run counts once however many rounds name it; a failed run tried again counts
    again, as it runs again.  The bar opens at the first sweep that has runs to make, shown or not as
    that sweep's pool says (:attr:`Pool.shows_progress`), and closes with :meth:`close`.
    """

    def __init__(self, name: str) -> None:
        self.name = name
        self.known: set[str] = set()
        self.total = self.done = self.failed = 0
        self.shown: bool | None = None
        self.bar: tqdm[Never] | None = None

    def add(self, keys: Iterable[str], todo: Collection[str], show: bool) -> None:
        """A sweep's runs (``keys``), of which ``todo`` are still to make."""
        found = {key for key in keys if key not in todo and key not in self.known}
        self.known.update(found)
        self.known.update(todo)
        self.total += len(found) + len(todo)
        self.done += len(found)
        if self.shown is None and todo:
            self.shown = show
        if not self.shown:
            return
        if self.bar is None:
            from tqdm import tqdm

            # no monitor thread (miniters=1 redraws at every run instead), so that workers can still be forked
            tqdm.monitor_interval = 0
            self.bar = tqdm(
                total=self.total,
                initial=self.done,
                unit="run",
                desc=self.name,
                dynamic_ncols=True,
                miniters=1,
                file=sys.stderr,
            )
        else:
            self.bar.total = self.total  # the study has learnt of more runs: the bar's end moves out
            if found:
                self.bar.update(len(found))
            else:
                self.bar.refresh()

    def finished(self, failed: bool) -> None:
        """One run made (and stored)."""
        self.done += 1
        self.failed += failed
        if self.bar is not None:
            self.bar.set_postfix(failed=self.failed, refresh=False)
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


_STUDY: ContextVar[Progress | None] = ContextVar("penetrate_study_progress", default=None)


@contextlib.contextmanager
def study_progress(name: str) -> Iterator[Progress]:
    """Count every run made inside the block on one progress bar named ``name``, closed when the block ends.

    Blocks nest: an inner block (a critical-speed search inside a fit) counts on the outer one's bar, so a
    study shows one bar whatever it calls.  Outside any block each sweep has a bar of its own.
    """
    active = _STUDY.get()
    if active is not None:
        yield active
        return
    progress = Progress(name)
    token = _STUDY.set(progress)
    try:
        yield progress
    finally:
        _STUDY.reset(token)
        progress.close()


def run_missing(todo: dict[str, Scene], store: RunStore, pool: Pool, keys: Iterable[str]) -> None:
    """Run the scenes of ``todo`` (scene key -> scene) on ``pool`` and save each in ``store`` as it finishes;
    ``keys``: every run of the sweep, those found in the store included (they count as done on the bar)."""
    with study_progress("sweep") as progress:
        progress.add(keys, todo, pool.shows_progress)
        if not todo:
            return
        jobs = {key: scene.model_dump_json() for key, scene in todo.items()}
        own = code_version("run")

        def finish(key: str, record: dict, history: bytes | None, code: str) -> None:
            if code != own:
                raise CodeMismatch(
                    f"a worker ran code version {code}, this process has {own}: install the same"
                    " version of penetrate on every worker of the cluster"
                )
            store.save(key, record, history)
            progress.finished("error" in record)

        if pool.scheduler:
            _on_dask(jobs, pool.scheduler, finish)
        else:
            _compile_once(todo.values(), pool.width)
            _on_processes(jobs, list(todo.values()), pool.width, finish)


def start_method() -> str:
    """How local workers start: ``"fork"`` on Linux when this process runs a single thread, else ``"spawn"``.

    A forked worker begins with this process's imports and the machine code it has loaded: it is ready in
    milliseconds, where a spawned one imports numpy, scipy, numba and this project and loads the compiled
    step again (about 1.5 s on 2 cores; a critical-speed search of #3 takes about half its time without it).
    A process with other threads (pytest-xdist's workers, a Dask client, a pool already running) spawns,
    because a thread may hold a lock at the moment of the fork that the child then waits for forever.
    """
    return "fork" if sys.platform == "linux" and threading.active_count() == 1 else "spawn"


def _compile_once(scenes: Iterable[Scene], width: int) -> None:
    """Compile the compiled step here, once (announced), before local workers start, when the cache lacks it
    and a run will take it: else every worker compiles it side by side, each saying so.  When the workers
    are about to be forked, also load it from the cache here, so that they start with it loaded."""
    from ...run.compiled import needs_compiling, precompile

    compiled = any(scene.with_kernel(many_runs=True).numerics.kernel == "compiled" for scene in scenes)
    forking = width not in _WARM and start_method() == "fork"
    if width > 1 and compiled and (forking or needs_compiling("dafl_step")):
        precompile()


def map_local(function: Callable[..., Any], jobs: Sequence[tuple], width: int) -> list:
    """``function(*job)`` for each of ``jobs``, in order, on ``width`` local processes (the study's warm workers,
    forked when :func:`start_method` allows): work that is not a run, such as the reduced model's sort of
    an ensemble's samples.  ``function`` must be importable by name (a module's top-level function)."""
    if width == 1 or len(jobs) <= 1:
        return [function(*job) for job in jobs]
    return list(_warm_executor(width).map(function, *zip(*jobs)))


# what a finished run is handed to: its key, record, gzipped history and code version (run_job's result)
_Finish = Callable[[str, dict, bytes | None, str], None]


def _on_dask(jobs: dict[str, str], scheduler: str, finish: _Finish) -> None:
    from distributed import Client
    from distributed import as_completed as dask_completed

    with Client(scheduler) as client:
        futures = {client.submit(run_job, text, pure=False): key for key, text in jobs.items()}
        for future in dask_completed(futures):
            finish(futures[future], *future.result())


_WARM: dict[int, ProcessPoolExecutor] = {}


def _warm_executor(count: int) -> ProcessPoolExecutor:
    """``count`` workers (:func:`start_method`), kept for the rest of this process: a study that runs in rounds
    (the bisection of a critical speed) finds them with their imports done and their projectiles prepared,
    instead of starting and preparing them again each round."""
    if count not in _WARM:
        _WARM[count] = ProcessPoolExecutor(count, mp_context=get_context(start_method()))
    return _WARM[count]


@atexit.register
def _shut_down_warm_executors() -> None:
    for executor in _WARM.values():
        executor.shutdown(wait=True, cancel_futures=True)
    _WARM.clear()


def _on_processes(jobs: dict[str, str], scenes: list[Scene], count: int, finish: _Finish) -> None:
    if count == 1:
        for key, text in jobs.items():
            finish(key, *run_job(text))
        return
    executor = _warm_executor(count)
    futures = {}
    try:
        # mesh and prepare each projectile once, in parallel, into the disk cache, before the runs that read it
        for done in [executor.submit(prepare_job, text) for text in _distinct_projectiles(scenes)]:
            done.result()
        futures = {executor.submit(run_job, text): key for key, text in jobs.items()}
        for future in as_completed(futures):
            finish(futures[future], *future.result())
    except BaseException as exc:
        for future in futures:  # a round that fails leaves nothing running behind it
            future.cancel()
        if isinstance(exc, BrokenProcessPool) or not isinstance(exc, Exception):
            _WARM.pop(count, None)  # a broken or interrupted pool is not reused
            executor.shutdown(wait=False, cancel_futures=True)
        raise
