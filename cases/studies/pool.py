"""Where the runs of a study go: local worker processes or a Dask distributed cluster.

Workers only compute: each returns a run's record and history to the process
that drives the study, which alone writes the run store.  Local workers are
spawned processes (every core by default); with ``scheduler`` the runs go to
an existing Dask cluster, whose workers import this project from their own
environment.  Every worker reports the version of the code it ran
(:func:`~cases.run.persistence.code_version`), and a run made by other code
than the driver's is refused rather than stored under the driver's version.
"""

from __future__ import annotations

import atexit
import contextlib
import os
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from multiprocessing import get_context

from ..run import RunStore, code_version, prepare_projectile
from ..run.prepare import preparation_key
from ..run.summary import simulate_record
from ..scene import Scene

__all__ = ["Pool", "run_missing", "run_job", "CodeMismatch"]


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
    progress : bool
        Show a progress bar (runs done, failed, time left) on stderr.
    """

    workers: int | None = None
    scheduler: str | None = None
    progress: bool = True

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


def run_missing(todo: dict[str, Scene], store: RunStore, pool: Pool, total: int) -> None:
    """Run the scenes of ``todo`` (scene key -> scene) on ``pool`` and save each in ``store`` as it finishes."""
    from tqdm import tqdm

    jobs = {key: scene.model_dump_json() for key, scene in todo.items()}
    bar = tqdm(
        total=total, initial=total - len(jobs), disable=not pool.progress, unit="run", desc="sweep", dynamic_ncols=True
    )
    failed = 0
    own = code_version("run")

    def finish(key: str, record: dict, history: bytes | None, code: str) -> None:
        nonlocal failed
        if code != own:
            raise CodeMismatch(
                f"a worker ran code version {code}, this process has {own}: install the same"
                " version of penetrate on every worker of the cluster"
            )
        store.save(key, record, history)
        failed += "error" in record
        bar.set_postfix(failed=failed, refresh=False)
        bar.update(1)

    try:
        if pool.scheduler:
            _on_dask(jobs, pool.scheduler, finish)
        else:
            _on_processes(jobs, list(todo.values()), pool.width, finish)
    finally:
        bar.close()


def _on_dask(jobs: dict[str, str], scheduler: str, finish) -> None:
    from distributed import Client
    from distributed import as_completed as dask_completed

    with Client(scheduler) as client:
        futures = {client.submit(run_job, text, pure=False): key for key, text in jobs.items()}
        for future in dask_completed(futures):
            finish(futures[future], *future.result())


_WARM: dict[int, ProcessPoolExecutor] = {}


def _warm_executor(count: int) -> ProcessPoolExecutor:
    """``count`` spawned workers, kept for the rest of this process: a study that runs in rounds (the
    bisection of a critical speed) finds them with their imports done and their projectiles prepared,
    instead of spawning and preparing again each round (about 1.5 s a round)."""
    if count not in _WARM:
        _WARM[count] = ProcessPoolExecutor(count, mp_context=get_context("spawn"))
    return _WARM[count]


@atexit.register
def _shut_down_warm_executors() -> None:
    for executor in _WARM.values():
        executor.shutdown(wait=True, cancel_futures=True)
    _WARM.clear()


def _on_processes(jobs: dict[str, str], scenes: list[Scene], count: int, finish) -> None:
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
