"""The one threshold search of the full runs: the critical impact velocity and the ballistic limit.

Both look for the impact speed at which a run's outcome changes side (stable to unstable, held to perforated),
to a ``resolution``, with as many runs a round as the pool has workers.  A :class:`Bracket` holds one search's
state; :func:`search` advances several in lockstep, each round one parallel sweep that its caller runs.

* **The bracket** is the lowest run above the threshold and the highest run below it.  An end not run yet is
  assumed (the range's, a guess's, a guide's) until a run confirms it.  The search ends when both ends are
  confirmed at most ``resolution`` apart; the result is the bracket's middle.
* **Unguided**, each round splits the bracket evenly (k-section) on a grid of half the resolution, and runs the
  assumed ends last.
* **Guided** (a model's first bracket one resolution wide around its prediction), the first round runs its two
  ends.  An end its run contradicts gallops away from the guide: each step as long as the way already gone, at
  least one resolution (the distance doubles); spare runs go where the gallop would go next.
* **No change in the range**: an end contradicted at the range's own end ends the search with a failure that
  says which side every run lay on.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

__all__ = ["Bracket", "search", "SLACK"]

SLACK = 1 + 1e-9  # a bracket this close to the resolution is narrow enough (rounding of the grid)


@dataclass
class Bracket:
    """One search's state: the bracket ``[low, high]`` (m/s) and whether a run confirms each end.

    ``limits`` is the range the search may widen to.  A guided search has the ``centre`` of its guide's
    bracket; ``resolution`` (m/s) is the width it stops at.  ``failures``: the message of a range whose runs
    all lie below the threshold (``{speed}``: its top) and of one whose runs all lie above it (its bottom).
    """

    low: float
    high: float
    limits: tuple[float, float]
    resolution: float
    centre: float | None = None
    failures: tuple[str, str] = field(kw_only=True)
    low_run: bool = False
    high_run: bool = False
    failure: str = ""
    below_throughout: bool = False

    @property
    def finished(self) -> bool:
        return bool(self.failure) or (
            self.low_run and self.high_run and self.high - self.low <= self.resolution * SLACK
        )

    @property
    def middle(self) -> float:
        return 0.5 * (self.low + self.high)

    def _gallop(self, speed: float) -> float:
        """The next speed beyond ``speed``, away from the guide's centre, inside the range."""
        assert self.centre is not None  # guided
        bottom, top = self.limits
        sign = 1.0 if speed >= self.centre else -1.0
        # each step as long as the way already gone from the guide's bracket (whose ends lie half a resolution
        # from its centre), at least one resolution: the distance doubles, from one resolution on
        gone = abs(speed - self.centre) - 0.5 * self.resolution
        return min(top, max(bottom, round(speed + sign * max(self.resolution, gone), 6)))

    def wanted(self, count: int) -> list[float]:
        """The speeds to run next: up to ``count`` that split the bracket evenly on the grid of half the
        resolution, or, once it is narrow enough, the ends not confirmed yet.  A guided search runs its
        doubtful ends first, and spare runs where the gallop beyond a doubtful end would go."""
        low, high, resolution = self.low, self.high, self.resolution
        doubtful = [v for v, known in ((low, self.low_run), (high, self.high_run)) if not known]
        if self.centre is not None and doubtful:
            points = list(doubtful)
            while len(points) < count and len(doubtful) == 1 and self._gallop(points[-1]) != points[-1]:
                points.append(self._gallop(points[-1]))
            return points[:count]
        if high - low <= resolution * SLACK:
            return doubtful[:count]
        count = min(count, math.ceil((high - low) / resolution - 1e-9) - 1)
        step = 0.5 * resolution
        split = {round(round((low + j * (high - low) / (count + 1)) / step) * step, 6) for j in range(1, count + 1)}
        return sorted(v for v in split if low < v < high)

    def update(self, above: dict[float, bool]) -> None:
        """The new bracket from every run so far (``above``: speed -> its outcome lies above the threshold): the
        lowest run above from the bracket's bottom up, and the highest run below under that.  An end that its run
        contradicts moves out to the range's end, or a guided search's next gallop; the search fails when the
        range's end was run and contradicts it too."""
        upper = {v for v, is_above in above.items() if is_above}
        lower = set(above) - upper
        bottom, top = self.limits
        guided = self.centre is not None
        up = self._gallop(max(lower, default=self.high)) if guided else top
        high = _end([v for v in upper if v >= self.low], min, self.high, lower, up, top)
        if high is None:
            self.failure = self.failures[0].format(speed=max(lower))
            self.below_throughout = True
            return
        down = self._gallop(min(upper, default=self.low)) if guided else bottom
        low = _end([v for v in lower if v < high[0]], max, self.low, upper, down, bottom)
        if low is None:
            self.failure = self.failures[1].format(speed=min(upper))
            return
        # runs beyond a contradicted end (a guided search's gallop) may lie inside the new bracket
        inside = [v for v in upper if low[0] < v < high[0]]
        (self.low, self.low_run), (self.high, self.high_run) = low, ((min(inside), True) if inside else high)


def _end(
    side: list[float],
    nearest: Callable[[list[float]], float],
    assumed: float,
    wrong_side: set[float],
    moved: float,
    limit: float,
) -> tuple[float, bool] | None:
    """One end of a bracket and whether a run confirms it: the ``nearest`` run on its side; else the assumed
    end, unless its run lay on the wrong side: then the end ``moved`` out (the range's ``limit``, or a guided
    search's next step towards it), and None if the limit too was run and lay on the wrong side."""
    if side:
        return nearest(side), True
    if assumed not in wrong_side:
        return assumed, False
    return None if limit in wrong_side else (moved, False)


def _shares(brackets: Sequence[Bracket], width: int) -> list[int]:
    """How many runs each bracket gets this round: together a whole number of rounds of ``width`` runs (at least
    one each), the widest brackets taking what is left over."""
    budget = width * math.ceil(len(brackets) / width)
    share, extra = divmod(budget, len(brackets))
    widest = sorted(range(len(brackets)), key=lambda i: brackets[i].low - brackets[i].high)
    counts = [share] * len(brackets)
    for i in widest[:extra]:
        counts[i] += 1
    return counts


def search(
    brackets: Sequence[Bracket], width: int, scan: Callable[[list[list[float]]], list[dict[float, bool]]]
) -> list[int]:
    """Advance every bracket in lockstep until each is finished; the rounds each took.

    Each round the open searches share a whole number of rounds of ``width`` runs (one search alone gets every
    worker, a family shares them), and ``scan(wanted)`` runs the speeds each search wants, as one parallel
    sweep, and gives for each search every speed run so far with whether its outcome lies above the threshold.
    """
    rounds = [0] * len(brackets)
    known: list[dict[float, bool]] = [{} for _ in brackets]
    while True:
        open_ = [i for i, b in enumerate(brackets) if not b.finished]
        if not open_:
            return rounds
        counts = dict(zip(open_, _shares([brackets[i] for i in open_], width)))
        wanted = [brackets[i].wanted(counts[i]) if i in counts else [] for i in range(len(brackets))]
        if all(v in known[i] for i in open_ for v in wanted[i]):  # cannot happen: every round runs something new
            raise RuntimeError("the threshold search stalled: no new speed to run")
        known = scan(wanted)
        for i in open_:
            rounds[i] += 1
            brackets[i].update(known[i])
