"""Helpers the tests share (importable as ``support``: tests/ is on the path through its conftest)."""

from __future__ import annotations

import functools
import os

from mesh import ProjectileGeometry, ProjectileMesh, build_mesh


@functools.lru_cache(maxsize=None)
def meshed(geometry: ProjectileGeometry, size: float, order: int = 2) -> ProjectileMesh:
    """``build_mesh``, once per test session for each geometry, size and order."""
    return build_mesh(geometry, size, order)


def rss_bytes() -> int:
    """Resident memory of this process (bytes), from ``/proc/self/statm`` (Linux)."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
