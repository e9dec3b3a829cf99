"""``penetrate ensemble``: a scene's runs under sampled impact conditions, and what they show.

The samples (:mod:`.sampling`) become typed :class:`~cases.studies.engine.sweep.Variation` objects and
run through :func:`~cases.studies.engine.sweep.run_sweep`, so each run is stored under its resolved
scene's key: the same seed gives the same runs on any pool, a killed ensemble resumes, and a
larger ``count`` (random or Sobol' design) runs only the new samples.  The study writes
``ensemble.csv`` (a row per run: its sample, outcomes and summary, without the timings), ``ensemble.json``,
``ensemble.md`` and the figures ``ensemble_histograms.png`` and, with bins, ``ensemble_curve.png``.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from ...run import CONVERGENCE_THRESHOLD, RunStore, convergence_speed
from ...run.persistence import json_safe
from ...scene import InputError, Overrides, one_line
from ...viz.figures import axis_label, legend_outside, quantity_unit, save_figure, subplots
from ..engine.pool import Pool
from ..engine.report import Report, markdown_table, number_cell, write_report
from ..engine.sweep import Sweep, SweepResult, Variation, run_sweep
from .multifidelity import FULL_RUNS, check_applies, interval_cell, multi_ensemble, multi_markdown
from .sampling import (
    OUTCOMES,
    Distribution,
    curve,
    draw,
    estimate,
    outcomes,
    parse_bins,
    parse_sample,
    summary_record,
    variations,
)

__all__ = ["run_ensemble", "INTERVAL", "FIDELITIES"]

FIDELITIES = ("full", "multi")

VOLATILE = ("wall_time", "integration_time")  # summary fields that differ from one run of a scene to the next

INTERVAL = "Wilson score, 95 %"


def _distributions(samples: Sequence[str], base: Sweep) -> list[Distribution]:
    if not samples:
        raise InputError("--sample: give one or more KEY=DIST options, e.g. impact.speed=normal:300:10")
    distributions = [parse_sample(text, base.scenes[0]) for text in samples]
    keys = [d.key for d in distributions]
    repeated = sorted({k for k in keys if keys.count(k) > 1})
    if repeated:
        raise InputError(f"--sample: {', '.join(repeated)} sampled more than once (allowed: one --sample per key)")
    return distributions


def _sweep(
    base: Sweep, distributions: list[Distribution], values: np.ndarray, seed: int, indices: np.ndarray | None = None
) -> Sweep:
    """The runs of the samples ``indices`` (default: all) as a sweep; a sample outside the scene's allowed range
    is refused with its index."""
    indices = np.arange(len(values)) if indices is None else np.asarray(indices, dtype=int)
    parts = variations(distributions, values[indices])
    try:
        return Sweep(base.base, parts, base.source)
    except InputError as exc:
        bad = next(int(indices[i]) for i, v in enumerate(parts) if _invalid(base, v))
        values_text = ", ".join(f"{k} = {v:g}" for k, v in variations(distributions, values[[bad]])[0].values.items())
        raise InputError(
            f"sample {bad} of seed {seed} ({values_text}"
            f"): {one_line(exc)}; keep the samples in range (truncnormal, uniform, choice)"
        ) from None


def _invalid(base: Sweep, variation: Variation) -> bool:
    try:
        Sweep(base.base, [variation], base.source)
    except InputError:
        return True
    return False


def run_ensemble(
    scene: str | os.PathLike,
    overrides: Overrides | None,
    samples: Sequence[str],
    count: int,
    store: RunStore,
    out: str | os.PathLike,
    *,
    seed: int = 0,
    design: str = "random",
    by: str | None = None,
    pool: Pool | None = None,
    fidelity: str = "full",
    full_runs: int = FULL_RUNS,
) -> dict:
    """Run ``count`` samples of ``scene``; write the report in ``out`` and return its JSON record.

    Parameters
    ----------
    scene, overrides
        The base scene file and its ``--set`` overrides.
    samples : sequence of str
        The ``--sample KEY=DIST`` texts (:func:`~cases.studies.ensemble.sampling.parse_sample`).
    count : int
        How many runs.
    store : RunStore
        Where runs are found and kept.
    out : path
        Where ``ensemble.csv``, ``.json``, ``.md`` and the figures go.
    seed : int
        The seed of the samples.
    design : str
        ``random``, ``sobol`` or ``lhs`` (:func:`~cases.studies.ensemble.sampling.unit_points`).
    by : str, optional
        ``KEY=START:STOP:STEP``: the outcomes' probabilities in bins of a sampled key.
    pool : Pool, optional
        Where the runs go.
    fidelity : {"full", "multi"}
        ``full``: a full run per sample; ``multi``: the reduced model sorts every sample and ``full_runs``
        full runs measure each sort (:mod:`.multifidelity`).
    full_runs : int
        How many full runs a ``multi`` ensemble makes.

    Returns
    -------
    dict
        ``{"runs", "probability", "interval", "curve", ...}``.
    """
    if fidelity not in FIDELITIES:
        raise InputError(f"--fidelity {fidelity!r}: expected one of {', '.join(FIDELITIES)}")
    base = Sweep.from_file(scene, overrides)
    distributions = _distributions(samples, base)
    bins = parse_bins(by, [d.key for d in distributions]) if by else None
    if fidelity == "multi":
        check_applies(base.scenes[0], [d.key for d in distributions])
    values = draw(distributions, count, seed, design)
    if fidelity == "multi":
        name = base.scenes[0].name or Path(scene).stem
        # a sample out of the scene's range is refused before anything runs: each key's extremes are checked
        extremes = np.unique(np.concatenate([values.argmin(axis=0), values.argmax(axis=0)]))
        _sweep(base, distributions, values, seed, extremes)

        def sweep_of(indices: np.ndarray) -> Sweep:
            return _sweep(base, distributions, values, seed, indices)

        record, samples_table = multi_ensemble(
            base, distributions, values, store, pool or Pool(), seed, full_runs, bins, sweep_of
        )
        record.update(design=design, seed=seed)
        _write_multi(Path(out), record, samples_table, name)
        return json_safe(record)
    result = run_sweep(_sweep(base, distributions, values, seed), store, pool)
    table = _table(result)
    record = summary_record(estimate(table), count)
    record.update(
        interval_method=INTERVAL,
        design=design,
        seed=seed,
        samples={d.key: d.text for d in distributions},
        finished=int((~table["failed"]).sum()),
        distributions=_quantiles(table),
    )
    if bins is not None:
        key, edges = bins
        record["by"] = key
        record["curve"] = curve(table[key].to_numpy(float), table, edges)
    # the runs' wall and integration times stay in the run store: without them the same seed writes the
    # same bytes on any number of workers or on a cluster
    shown = table.drop(columns=list(VOLATILE), errors="ignore")
    figures: dict[str, Callable[[Path], None]] = {
        "ensemble_histograms.png": lambda path: _histograms(table, distributions, path)
    }
    if bins is not None:
        figures["ensemble_curve.png"] = lambda path: _curve_figure(record, path)
    markdown = _markdown(record, table, base.scenes[0].name or Path(scene).stem)
    write_report(out, Report("ensemble", markdown, shown, record, figures))
    return json_safe(record)


def _table(result: SweepResult) -> pd.DataFrame:
    """The sweep's table with the sample index first, the outcomes after the sampled keys, and each
    finished run's convergence speed (from its stored history; empty where the attack angle never
    peaked and fell below the threshold, or the run failed)."""
    table = result.table()
    table.insert(0, "sample", range(len(table)))
    columns = len(result.sweep.variations[0].values) + 1
    for i, (name, column) in enumerate(outcomes(result).items()):
        table.insert(columns + i, name, column.to_numpy())
    # a run whose attack angle never reached the threshold had nothing to converge from
    speeds = [
        convergence_speed(result.history(i))
        if run.summary is not None and run.summary.max_attack_angle >= CONVERGENCE_THRESHOLD
        else None
        for i, run in enumerate(result.runs)
    ]
    table["convergence_speed"] = [math.nan if v is None else float(v) for v in speeds]
    return table


#: the distributions an ensemble reports: run quantities and their units
DISTRIBUTED = {
    "depth": "m",
    "path_length": "m",
    "axis_angle_change": "deg",
    "convergence_speed": "m/s",
    "residual_velocity": "m/s",
}
QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)


def _quantiles(table: pd.DataFrame) -> dict:
    """``{quantity: {"runs": n, "mean": m, "quantiles": {"0.05": q, ...}}}`` over the runs that have it."""
    record = {}
    for name in DISTRIBUTED:
        values = table[name].dropna().astype(float).to_numpy() if name in table else np.array([])
        record[name] = {
            "runs": int(len(values)),
            "mean": float(values.mean()) if len(values) else None,
            "quantiles": {f"{q:g}": (float(np.quantile(values, q)) if len(values) else None) for q in QUANTILES},
        }
    return record


def _markdown(record: dict, table: pd.DataFrame, name: str) -> str:
    lines = [
        f"# {name}: an ensemble of {record['runs']} runs",
        "",
        f"Design {record['design']}, seed {record['seed']}; {record['finished']} runs finished. Unstable: the axis"
        " turned by at least 30 degrees (as `penetrate critical` decides). `failed` is counted over every run,"
        f" the other outcomes over the finished runs; intervals: {INTERVAL}.",
        "",
    ]
    samples = []
    for key, text in record["samples"].items():
        column = table[key].astype(float)
        samples.append([key, text, *(number_cell(v, ".4g") for v in (column.min(), column.mean(), column.max()))])
    lines += markdown_table(["sampled key", "distribution", "min", "mean", "max"], samples)
    quantities = []
    for name, unit in DISTRIBUTED.items():
        d = record["distributions"][name]
        quantiles = [number_cell(v) for v in d["quantiles"].values()]
        quantities.append([f"{name} ({unit})", d["runs"], number_cell(d["mean"]), *quantiles])
    lines += ["", *markdown_table(["quantity", "runs", "mean", *(f"{q:.0%}" for q in QUANTILES)], quantities)]
    lines += [
        "",
        "(quantiles over the finished runs; the convergence speed over the runs whose attack angle"
        " peaked and fell below 0.1 degree, the residual velocity over the runs that perforated)",
    ]
    probabilities = [
        [outcome, number_cell(record["probability"][outcome]), interval_cell(record["interval"][outcome])]
        for outcome in OUTCOMES
    ]
    lines += ["", *markdown_table(["outcome", "probability", "95 % interval"], probabilities)]
    if "curve" in record:
        bins = [
            [
                interval_cell(b["bin"], "g"),
                b["runs"],
                *(f"{number_cell(b[o])} ({interval_cell(b['interval'][o])})" for o in OUTCOMES),
            ]
            for b in record["curve"]
        ]
        lines += ["", f"By {record['by']}:", "", *markdown_table(["bin", "runs", *OUTCOMES], bins)]
        lines += ["", "![probabilities by bin](ensemble_curve.png)"]
    lines += ["", "![the samples and the outcomes' distributions](ensemble_histograms.png)", ""]
    # what found nothing, last (the printed report ends with it), with the option that would find something
    empty = _empty_bins(record, table) if "curve" in record else ""
    if empty:
        lines += [empty, ""]
    if record["finished"] == 0:
        lines += [
            "No run finished, so no outcome but `failed` has a probability: the `error` column of ensemble.csv"
            " says why, and `penetrate --debug run` of the scene with a sample's values (`--set KEY=VALUE`)"
            " shows its traceback.",
            "",
        ]
    return "\n".join(lines)


def _empty_bins(record: dict, table: pd.DataFrame) -> str:
    """A line on the bins no sample fell in, with the option that would fill them: bins over the sampled values
    (``--by``) where the empty ones lie outside them, else more runs (``-n``)."""
    curve, key = record["curve"], record["by"]
    empty = [b["bin"] for b in curve if not b["runs"]]
    if not empty:
        return ""
    values = table[key].astype(float)
    low, high = float(values.min()), float(values.max())
    names = ", ".join(f"{lo:g} - {hi:g}" for lo, hi in empty)
    if all(hi <= low or lo > high for lo, hi in empty):
        step = curve[0]["bin"][1] - curve[0]["bin"][0]
        start = math.floor(low / step) * step
        stop = max(math.ceil(high / step) * step, start + step)
        fix = f"bin where the samples lie ({low:.4g} to {high:.4g}), e.g. --by {key}={start:g}:{stop:g}:{step:g}"
    else:
        fix = f"give more runs (-n {2 * record['runs']}) or widen the distribution of {key} (--sample) over them"
    return f"No sample fell in {len(empty)} of {len(curve)} bins ({names}): {fix}."


def _histograms(table: pd.DataFrame, distributions: list[Distribution], path: Path) -> None:
    panels = [d.key for d in distributions] + [name for name in DISTRIBUTED if name in table]
    columns = min(4, len(panels))
    rows = -(-len(panels) // columns)
    fig, axes = subplots(rows, columns, figsize=(4.2 * columns, 3.4 * rows), squeeze=False)
    for ax in axes.flat[len(panels) :]:
        ax.set_visible(False)
    for ax, column in zip(axes.flat, panels):
        values = table[column].dropna().astype(float)
        ax.hist(values, bins=min(30, max(5, len(values) // 5)), color="tab:blue", alpha=0.8)
        ax.set(xlabel=axis_label(column, DISTRIBUTED.get(column, quantity_unit(column))), ylabel=axis_label("runs", ""))
        ax.grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path)


def _curve_figure(record: dict, path: Path) -> None:
    fig, ax = subplots(1, 1, figsize=(7.6, 4.2))
    middles = [0.5 * (b["bin"][0] + b["bin"][1]) for b in record["curve"]]
    # an outcome that no run had would only lay its band over the others: left out, and said so
    shown = [o for o in OUTCOMES if any(b.get(o) for b in record["curve"] if b.get(o) is not None and b[o] == b[o])]
    for outcome in shown:
        p = [b[outcome] for b in record["curve"]]
        low, high = ([b["interval"][outcome][i] for b in record["curve"]] for i in (0, 1))
        (line,) = ax.plot(middles, p, marker="o", label=outcome)
        ax.fill_between(middles, low, high, color=line.get_color(), alpha=0.2)
    absent = [o for o in OUTCOMES if o not in shown]
    ax.set(
        xlabel=axis_label(record["by"], quantity_unit(record["by"])),
        ylabel=axis_label("probability", ""),
        ylim=(-0.02, 1.02),
        title=f"outcomes by {record['by']} ({INTERVAL} bands)" + (f"\nnever: {', '.join(absent)}" if absent else ""),
    )
    ax.grid(alpha=0.3)
    legend_outside(ax)  # the bands span the plot: no spot inside is free
    fig.tight_layout()
    save_figure(fig, path)


def _write_multi(out: Path, record: dict, samples: pd.DataFrame, name: str) -> None:
    """A multi-fidelity ensemble's files: the samples' table, its JSON, the report and the curve."""
    figures = {"ensemble_curve.png": lambda path: _curve_figure(record, path)} if "curve" in record else {}
    write_report(out, Report("ensemble", multi_markdown(record, name), samples, record, figures))
