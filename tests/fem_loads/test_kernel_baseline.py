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
    """Straight scenes within 1e-9 of depth and path length, turning ones within 1e-5 and 1e-3 degrees of turn or
    twice their round-off range where that is wider, and the same end reason."""
    assert kernel_baseline.differences(want, kernel_baseline.run(want["scene"], want["kernel"])) == []


def test_every_turning_row_has_its_round_off_range_and_no_straight_row_has_one():
    for row in ROWS:
        ranges = [row[column] for column in kernel_baseline.RANGES.values()]
        if kernel_baseline.turning(row):
            assert all(float(value) >= 0.0 for value in ranges), row["scene"]
        else:
            assert ranges == ["", "", ""], row["scene"]


def test_a_turning_row_may_move_within_twice_its_round_off_range_and_no_further():
    want = {"depth": "4.0", "path_length": "10.0", "axis_angle_change": "150.0", "end_reason": "stopped"}
    want |= {"depth_range": "1e-3", "path_range": "0.0", "turn_range": "0.5"}  # depth 2.5e-4 relative, turn 0.5 deg
    got = dict(want)
    got["depth"], got["axis_angle_change"] = repr(4.0 + 1.9e-3), repr(150.0 - 0.99)
    assert kernel_baseline.differences(want, got) == []
    got["depth"] = repr(4.0 + 2.1e-3)
    assert [line.split()[0] for line in kernel_baseline.differences(want, got)] == ["depth"]
    got["depth"], got["path_length"] = "4.0", repr(10.0 * (1 + 2e-5))  # no range: the fixed 1e-5
    assert [line.split()[0] for line in kernel_baseline.differences(want, got)] == ["path_length"]


def test_a_straight_row_is_held_to_its_fixed_tolerance_whatever_its_range_columns_say():
    want = {"depth": "4.0", "path_length": "4.0", "axis_angle_change": "0.0", "end_reason": "stopped"}
    want |= {"depth_range": "1.0", "path_range": "1.0", "turn_range": "1.0"}
    got = dict(want, depth=repr(4.0 * (1 + 1e-8)))
    assert [line.split()[0] for line in kernel_baseline.differences(want, got)] == ["depth"]
