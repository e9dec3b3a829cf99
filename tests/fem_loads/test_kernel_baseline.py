"""The load kernel's structure may change; its results may not: every shipped scene on both kernels against the
committed baseline (``tests/kernel_baseline.csv``, written by ``python tests/kernel_baseline.py record``)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import kernel_baseline  # noqa: E402

ROWS = kernel_baseline.read()


def test_the_baseline_covers_every_shipped_scene_on_every_kernel_that_runs_it():
    assert sorted((row["scene"], row["kernel"]) for row in ROWS) == sorted(kernel_baseline.cases())


@pytest.mark.slow
@pytest.mark.parametrize("want", ROWS, ids=[f"{row['scene']}-{row['kernel']}" for row in ROWS])
def test_a_shipped_scene_gives_its_baseline(want):
    """Straight scenes within 1e-9 of depth and path length, turning ones within 1e-5 and 1e-3 degrees of turn,
    and the same end reason."""
    assert kernel_baseline.differences(want, kernel_baseline.run(want["scene"], want["kernel"])) == []
