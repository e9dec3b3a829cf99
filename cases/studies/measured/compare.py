"""Run one scene under several resistance laws, side by side: ``penetrate compare``.

Any law a scene takes can be compared: a name, a family's coefficients or a user's function.  For each law the
report gives the scene's run (depth, path, turn, end), optionally the depth against the impact speed, the
critical and the convergent speeds, and the normal stress on the body at one instant: the scene's start
moved one body length into the target, so every law is seen on the same state.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ...run import RunStore, initial_state, prepare_projectile
from ...scene import InputError, Overrides, Scene
from ...viz.figures import legend_outside, save_figure, subplots
from ..engine.pool import Pool
from ..engine.report import Report, markdown_table, number_cell, write_report
from ..engine.sweep import Sweep, SweepResult, Variation, end_cells, run_sweep
from ..speeds.characteristic import find_critical_velocities, measure_convergent_velocity
from .series import Series, combined

__all__ = ["compare_laws", "compare_series", "LawComparison", "SeriesComparison", "law_values", "COLUMNS", "SCENE_LAW"]

#: the label of the scene's own law in a comparison (``--laws scene``)
SCENE_LAW = "scene"

COLUMNS = ("end_reason", "depth", "path_length", "final_time", "max_attack_angle", "axis_angle_change")
UNITS = "Units: m, m, s, deg, deg; speeds m/s; stress MPa."


@dataclass
class LawComparison:
    """What :func:`compare_laws` measured: the table (one row per law) and what the figure draws."""

    table: pd.DataFrame
    runs: SweepResult
    depth_by_speed: pd.DataFrame | None
    nose_stress: dict[str, tuple[np.ndarray, np.ndarray]]
    body_lengths: list[float] | None = None


def compare_laws(
    scene: str | os.PathLike,
    overrides: Overrides | None,
    laws: Sequence[tuple[str, Any]],
    store: RunStore,
    out: str | os.PathLike,
    pool: Pool | None = None,
    speeds: Sequence[float] | None = None,
    critical: tuple[float, float] | None = None,
    resolution: float = 5.0,
    convergent: bool = False,
) -> LawComparison:
    """Run ``scene`` once per law; write ``compare.csv``, ``compare.md`` and ``compare.png`` in ``out``.

    Parameters
    ----------
    laws : sequence of (label, law)
        Each law as ``target.law`` takes it (a name, or a table), or None for the scene's own law; every
        scene is checked before any run.
    speeds : sequence of float, optional
        Impact speeds (m/s) at which each law's depth is measured too.
    critical : (low, high), optional
        The range (m/s) in which each law's critical speed is sought, to ``resolution``.
    convergent : bool
        Also measure each law's characteristic convergent speed.
    """
    variations = [Variation(law_values(law)) for _, law in laws]
    sweep = Sweep.from_file(scene, overrides, variations)
    labels = [label for label, _ in laws]
    result = run_sweep(sweep, store, pool)
    table = result.table()
    table.insert(0, "law", labels)
    table = table.drop(columns=["target.law"], errors="ignore")
    depth_by_speed = None
    if speeds:
        by_speed = Sweep.from_file(
            scene, overrides, [Variation({**v.values, "impact.speed": float(s)}) for v in variations for s in speeds]
        )
        grid = run_sweep(by_speed, store, pool).table()
        grid.insert(0, "law", [label for label in labels for _ in speeds])
        depth_by_speed = grid[["law", "impact.speed", "depth", "end_reason"]]
    if critical is not None:
        bases = [Sweep(sweep.base, [v], sweep.source) for v in variations]
        searches = find_critical_velocities(bases, store, critical, resolution, pool)
        table["critical_speed"] = [s.critical_velocity for s in searches]
    if convergent:
        found = [
            measure_convergent_velocity(Sweep(sweep.base, [v], sweep.source), store, pool=pool) for v in variations
        ]
        table["convergent_speed"] = [f.characteristic_convergent_velocity for f in found]
    stress = {label: embedded_stress(s) for label, s in zip(labels, sweep.scenes)}
    table["peak_nose_stress"] = [float(values.max()) / 1e6 for _, values in stress.values()]
    lengths = [float(prepare_projectile(s).profile.length) for s in sweep.scenes]
    comparison = LawComparison(table, result, depth_by_speed, stress, lengths)
    name = sweep.scenes[0].name or Path(scene).stem
    figures = {"compare.png": lambda path: _figure(comparison, path)}
    write_report(out, Report("compare", _markdown(comparison, name), table, figures=figures))
    return comparison


def law_values(law: Any | None) -> dict[str, Any]:
    """The scene keys that give a scene ``law`` (None: the scene's own, nothing set)."""
    return {} if law is None else {"target.law": law}


def embedded_stress(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """``(x, sigma_n)``: the axial position (m, from the tip, backwards) and normal stress (Pa) of every surface
    point at the scene's start (speed, attitude, spin) moved one body length below the surface."""
    prepared = prepare_projectile(scene)
    loads = scene.loads(prepared.quadrature)
    state = initial_state(scene, prepared)
    rotation = state.rotation
    position = np.array([0.0, 0.0, -(loads.max_radius + prepared.profile.length)])
    field = loads.surface_stress(position, state.velocity, rotation, state.angular_velocity)
    x = float(prepared.tip[0]) - prepared.quadrature.points[:, 0]
    return x, field.sigma_n


def _markdown(comparison: LawComparison, name: str) -> str:
    table = comparison.table
    shown = [c for c in ("law", *COLUMNS, "critical_speed", "convergent_speed", "peak_nose_stress") if c in table]
    lines = [
        f"# {name} under {len(table)} resistance law{'s' if len(table) != 1 else ''}",
        "",
    ]
    ends, notes = end_cells(
        [
            (str(row["end_reason"]), json.loads(row["warnings"]) if isinstance(row.get("warnings"), str) else [])
            for _, row in table.iterrows()
        ]
    )
    rows = []
    for (_, row), end in zip(table.iterrows(), ends):
        row = row.copy()
        row["end_reason"] = end
        rows.append([number_cell(row[c], ".4g", missing="none found") for c in shown])
    lines += markdown_table(shown, rows)
    lines += ["", *[f"[{i}] {note}" for i, note in enumerate(notes, 1)]] if notes else []
    lines += ["", UNITS, "peak_nose_stress: the largest normal stress one body length in, at the impact speed.", ""]
    short = [
        f"{law} stopped at {depth:.3g} m, short of one body length ({length:.3g} m)"
        for law, depth, length in zip(table["law"], table.get("depth", []), comparison.body_lengths or [])
        if isinstance(depth, float) and depth < length
    ]
    if short:
        lines += [
            "The stress one body length in is of a state these runs never reach: " + "; ".join(short) + ".",
            "",
        ]
    if comparison.depth_by_speed is not None:
        wide = comparison.depth_by_speed.pivot(index="impact.speed", columns="law", values="depth")
        lines += ["Depth (m) against impact speed (m/s):", ""]
        lines += markdown_table(
            ["impact speed", *wide.columns],
            [
                [number_cell(speed, "g"), *(number_cell(depth, ".4g") for depth in row)]
                for speed, row in wide.iterrows()
            ],
        )
        lines.append("")
    lines += ["![runs, depth against speed, stress on the body](compare.png)", ""]
    return "\n".join(lines)


def _figure(comparison: LawComparison, path: Path) -> None:
    panels = 3 if comparison.depth_by_speed is not None else 2
    fig, axes = subplots(1, panels, figsize=(5.0 * panels + 1.5, 4.4))
    result = comparison.runs
    for i, label in enumerate(comparison.table["law"]):
        if not result.runs[i].failed:
            h = result.history(i)
            axes[0].plot(h["tip_depth"], h["speed"], label=label)
        x, sigma = comparison.nose_stress[label]
        order = np.argsort(x)
        axes[1].plot(x[order], sigma[order] / 1e6, ".", markersize=2, label=label)
        if comparison.depth_by_speed is not None:
            rows = comparison.depth_by_speed[comparison.depth_by_speed["law"] == label]
            axes[2].plot(rows["impact.speed"], rows["depth"], "o-", label=label)
    axes[0].set(xlabel="depth of the nose tip (m)", ylabel="speed (m/s)", title="speed against depth")
    axes[1].set(
        xlabel="distance from the tip along the axis (m)",
        ylabel="normal stress (MPa)",
        title="stress on the body, one length in",
    )
    if comparison.depth_by_speed is not None:
        axes[2].set(xlabel="impact speed (m/s)", ylabel="depth of the nose tip (m)", title="depth against speed")
    for ax in axes:
        ax.grid(alpha=0.3)
    legend_outside(axes[-1])  # the same laws in every panel: one legend, right of the panels
    fig.tight_layout()
    save_figure(fig, path)


@dataclass
class SeriesComparison:
    """What :func:`compare_series` measured: each law's predictions of the series, and the laws ranked."""

    rows: list[dict[str, Any]]
    ranking: list[dict[str, Any]]
    settings: list[tuple[str, Any]]
    source: str

    def record(self) -> dict[str, Any]:
        return {"series": self.source, "ranking": self.ranking, "shots": self.rows}


def compare_series(
    series: Series,
    overrides: Overrides | None,
    laws: Sequence[tuple[str, Any]],
    store: RunStore,
    out: str | os.PathLike,
    pool: Pool | None = None,
    with_formulas: bool = False,
) -> SeriesComparison:
    """Every shot of ``series`` under each law; the laws ranked by their mean |error| over every measurement
    (then chi-squared); ``compare.md``, ``compare.csv``, ``compare.json`` and ``compare.png`` in ``out``.

    ``laws`` as :func:`compare_laws` takes them (None: each shot's scene's own law).  A series whose columns
    set the law of each shot is refused: there would be nothing to compare.  ``with_formulas``: the empirical
    formulas' depths (:func:`~.formulas.formula_rows`, on each shot's own scene) ranked with the laws, each
    entry's ``kind`` saying which it is.
    """
    from .validate import error_summary, figure, prediction_rows

    setting = [key for key in series.columns if key == "target" or key.startswith(("target.law", "target.layers"))]
    if setting:
        raise InputError(
            f"compare --series: the series sets {setting[0]} per shot (a column), which the laws would replace;"
            " drop the column, or compare with penetrate validate --set target.law=... one law at a time"
        )
    settings = list(overrides.items() if isinstance(overrides, Mapping) else overrides or [])
    result = run_sweep(combined(series, series.parts(settings, [law_values(law) for _, law in laws])), store, pool)
    rows = []
    ranking = []
    for k, (label, _) in enumerate(laws):
        mine = [{"law": label, **row} for row in prediction_rows(series, result, offset=k * len(series.shots))]
        rows += mine
        quantities = list(dict.fromkeys(row["quantity"] for row in mine))
        ranking.append(
            {
                "law": label,
                "kind": "law",
                **error_summary(mine),
                "quantities": {q: error_summary([r for r in mine if r["quantity"] == q]) for q in quantities},
            }
        )
    if with_formulas:
        estimates, ranked = _formula_entries(series, settings)
        rows += estimates
        ranking += ranked
    ranking.sort(key=_rank)
    for place, entry in enumerate(ranking, start=1):
        entry["rank"] = place
    comparison = SeriesComparison(rows, ranking, settings, series.source)
    table = pd.DataFrame([{**row, "warnings": "; ".join(w for w in row["warnings"] if w)} for row in rows])
    figures = {"compare.png": lambda path: figure(rows, {}, path, colour_by="law")}
    markdown = _series_markdown(comparison, series)
    write_report(out, Report("compare", markdown, table, comparison.record(), figures))
    return comparison


def _formula_entries(series: Series, settings: list[tuple[str, Any]]) -> tuple[list[dict], list[dict]]:
    """The empirical formulas' rows (one per measured depth, shaped as a law's) and ranking entries: each shot's
    scene as the series and ``settings`` give it, whatever laws are compared."""
    from .formulas import formula_rows
    from .validate import error_summary

    scenes = combined(series, series.parts(settings)).scenes
    found, _ = formula_rows(series, scenes)
    speeds = {shot.label: scene.impact.speed for shot, scene in zip(series.shots, scenes)}
    rows = [
        {"law": row["formula"], "quantity": "depth", "impact_speed": speeds[row["label"]], "end_reason": None}
        | {"warnings": [], **row}
        for row in found
    ]
    ranking = []
    for name in dict.fromkeys(row["law"] for row in rows):
        mine = [row for row in rows if row["law"] == name]
        summary = error_summary(mine)
        ranking.append({"law": name, "kind": "formula", **summary, "quantities": {"depth": summary}})
    return rows, ranking


def _rank(entry: Mapping[str, Any]) -> tuple[float, float]:
    """Mean |error| first (a law whose every run failed last), then chi-squared where given."""
    mean = entry["mean_abs_error_percent"]
    chi2 = entry["chi2"]
    return (math.inf if mean is None or entry["failed"] else mean, math.inf if chi2 is None else chi2)


def _series_markdown(comparison: SeriesComparison, series: Series) -> str:
    from .validate import error_cells, settings_lines

    name = Path(series.source).name
    laws = [entry["law"] for entry in comparison.ranking]
    count = sum(entry["kind"] == "law" for entry in comparison.ranking)
    formulas = len(laws) - count
    lines = [
        f"# {name}: {len(series.shots)} shots under {count} resistance law{'s' if count != 1 else ''}"
        + (f" and {formulas} empirical formula{'s' if formulas != 1 else ''}" if formulas else "")
    ]
    lines.append("")
    lines += settings_lines(comparison.settings)
    lines += markdown_table(
        ["rank", "law", "measurements", "mean abs error (%)", "bias (%)", "RMS (%)", "chi-squared"],
        [
            [
                entry["rank"],
                entry["law"] if entry["kind"] == "law" else f"{entry['law']} (formula)",
                f"{entry['shots']} ({entry['failed']} failed)" if entry["failed"] else entry["shots"],
                *error_cells(entry),
            ]
            for entry in comparison.ranking
        ],
    )
    lines += [
        "",
        "Ranked by the mean |error| over every measurement (per cent of the measurement), then chi-squared"
        " (where every shot gives a sigma). The scene's own law is `scene`."
        + (
            " A formula predicts the depths of the shots it describes, each on the shot's own target"
            " (penetrate formulas)."
            if any(entry["kind"] == "formula" for entry in comparison.ranking)
            else ""
        ),
        "",
    ]
    by_key = {(row["law"], row["label"], row["quantity"]): row for row in comparison.rows}
    lines += markdown_table(
        ["shot", "quantity", "measured", *laws],
        [
            [
                shot.label,
                measurement.quantity,
                number_cell(measurement.value, ".4g"),
                *(_prediction_cell(by_key.get((law, shot.label, measurement.quantity))) for law in laws),
            ]
            for shot in series.shots
            for measurement in shot.measurements
        ],
    )
    lines += ["", "Predicted (error against the measurement); SI units.", "", "![parity by law](compare.png)", ""]
    return "\n".join(lines)


def _prediction_cell(row: Mapping[str, Any] | None) -> str:
    """One law's prediction of one measurement: ``predicted (error %)``, with the run's end unless it stopped or
    exited (a formula has none); ``failed`` for a run that gave none; ``-`` for a formula's missing quantity."""
    if row is None:
        return "-"
    if row["predicted"] is None:
        return "failed"
    end = "" if row["end_reason"] in (None, "stopped", "exited") else f", {row['end_reason']}"
    return f"{number_cell(row['predicted'], '.4g')} ({number_cell(row['error_percent'], '+.1f')} %{end})"
