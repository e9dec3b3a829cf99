"""Helpers the tests share (importable as ``support``: tests/ is on the path through its conftest)."""

from __future__ import annotations

import contextlib
import functools
import math
import os
import shutil
import signal
import socket
import subprocess
import sys
import typing
from collections.abc import Iterator

import pytest
from pydantic import BaseModel

from mesh import ProjectileGeometry, ProjectileMesh, build_mesh


def slow_except(values, *keep):
    """``values`` as pytest parameters: those in ``keep`` run in the default suite, the others only in
    CI's slow step (``-m slow``), so that each parametrised family keeps a representative in the default
    run and its full range in CI without the default run passing five minutes."""

    def slow(value):
        return pytest.param(*value if isinstance(value, tuple) else (value,), marks=pytest.mark.slow)

    return [value if value in keep else slow(value) for value in values]


@functools.cache
def meshed(geometry: ProjectileGeometry, size: float, order: int = 2) -> ProjectileMesh:
    """``build_mesh``, once per test session for each geometry, size and order."""
    return build_mesh(geometry, size, order)


def rss_bytes() -> int:
    """Resident memory of this process (bytes), from ``/proc/self/statm`` (Linux)."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def free_port() -> int:
    """A TCP port on the loopback that nothing listens on now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def dask_cluster(folder, workers: int = 2) -> Iterator[str]:
    """A ``dask scheduler`` and ``dask worker --nworkers N`` started from the command line, as on a real
    cluster: the workers import this project as installed (no ``PYTHONPATH``), from ``folder``.  Yields the
    scheduler's address once the workers have joined; stops both (SIGKILL after 30 s) on leaving."""
    import pytest

    dask = shutil.which("dask", path=os.path.dirname(sys.executable))
    if dask is None:
        pytest.skip("no dask command beside this interpreter")
    from distributed import Client

    address = f"tcp://127.0.0.1:{free_port()}"
    env = {**os.environ, "PYTHONPATH": ""}  # the workers find the project as installed, from another folder
    options = {
        "cwd": folder,
        "env": env,
        "start_new_session": True,
        "stdout": subprocess.DEVNULL,
        "stderr": subprocess.DEVNULL,
    }
    scheduler = subprocess.Popen(
        [dask, "scheduler", "--host", "127.0.0.1", "--port", address.rsplit(":", 1)[1], "--no-dashboard"], **options
    )
    worker = subprocess.Popen(
        [dask, "worker", address, "--nworkers", str(workers), "--nthreads", "1", "--no-dashboard"], **options
    )
    try:
        with Client(address, timeout=60) as client:
            client.wait_for_workers(workers, timeout=60)
        yield address
    finally:
        for proc in (worker, scheduler):
            os.killpg(proc.pid, signal.SIGTERM)
        for proc in (worker, scheduler):
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)


MIRROR_Y = ((1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, 1.0))  # the world plane Y = 0


def mirrored_states(rng, count: int = 20):
    """``count`` random embedded states and their images in the world plane ``Y = 0``: pairs of
    ``(position, velocity, rotation, spin)``.  The image reverses world Y and body y: the quaternion
    ``(w, -x, y, -z)``, the body angular velocity ``-(M omega)``."""
    import numpy as np

    from dynamics.quaternion import rotation_matrix

    mirror = np.array(MIRROR_Y)
    for _ in range(count):
        w, x, y, z = rng.normal(size=4)
        q = np.array([w, x, y, z]) / math.sqrt(w * w + x * x + y * y + z * z)
        position = np.array([0.0, 0.0, rng.uniform(-1.5, -0.2)])
        velocity, spin = rng.normal(size=3) * 300.0, rng.normal(size=3) * 20.0
        yield (
            (position, velocity, rotation_matrix(q), spin),
            (
                mirror @ position,
                mirror @ velocity,
                rotation_matrix(q * np.array([1.0, -1.0, 1.0, -1.0])),
                -(mirror @ spin),
            ),
        )


def ring_records(law, entry_length: float = 0.0, max_radius: float = 0.0, **effects):
    """The rings' law and effects records (``fem_loads.kernels.records``) of a load of ``law`` with ``effects`` (the
    keyword arguments of ``DAFLLoads``, a guard of 0 and no effect by default), without a mesh."""
    from types import SimpleNamespace

    from fem_loads.dafl import effect_values
    from fem_loads.kernels.records import pack_effects, pack_laws
    from fem_loads.target import LEVEL

    loads = SimpleNamespace(
        law=law, contact_width=0.0, contact_incidence=0.0, contact="one_sided", normal_velocity_guard=0.0,
        separation=True, friction=None, free_surface=None, front_face=LEVEL,
    )  # fmt: skip
    loads.__dict__.update(effects)
    laws, _, _, address = pack_laws(law)
    return laws, pack_effects(loads, effect_values(loads, entry_length, max_radius), address)


def schema_models(annotation: object) -> list[type[BaseModel]]:
    """The pydantic models a scene field's annotation may hold, through Annotated, unions, lists and dicts."""
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if origin is typing.Annotated:
        return schema_models(args[0])
    if args and origin is not typing.Literal:
        return [m for a in args for m in schema_models(a)]
    return [annotation] if isinstance(annotation, type) and issubclass(annotation, BaseModel) else []
