"""The one threshold search of the critical speed and the ballistic limit, against a known threshold."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cases.studies.engine.search import Bracket, search

LIMITS = (200.0, 1600.0)
FAILURES = ("below up to {speed:g}", "above down to {speed:g}")


def run_search(threshold: float, width: int, resolution: float, centre: float | None = None):
    """Search a sharp threshold (above at and beyond ``threshold``); the bracket, the rounds and every round's
    speeds."""
    if centre is None:
        bracket = Bracket(*LIMITS, LIMITS, resolution, failures=FAILURES)
    else:
        low = min(max(centre - 0.5 * resolution, LIMITS[0]), LIMITS[1] - resolution)
        bracket = Bracket(low, low + resolution, LIMITS, resolution, centre=centre, failures=FAILURES)
    seen: dict[float, bool] = {}
    rounds: list[list[float]] = []

    def scan(wanted):
        rounds.append(wanted[0])
        seen.update({v: v >= threshold for v in wanted[0]})
        return [dict(seen)]

    (count,) = search([bracket], width, scan)
    assert count == len(rounds)
    return bracket, rounds


@settings(max_examples=200, deadline=None)
@given(
    threshold=st.floats(200.5, 1600.0),
    width=st.integers(1, 8),
    resolution=st.sampled_from([1.0, 5.0, 20.0]),
    guide_error=st.one_of(st.none(), st.floats(-600.0, 600.0)),
)
def test_the_bracket_holds_the_threshold_confirmed_and_narrow(threshold, width, resolution, guide_error):
    """Unguided or guided, however wrong the guide, the final bracket's ends are both run, on either side of the
    threshold, at most one resolution apart; no round runs more than the workers or a speed twice."""
    centre = None if guide_error is None else min(max(threshold + guide_error, LIMITS[0]), LIMITS[1])
    bracket, rounds = run_search(threshold, width, resolution, centre)
    assert not bracket.failure and bracket.low_run and bracket.high_run
    assert bracket.low < threshold <= bracket.high and bracket.high - bracket.low <= resolution * (1 + 1e-9)
    assert all(0 < len(r) <= width for r in rounds)
    speeds = [v for r in rounds for v in r]
    assert len(speeds) == len(set(speeds)) and all(LIMITS[0] <= v <= LIMITS[1] for v in speeds)
    if guide_error is None:  # k-section: splitting into width + 1 parts a round, plus the grid and an end
        assert len(rounds) <= math.ceil(math.log(1400 / resolution) / math.log(width + 1)) + 2


def test_a_good_guide_takes_one_round_of_two_runs():
    bracket, rounds = run_search(905.3, 2, 5.0, centre=906.0)
    assert rounds == [[903.5, 908.5]] and (bracket.low, bracket.high) == (903.5, 908.5) and bracket.middle == 906.0


def test_a_wrong_guide_gallops_out_doubling():
    """An end its run contradicts moves away from the guide, each step as long as the way gone (at least one
    resolution), spare workers running the steps beyond."""
    _, rounds = run_search(1000.0, 4, 5.0, centre=900.0)
    assert rounds[0] == [897.5, 902.5]
    assert rounds[1] == [907.5, 912.5, 922.5, 942.5]  # 5, 5, 10, 20 m/s on


@pytest.mark.parametrize(("threshold", "failure"), [(2000.0, 0), (100.0, 1)])
@pytest.mark.parametrize("centre", [None, 900.0])
def test_a_range_without_the_change_fails_saying_which_side(threshold, failure, centre):
    failures = FAILURES
    bracket = Bracket(*LIMITS, LIMITS, 5.0, failures=failures)
    if centre is not None:
        bracket = Bracket(centre - 2.5, centre + 2.5, LIMITS, 5.0, centre=centre, failures=failures)
    seen: dict[float, bool] = {}

    def scan(wanted):
        seen.update({v: v >= threshold for v in wanted[0]})
        return [dict(seen)]

    search([bracket], 2, scan)
    end = LIMITS[1] if failure == 0 else LIMITS[0]
    assert bracket.failure == failures[failure].format(speed=end)
    assert bracket.below_throughout == (failure == 0)


def test_the_critical_speed_and_the_ballistic_limit_share_the_search():
    """Neither study keeps a bracket, a gallop or a split of its own: both run :func:`search`."""
    import inspect

    from cases.studies.speeds import ballistic
    from cases.studies.speeds import characteristic as speeds

    for module in (ballistic, speeds):
        source = inspect.getsource(module)
        assert "search(" in source and "Bracket(" in source
        assert not any(name in source for name in ("def _gallop", "def _split", "class _Bracket", "_SLACK ="))
