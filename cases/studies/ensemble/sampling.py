"""Ensembles: runs of a scene under uncertain impact conditions, and the probability of each outcome.

A ``--sample KEY=DIST`` option gives a numeric scene key a distribution (:func:`parse_sample`).
:func:`draw` makes the samples: points of the unit cube from a design (independent random
points, a scrambled Sobol' sequence or a Latin hypercube, :func:`unit_points`), each coordinate
mapped through its distribution's inverse cumulative distribution function (``ppf`` of
:mod:`scipy.stats`).  Sample ``i`` of the random design depends on the seed and ``i`` only, and the
Sobol' points are a prefix of one sequence, so raising the number of runs keeps the earlier
samples (and their stored runs); a Latin hypercube is made for its size and cannot be extended.

Each run's outcomes (:func:`outcomes`) are ``unstable`` (the axis turned by at least 30 degrees,
:func:`~cases.studies.speeds.instability.is_unstable`, as ``penetrate critical`` decides), ``exited``, ``stopped``,
``perforated`` and ``ricocheted`` (its end reason) and ``failed`` (an error ended it).  :func:`estimate` gives each
outcome's probability with a 95 % Wilson score interval (:func:`wilson_interval`), and
:func:`curve` the same in bins of one sampled key (``--by KEY=START:STOP:STEP``, :func:`parse_bins`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from ...scene import InputError, Scene, dotted_key
from ..engine.sweep import MAX_GRID_VALUES, SweepResult, Variation
from ..speeds.instability import is_unstable

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "Distribution",
    "parse_sample",
    "parse_bins",
    "bin_index",
    "unit_points",
    "draw",
    "variations",
    "wilson_interval",
    "Estimate",
    "outcomes",
    "estimate",
    "curve",
    "summary_record",
    "FORMS",
    "DESIGNS",
    "OUTCOMES",
    "CONFIDENCE",
]

FORMS = {
    "normal": "normal:MEAN:SD",
    "truncnormal": "truncnormal:MEAN:SD:LO:HI",
    "uniform": "uniform:LO:HI",
    "lognormal": "lognormal:MEDIAN:SIGMA",
    "halfnormal": "halfnormal:SCALE",
    "choice": "choice:V1,V2,...",
}
DESIGNS = ("random", "sobol", "lhs")
OUTCOMES = ("unstable", "exited", "stopped", "failed", "perforated", "ricocheted")
CONFIDENCE = 0.95
_ALLOWED = "allowed: " + ", ".join(FORMS.values())
_TINY = 2.0**-53  # unit points are kept inside (0, 1), where every ppf is finite


@dataclass(frozen=True)
class Distribution:
    """The distribution of one sampled scene key.

    Parameters
    ----------
    key : str
        The dotted scene key, e.g. ``impact.speed``.
    name : str
        One of :data:`FORMS`.
    parameters : tuple of float
        The numbers after the name, in the order of its form (for ``choice``: the values).
    """

    key: str
    name: str
    parameters: tuple[float, ...]

    def frozen(self) -> Any:  # a frozen scipy.stats distribution (scipy has no types here), or None
        """The :mod:`scipy.stats` distribution (a frozen ``rv_continuous``), or None for ``choice``."""
        from scipy import stats  # here, not at the top: the command line's help reads FORMS (1 s less)

        p = self.parameters
        if self.name == "normal":
            return stats.norm(loc=p[0], scale=p[1])
        if self.name == "truncnormal":
            return stats.truncnorm((p[2] - p[0]) / p[1], (p[3] - p[0]) / p[1], loc=p[0], scale=p[1])
        if self.name == "uniform":
            return stats.uniform(loc=p[0], scale=p[1] - p[0])
        if self.name == "lognormal":
            return stats.lognorm(s=p[1], scale=p[0])
        if self.name == "halfnormal":  # |N(0, SCALE)|: a disturbance of unknown sign, e.g. an attack angle
            return stats.halfnorm(scale=p[0])
        return None

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """The values at the quantiles ``u`` in (0, 1): each ``choice`` value is equally likely."""
        u = np.asarray(u, dtype=float)
        if self.name == "choice":
            index = np.minimum((u * len(self.parameters)).astype(int), len(self.parameters) - 1)
            return np.asarray(self.parameters)[index]
        return self.frozen().ppf(u)

    @property
    def text(self) -> str:
        """The distribution as the option gives it, e.g. ``normal:300:10``."""
        if self.name == "choice":
            return "choice:" + ",".join(f"{v:g}" for v in self.parameters)
        return ":".join([self.name, *(f"{v:g}" for v in self.parameters)])


def _numbers(option: str, fields: Sequence[str], integer: bool) -> tuple[float, ...]:
    try:
        values = tuple(int(f) if integer else float(f) for f in fields)
    except ValueError:
        what = "whole numbers (the key is an integer)" if integer else "numbers"
        raise InputError(f"{option}: the parameters must be {what} ({_ALLOWED})") from None
    if not all(math.isfinite(v) for v in values):
        raise InputError(f"{option}: the parameters must be finite numbers ({_ALLOWED})")
    return values


def _check(option: str, name: str, p: tuple[float, ...]) -> None:
    """The ranges of a distribution's parameters."""
    if name in ("normal", "truncnormal") and not p[1] > 0:
        raise InputError(f"{option}: need SD > 0 ({FORMS[name]})")
    if name == "truncnormal" and not p[2] < p[3]:
        raise InputError(f"{option}: need LO < HI ({FORMS[name]})")
    if name == "uniform" and not p[0] < p[1]:
        raise InputError(f"{option}: need LO < HI ({FORMS[name]})")
    if name == "lognormal" and not (p[0] > 0 and p[1] > 0):
        raise InputError(f"{option}: need MEDIAN > 0 and SIGMA > 0 ({FORMS[name]})")
    if name == "halfnormal" and not p[0] > 0:
        raise InputError(f"{option}: need SCALE > 0 ({FORMS[name]})")


def _base_value(option: str, key: str, base: Scene | None) -> Any:
    """The value of ``key`` in the base scene; refused unless it is a number."""
    if base is None:
        return None
    node: Any = base.model_dump()
    for part in key.split("."):
        node = node.get(part) if isinstance(node, dict) else None
    if isinstance(node, bool) or not isinstance(node, (int, float)):
        raise InputError(
            f"{option}: {key} is not a numeric key of the scene (allowed: a key whose value is a number,"
            " e.g. impact.speed, impact.attack_angle, projectile.mass)"
        )
    return node


def parse_sample(text: str, base: Scene | None = None) -> Distribution:
    """``KEY=DIST`` of ``--sample`` as a :class:`Distribution` (one of :data:`FORMS`).

    Parameters
    ----------
    text : str
        The option's text, e.g. ``impact.speed=normal:300:10``.
    base : Scene, optional
        The base scene: when given, ``KEY`` must hold a number in it, and a key holding a whole
        number (``numerics.quadrature_order``) takes only ``choice`` of whole numbers.

    Raises
    ------
    InputError
        One line naming the option and the allowed form.
    """
    option = f"--sample {text!r}"
    key, raw = text.split("=", 1) if "=" in text else (text, "")
    name, _, rest = raw.strip().partition(":")
    if name not in FORMS:
        raise InputError(f"{option}: expected KEY=DIST with DIST one of {', '.join(FORMS.values())}")
    key = ".".join(dotted_key(key, option))
    value = _base_value(option, key, base)
    integer = isinstance(value, int)
    if name == "choice":
        fields = rest.split(",")
        if not rest.strip() or not all(f.strip() for f in fields):
            raise InputError(f"{option}: expected {FORMS['choice']} (one or more values)")
        return Distribution(key, name, _numbers(option, fields, integer))
    if integer:
        raise InputError(f"{option}: {key} is a whole number; sample it with {FORMS['choice']}")
    fields = rest.split(":") if rest else []
    if len(fields) != FORMS[name].count(":"):
        raise InputError(f"{option}: expected {FORMS[name]}")
    parameters = _numbers(option, fields, False)
    _check(option, name, parameters)
    return Distribution(key, name, parameters)


def parse_bins(text: str, sampled: Sequence[str]) -> tuple[str, np.ndarray]:
    """``KEY=START:STOP:STEP`` of ``--by`` as the key and its bin edges (the last bin ends at STOP).

    ``KEY`` must be one of the ``sampled`` keys.
    """
    option = f"--by {text!r}"
    key, raw = text.split("=", 1) if "=" in text else (text, "")
    key = ".".join(dotted_key(key, option)) if key.strip() else ""
    if key not in sampled:
        raise InputError(
            f"{option}: expected KEY=START:STOP:STEP with KEY one of the sampled keys ({', '.join(sampled) or 'none'})"
        )
    parts = raw.split(":")
    try:
        start, stop, step = (float(p) for p in parts) if len(parts) == 3 else (math.nan,) * 3
    except ValueError:
        start = stop = step = math.nan
    if not all(math.isfinite(v) for v in (start, stop, step)):
        raise InputError(f"{option}: START:STOP:STEP must be three finite numbers")
    if not (step > 0 and stop > start):
        raise InputError(f"{option}: need STEP > 0 and STOP > START")
    if (stop - start) / step >= MAX_GRID_VALUES:
        raise InputError(
            f"{option}: more than {MAX_GRID_VALUES} bins (allowed: (STOP - START) / STEP < {MAX_GRID_VALUES})"
        )
    count = max(1, int(math.ceil((stop - start) / step - 1e-9)))
    edges = start + step * np.arange(count + 1)
    edges[-1] = stop
    return key, edges


#: the random design's points come in blocks of this many, one generator each (:func:`unit_points`)
RANDOM_BLOCK = 1024


def unit_points(design: str, count: int, dimensions: int, seed: int) -> np.ndarray:
    """``count`` points of the open unit cube of ``dimensions`` dimensions, shape ``(count, dimensions)``.

    ``random``: point ``i`` is row ``i % RANDOM_BLOCK`` of the block of :data:`RANDOM_BLOCK` points drawn by the
    generator seeded with ``(seed, i // RANDOM_BLOCK)``, so it depends on neither ``count`` nor the order of the
    runs (a generator per block, not per point: making a generator costs 35 us, drawing a point 0.1 us).
    ``sobol``: the first ``count`` points of the scrambled Sobol' sequence of ``seed`` (drawn as the next power
    of two, whose balance the sequence guarantees, and cut), so a larger ``count`` keeps the smaller one's points.
    ``lhs``: a Latin hypercube of ``count`` points (one in each of ``count`` equal strata of every
    dimension), made for that size: another ``count`` gives other points.
    """
    if design not in DESIGNS:
        raise InputError(f"--design {design!r}: expected one of {', '.join(DESIGNS)}")
    if count < 1 or dimensions < 1:
        raise InputError("-n: need one or more runs and one or more --sample options")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError(f"--seed {seed!r}: must be a whole number >= 0")
    from scipy.stats import qmc

    if design == "random":
        blocks = -(-count // RANDOM_BLOCK)
        drawn = [np.random.default_rng([seed, b]).random((RANDOM_BLOCK, dimensions)) for b in range(blocks)]
        points = np.concatenate(drawn)[:count]
    elif design == "sobol":
        points = qmc.Sobol(dimensions, rng=seed).random_base2(max(0, math.ceil(math.log2(count))))[:count]
    else:
        points = qmc.LatinHypercube(dimensions, rng=seed).random(count)
    return np.clip(points, _TINY, 1.0 - _TINY)


def draw(distributions: Sequence[Distribution], count: int, seed: int = 0, design: str = "random") -> np.ndarray:
    """The samples, shape ``(count, len(distributions))``: the design's unit points through each ``ppf``."""
    points = unit_points(design, count, len(distributions), seed)
    return np.column_stack([d.ppf(points[:, j]) for j, d in enumerate(distributions)])


def variations(distributions: Sequence[Distribution], samples: np.ndarray) -> list[Variation]:
    """One typed :class:`~cases.studies.engine.sweep.Variation` per sample (Python floats, or ints for
    whole-number keys)."""

    def typed(d: Distribution, value: float) -> Any:
        return int(value) if d.name == "choice" and all(isinstance(v, int) for v in d.parameters) else float(value)

    return [Variation({d.key: typed(d, v) for d, v in zip(distributions, row)}) for row in samples]


def wilson_interval(
    successes: npt.ArrayLike, trials: npt.ArrayLike, confidence: float = CONFIDENCE
) -> tuple[np.ndarray, np.ndarray]:
    """The Wilson score interval (no continuity correction) of a binomial proportion, from
    ``scipy.stats.binomtest(...).proportion_ci(method="wilson")``; NaN for no trials.

    Parameters
    ----------
    successes, trials : int or array of int
        Counts, elementwise.
    confidence : float
        The two-sided level (default 0.95).

    Returns
    -------
    low, high : ndarray
    """
    from scipy import stats

    k, n = np.broadcast_arrays(np.asarray(successes, dtype=int), np.asarray(trials, dtype=int))
    low, high = np.full(k.shape, np.nan), np.full(k.shape, np.nan)
    for index in np.ndindex(k.shape):
        if n[index] > 0:  # scipy's Wilson interval; none for no trials
            interval = stats.binomtest(int(k[index]), int(n[index])).proportion_ci(confidence, method="wilson")
            low[index], high[index] = interval.low, interval.high
    # exactly 0 (1) for no (every) success, where rounding would leave 1e-17
    low = np.where(k == 0, 0.0, low)
    high = np.where(k == n, 1.0, high)
    return np.where(n > 0, low, np.nan), np.where(n > 0, high, np.nan)


@dataclass(frozen=True)
class Estimate:
    """An outcome's probability: ``count`` of ``runs``, the proportion and its 95 % Wilson interval."""

    count: int
    runs: int
    probability: float
    interval: tuple[float, float]

    @classmethod
    def of(cls, count: int, runs: int) -> Estimate:
        low, high = wilson_interval(count, runs)
        return cls(int(count), int(runs), count / runs if runs else math.nan, (float(low), float(high)))


def outcomes(result: SweepResult) -> pd.DataFrame:
    """Each run's outcomes (booleans :data:`OUTCOMES`), a row per run in the order of the variations.

    A failed run is ``failed`` and nothing else; the other outcomes are read from the summary.
    """
    rows = []
    for run in result.runs:
        s = run.summary
        rows.append(
            {
                "unstable": s is not None and is_unstable(s.axis_angle_change),
                "exited": s is not None and s.end_reason == "exited",
                "stopped": s is not None and s.end_reason == "stopped",
                "failed": s is None,
                "perforated": s is not None and s.end_reason == "perforated",
                "ricocheted": s is not None and s.end_reason == "ricocheted",
            }
        )
    return pd.DataFrame(rows, columns=list(OUTCOMES), dtype=bool)


def estimate(table: pd.DataFrame) -> dict[str, Estimate]:
    """Each outcome's :class:`Estimate` from an :func:`outcomes` table.

    ``failed`` is counted over every run, the other outcomes over the runs that finished, so that a failed run
    counts neither for nor against them.  Outcomes without a column in ``table`` are left out.
    """
    finished = int((~table["failed"]).sum())
    return {
        name: Estimate.of(int(table[name].sum()), len(table) if name == "failed" else finished)
        for name in OUTCOMES
        if name in table
    }


def bin_index(values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """The bin of each of ``values`` among ``edges``: ``lo <= value < hi``, the last bin also ``value == hi``;
    -1 or ``len(edges) - 1`` for a value outside them."""
    values = np.asarray(values, dtype=float)
    index = np.searchsorted(edges, values, side="right") - 1
    index[values == edges[-1]] = len(edges) - 2
    return index


def curve(values: np.ndarray, table: pd.DataFrame, edges: np.ndarray) -> list[dict]:
    """The outcomes' probabilities in the bins ``edges`` of one sampled key's ``values``.

    A bin holds ``lo <= value < hi`` (the last also ``value == hi``); values outside the edges are
    left out.  Each bin: ``{"bin": [lo, hi], "runs": n, "finished": m, "unstable": p, ...,
    "interval": {"unstable": [lo, hi], ...}}`` (NaN for an empty bin).
    """
    index = bin_index(values, edges)
    bins = []
    for b in range(len(edges) - 1):
        estimates = estimate(table[index == b])
        entry: dict[str, Any] = {
            "bin": [float(edges[b]), float(edges[b + 1])],
            "runs": int((index == b).sum()),
            "finished": estimates["unstable"].runs,
        }
        entry.update({name: e.probability for name, e in estimates.items()})
        entry["interval"] = {name: list(e.interval) for name, e in estimates.items()}
        bins.append(entry)
    return bins


def summary_record(estimates: Mapping[str, Estimate], runs: int) -> dict:
    """The JSON of :func:`estimate`: ``{"runs": N, "probability": {...}, "interval": {...}}``."""
    return {
        "runs": runs,
        "probability": {name: e.probability for name, e in estimates.items()},
        "interval": {name: list(e.interval) for name, e in estimates.items()},
    }
