"""Multi-fidelity ensembles: the reduced model sorts every sample, and full runs measure each sort.

``penetrate ensemble ... --fidelity multi`` (docs/ensembles.md):

1. **Sort.**  Each sample gets reduced runs (:class:`~cases.studies.reduced.pitch_plane.ReducedModel`) at its
   impact speed lowered and raised by :data:`MARGIN`: unstable at the lower speed, it is *unstable*;
   stable at the higher speed, *stable*; else it lies *near* the stability boundary.  The margin is the
   reduced model's largest measured error of a critical speed (0.6 %, docs/theory.md), about doubled.
   The sort assumes that a faster impact is no more stable (the estimate below does not rely on it), so
   one run decides a sample that is not near: the first :data:`PILOT` samples are run at the lower speed
   first, and every other one first at the speed that confirms the sort of its nearest pilot sample.
2. **Full runs.**  Of ``full_runs`` full runs, up to :data:`NEAR_SHARE` go to near samples, the rest to a
   random audit of the stable and unstable samples, in proportion to their numbers; each chosen at random
   within its stratum (the seed's own stream).
3. **Estimate.**  Stratified sampling: each stratum's probability of an outcome is measured by its full
   runs, and the strata are weighted by their share of the samples,
   ``P = sum_h (N_h / N) k_h / n_h``.  Unbiased whatever the reduced model gets wrong: it only decides
   where the full runs go, never what they count (a control variate would lean on its correlation, and
   importance weights on a density the sort does not have).  The interval is conservative: the sum of each
   stratum's Wilson bounds (a stratum run in full is exact), each at level ``1 - 0.05 / m`` for the ``m``
   audited strata and the Monte Carlo error of the ``N`` samples themselves (Bonferroni), so that it holds
   at 95 % jointly.

The reduced model applies to a body of revolution in a homogeneous target
(:func:`..reduced.pitch_plane.check_supported`) with the sampled keys among :data:`REDUCED_KEYS`; elsewhere
``multi`` is refused in one line.
"""

from __future__ import annotations

import functools
import os
import time
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ...scene import InputError, Scene, one_line
from ..engine.pool import Pool
from ..engine.report import markdown_table, number_cell
from .sampling import CONFIDENCE, Distribution, wilson_interval

if TYPE_CHECKING:
    import pandas as pd

    from ...run import RunStore
    from ..engine.sweep import Sweep

__all__ = [
    "MARGIN",
    "NEAR_SHARE",
    "REDUCED_KEYS",
    "STRATA",
    "FULL_RUNS",
    "check_applies",
    "sort_samples",
    "choose",
    "stratified",
    "multi_ensemble",
    "multi_markdown",
    "interval_cell",
]

MARGIN = 0.012  # relative change of the impact speed either side of a sample (twice the 0.6 % measured)
NEAR_SHARE = 0.25  # of the full runs, at most this share goes to the samples near the boundary
REDUCED_KEYS = ("impact.speed", "impact.attack_angle", "impact.oblique_angle")
STRATA = ("stable", "unstable", "near")  # the sort's codes 0, 1, 2
PILOT = 1024  # samples sorted first, whose sort guesses which run decides each other sample


def check_applies(scene: Scene, keys: Sequence[str]) -> None:
    """Refuse, in one line, an ensemble the reduced model cannot sort."""
    from ..reduced.pitch_plane import check_supported

    other = [key for key in keys if key not in REDUCED_KEYS]
    if other:
        raise InputError(
            f"--fidelity multi: the reduced model sorts samples of {', '.join(REDUCED_KEYS)} only, not"
            f" {', '.join(other)}; use --fidelity full"
        )
    try:
        check_supported(scene)
    except InputError as exc:
        raise InputError(
            f"--fidelity multi: the reduced model does not apply ({one_line(exc)}); use --fidelity full"
        ) from None


@functools.lru_cache(maxsize=4)
def _model(scene_json: str) -> Any:  # a ReducedModel, made once per process and scene
    from ...run import prepare_projectile
    from ..reduced.pitch_plane import ReducedModel

    scene = Scene.model_validate_json(scene_json)
    return ReducedModel(scene, prepare_projectile(scene))


def sort_chunk(
    scene_json: str, speeds: np.ndarray, attacks: np.ndarray, obliques: np.ndarray, stable_first: np.ndarray
) -> np.ndarray:
    """The sort (codes of :data:`STRATA`) of samples of the scene (m/s, deg): a worker's job.  A sample marked
    ``stable_first`` is run at its raised speed first (stable there, it is stable), any other at its lowered
    speed first (unstable there, it is unstable): the same sort either way, one run for most samples when the
    guess is right."""
    model = _model(scene_json)
    unit = model.starts(np.ones(len(speeds)), attacks, obliques)  # velocities scale with the speed
    first = np.where(stable_first, 1.0 + MARGIN, 1.0 - MARGIN) * speeds
    unstable_first = model.unstable(first, _at(unit, first))
    # decided by the first run: stable at the raised speed, or unstable at the lowered one
    undecided = np.flatnonzero(stable_first == unstable_first)
    second = np.where(stable_first, 1.0 - MARGIN, 1.0 + MARGIN)[undecided] * speeds[undecided]
    unstable_second = np.zeros(len(speeds), dtype=bool)
    unstable_second[undecided] = model.unstable(second, _at(unit[undecided], second))
    lowered = np.where(stable_first, unstable_second, unstable_first)
    raised = np.where(stable_first, unstable_first, unstable_second)
    # unstable at the lowered speed: unstable; else unstable at the raised one: near; else stable
    return np.where(lowered, 1, np.where(raised, 2, 0)).astype(np.int8)


def _at(unit_starts: np.ndarray, speeds: np.ndarray) -> np.ndarray:
    """The starts at 1 m/s (rows of :meth:`~..reduced.pitch_plane.ReducedModel.starts`) with their velocities
    at ``speeds`` (m/s)."""
    starts = unit_starts.copy()
    starts[:, 3:5] *= speeds[:, None]
    return starts


def sort_samples(scene: Scene, values: Mapping[str, np.ndarray], width: int) -> np.ndarray:
    """Sort every sample (``values``: sampled key -> one value per sample) on ``width`` local processes.

    The first :data:`PILOT` samples are sorted first; each other sample is guessed to sort as its nearest pilot
    sample (each key scaled by its spread) and run first at the speed that confirms that guess.  The guess
    changes only how many runs a sample costs, never its stratum."""
    from scipy.spatial import cKDTree

    from ..engine.pool import map_local

    count = len(next(iter(values.values())))
    impact = scene.impact
    columns = np.array(
        [
            np.asarray(values.get(key, np.full(count, default)), dtype=float)
            for key, default in zip(REDUCED_KEYS, (impact.speed, impact.attack_angle, impact.oblique_angle))
        ]
    ).reshape(len(REDUCED_KEYS), count)
    scene_json = scene.model_dump_json()
    _model(scene_json).unstable(np.zeros(0), np.zeros((0, 6)))  # numba loads the model here, before workers fork

    def sort(indices: np.ndarray, stable_first: np.ndarray, pieces: int) -> np.ndarray:
        chunks = np.array_split(np.arange(len(indices)), max(1, min(len(indices) // 500, pieces)))
        jobs = [(scene_json, *columns[:, indices[c]], stable_first[c]) for c in chunks if len(c)]
        return np.concatenate(map_local(sort_chunk, jobs, width)) if jobs else np.zeros(0, dtype=np.int8)

    pilot = np.arange(min(count, PILOT))
    codes = np.empty(count, dtype=np.int8)
    codes[pilot] = sort(pilot, np.zeros(len(pilot), dtype=bool), width)
    rest = np.arange(len(pilot), count)
    if len(rest):
        scale = columns[:, pilot].std(axis=1)
        scale[scale == 0.0] = 1.0
        _, nearest = cKDTree((columns[:, pilot] / scale[:, None]).T).query((columns[:, rest] / scale[:, None]).T)
        codes[rest] = sort(rest, codes[pilot][nearest] == 0, 8 * width)
    return codes


def choose(codes: np.ndarray, full_runs: int, seed: int) -> np.ndarray:
    """The samples that get full runs, sorted indices: up to :data:`NEAR_SHARE` of ``full_runs`` near ones, the
    rest an audit of the other two strata in proportion to their sizes (each at random within its stratum)."""
    rng = np.random.default_rng([seed, 1_000_003])  # a stream of its own: the samples' draws stay as they are
    members = [np.flatnonzero(codes == code) for code in range(len(STRATA))]
    near = min(len(members[2]), int(round(NEAR_SHARE * full_runs)))
    rest = full_runs - near
    sizes = [len(members[0]), len(members[1])]
    audit = [min(size, int(round(rest * size / max(1, sum(sizes))))) for size in sizes]
    spare = full_runs - near - sum(audit)  # rounding, or a small stratum: the leftover goes where there is room
    for h in (0, 1):
        extra = min(spare, sizes[h] - audit[h])
        audit[h], spare = audit[h] + extra, spare - extra
    near = min(len(members[2]), near + spare)
    counts = [*audit, near]
    chosen = [rng.choice(m, size=n, replace=False) for m, n in zip(members, counts)]
    return np.sort(np.concatenate(chosen)).astype(int)


def stratified(codes: np.ndarray, ran: np.ndarray, counted: np.ndarray, confidence: float = CONFIDENCE) -> dict:
    """The stratified estimate of one outcome over a set of samples.

    Parameters
    ----------
    codes : ndarray of int
        Each sample's stratum (:data:`STRATA`).
    ran : ndarray of bool
        Whether its full run counts (run and, for outcomes other than ``failed``, finished).
    counted : ndarray of bool
        Whether that run had the outcome (read only where ``ran``).

    Returns
    -------
    dict
        ``probability``, ``interval`` (conservative, see the module), and per stratum its ``samples``,
        ``runs`` and ``count``.  A stratum with samples but no run leaves its share unknown: the point
        estimate takes the sort's label there and the interval spans its whole share.
    """
    total = len(codes)
    if not total:
        return {"probability": float("nan"), "interval": [float("nan")] * 2, "strata": {}}
    audited = [h for h in range(len(STRATA)) if 0 < (ran & (codes == h)).sum() < (codes == h).sum()]
    level = 1.0 - (1.0 - confidence) / (len(audited) + 1)
    point = low = high = 0.0
    strata = {}
    for h, name in enumerate(STRATA):
        members = codes == h
        size, runs = int(members.sum()), int((ran & members).sum())
        count = int((ran & members & counted).sum())
        strata[name] = {"samples": size, "runs": runs, "count": count}
        if not size:
            continue
        share = size / total
        if not runs:
            point += share * (0.5 if name == "near" else float(h))
            high += share
            continue
        p = count / runs
        lo, hi = (p, p) if runs == size else (float(v) for v in wilson_interval(count, runs, level))
        point, low, high = point + share * p, low + share * lo, high + share * hi
    # the N samples are themselves a sample of the distribution: their own Wilson error, added outside
    mc_low, mc_high = (float(v) for v in wilson_interval(int(round(point * total)), total, level))
    mc_low, mc_high = min(mc_low, point), max(mc_high, point)
    interval = [max(0.0, low - (point - mc_low)), min(1.0, high + (mc_high - point))]
    return {"probability": point, "interval": interval, "strata": strata}


FULL_RUNS = 1024  # the default number of full runs of a multi-fidelity ensemble


def multi_ensemble(
    base: Sweep,
    distributions: Sequence[Distribution],
    values: np.ndarray,
    store: RunStore,
    pool: Pool,
    seed: int,
    full_runs: int,
    bins: tuple[str, np.ndarray] | None,
    sweep_of: Callable[[np.ndarray], Sweep],
) -> tuple[dict, pd.DataFrame]:
    """Sort the samples ``values`` (one row each), run the chosen ones in full, estimate every outcome.

    ``sweep_of(indices)``: the full runs of those samples as a sweep (refusing a sample out of range).
    Returns the record and the samples' table (each sample's values, stratum, and the outcomes of those run).
    """
    import pandas as pd

    from ..engine.sweep import run_sweep
    from .sampling import OUTCOMES, bin_index, outcomes

    keys = [d.key for d in distributions]
    clock = time.perf_counter()
    width = pool.width if not pool.scheduler else (os.cpu_count() or 1)
    codes = sort_samples(base.scenes[0], {key: values[:, j] for j, key in enumerate(keys)}, width)
    sort_time = time.perf_counter() - clock
    chosen = choose(codes, full_runs, seed)
    result = run_sweep(sweep_of(chosen), store, pool)
    runs = outcomes(result)
    table = pd.DataFrame({"sample": np.arange(len(values))})
    for j, key in enumerate(keys):
        table[key] = values[:, j]
    table["stratum"] = [STRATA[c] for c in codes]
    table["full_run"] = False
    table.loc[chosen, "full_run"] = True
    for name in OUTCOMES:
        column = np.full(len(values), np.nan)
        column[chosen] = runs[name].to_numpy(float)
        table[name] = column

    # whose full run counts for each outcome (``failed`` over every run, the others over the finished ones),
    # and which had it
    ran_any = table["full_run"].to_numpy()
    finished = ran_any & (table["failed"].to_numpy() == 0)
    had = {name: table[name].to_numpy() == 1 for name in OUTCOMES}

    def estimates(mask: np.ndarray) -> dict[str, dict]:
        return {
            name: stratified(codes[mask], (ran_any if name == "failed" else finished)[mask], had[name][mask])
            for name in OUTCOMES
        }

    overall = estimates(np.ones(len(values), dtype=bool))
    record: dict[str, Any] = {
        "fidelity": "multi",
        "runs": len(values),
        "full_runs": len(chosen),
        "margin": MARGIN,
        "sort_time": sort_time,
        "samples": {d.key: d.text for d in distributions},
        "strata": {name: int((codes == h).sum()) for h, name in enumerate(STRATA)},
        "probability": {name: e["probability"] for name, e in overall.items()},
        "interval": {name: e["interval"] for name, e in overall.items()},
        "by_stratum": overall["unstable"]["strata"],
        "interval_method": INTERVAL,
    }
    if bins is not None:
        key, edges = bins
        index = bin_index(table[key].to_numpy(float), edges)
        record["by"], record["curve"] = key, []
        for b in range(len(edges) - 1):
            found = estimates(index == b)
            entry: dict[str, Any] = {
                "bin": [float(edges[b]), float(edges[b + 1])],
                "runs": int((index == b).sum()),
                "full_runs": int(ran_any[index == b].sum()),
            }
            entry.update({name: e["probability"] for name, e in found.items()})
            entry["interval"] = {name: e["interval"] for name, e in found.items()}
            record["curve"].append(entry)
    return record, table


INTERVAL = (
    "stratified by the reduced model's sort: the sum of each stratum's Wilson bounds and the samples' own"
    " Monte Carlo error, Bonferroni, 95 % jointly (conservative)"
)


def interval_cell(interval: Sequence[float | None], spec: str = ".3g") -> str:
    """A range as a table cell, ``low - high`` (a 95 % interval, a bin), each bound a
    :func:`~..engine.report.number_cell`."""
    low, high = interval
    return f"{number_cell(low, spec)} - {number_cell(high, spec)}"


def multi_markdown(record: dict, name: str) -> str:
    """The report of a multi-fidelity ensemble."""
    strata = record["strata"]
    lines = [
        f"# {name}: a multi-fidelity ensemble of {record['runs']} samples, {record['full_runs']} full runs",
        "",
        f"Design {record['design']}, seed {record['seed']}. The reduced pitch-plane model sorted every sample by"
        f" its runs at its speed -/+ {100 * record['margin']:.1f} % ({record['sort_time']:.1f} s): stable"
        f" {strata['stable']}, unstable {strata['unstable']}, near the boundary {strata['near']}. Full runs:"
        f" {record['by_stratum']['near']['runs']} near, an audit of {record['by_stratum']['stable']['runs']} stable"
        f" and {record['by_stratum']['unstable']['runs']} unstable. Each stratum's probability is measured by its"
        f" full runs (the estimate does not trust the sort); intervals: {INTERVAL}.",
        "",
    ]
    probabilities = [
        [outcome, number_cell(p), interval_cell(record["interval"][outcome])]
        for outcome, p in record["probability"].items()
    ]
    lines += markdown_table(["outcome", "probability", "95 % interval"], probabilities)
    strata_rows = [[name, c["samples"], c["runs"], c["count"]] for name, c in record["by_stratum"].items()]
    lines += ["", *markdown_table(["stratum", "samples", "full runs", "unstable among them"], strata_rows)]
    if "curve" in record:
        bins = [
            [
                interval_cell(b["bin"], "g"),
                b["runs"],
                b["full_runs"],
                number_cell(b["unstable"]),
                interval_cell(b["interval"]["unstable"]),
            ]
            for b in record["curve"]
        ]
        header = ["bin", "samples", "full runs", "unstable", "95 % interval"]
        lines += ["", f"By {record['by']}:", "", *markdown_table(header, bins)]
        lines += ["", "![probabilities by bin](ensemble_curve.png)"]
    return "\n".join(lines) + "\n"
