"""Predictions against measurements: every shot of a series run and compared, ``penetrate validate``.

Each measured quantity of each shot gives one row: predicted, measured, the error in per cent of the
measurement, and where a sigma is given the residual in sigmas.  The summary, per quantity and per group,
gives the mean absolute error, the bias (the mean signed error), the RMS error (all in per cent of the
measurements) and, where every shot of it gives a sigma, chi-squared.  Runs go through the run store
and the worker pool as every study's do: a validation run again makes no new run.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...run import RunStore
from ...scene import Overrides
from ..engine.pool import Pool
from ..engine.report import Report, markdown_table, number_cell, write_report
from ..engine.sweep import SweepResult, end_cells, run_sweep
from .series import Series, Shot, combined, run_value

__all__ = [
    "Validation",
    "validate",
    "prediction_rows",
    "error_summary",
    "write_validation",
    "curve_variations",
    "CURVE_POINTS",
]

#: impact speeds of a group's predicted curve (``--curve-points``)
CURVE_POINTS = 12


def prediction_rows(series: Series, result: SweepResult, offset: int = 0) -> list[dict[str, Any]]:
    """One row per measurement: the shot's label and group, the quantity, predicted and measured, the error
    (per cent of the measurement), sigma and the residual in sigmas, the impact speed, the run's end reason and
    warnings.  ``result`` holds the shots' runs from index ``offset`` on, in the series' order."""
    rows = []
    for index, shot in enumerate(series.shots):
        run = result.runs[offset + index]
        scene = result.sweep.scenes[offset + index]
        for measurement in shot.measurements:
            predicted = run_value(result, offset + index, measurement.quantity)
            error = None
            if predicted is not None and measurement.value != 0:
                error = 100.0 * (predicted - measurement.value) / abs(measurement.value)
            rows.append(
                {
                    "label": shot.label,
                    "group": shot.group,
                    "quantity": measurement.quantity,
                    "impact_speed": scene.impact.speed,
                    "predicted": predicted,
                    "measured": measurement.value,
                    "error_percent": error,
                    "sigma": measurement.sigma,
                    "residual_sigmas": (
                        None
                        if predicted is None or measurement.sigma is None
                        else (predicted - measurement.value) / measurement.sigma
                    ),
                    "end_reason": "failed" if run.summary is None else run.summary.end_reason,
                    "warnings": [run.error or ""] if run.summary is None else list(run.summary.warnings),
                }
            )
    return rows


def error_summary(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Mean |error|, bias and RMS (per cent), chi-squared (all sigmas given, else None) over ``rows`` of one
    quantity; rows without a prediction (failed runs) are counted apart, as ``failed``."""
    done = [row for row in rows if row["error_percent"] is not None]
    errors = np.array([row["error_percent"] for row in done], dtype=float)
    sigmas = [row["residual_sigmas"] for row in done]
    chi2 = float(sum(z * z for z in sigmas)) if done and all(z is not None for z in sigmas) else None
    return {
        "shots": len(done),
        "failed": len(rows) - len(done),
        "mean_abs_error_percent": float(np.mean(np.abs(errors))) if done else None,
        "bias_percent": float(np.mean(errors)) if done else None,
        "rms_percent": float(np.sqrt(np.mean(errors**2))) if done else None,
        "chi2": chi2,
    }


def error_cells(summary: Mapping[str, Any]) -> list[str]:
    """A table's cells of an :func:`error_summary`: mean |error|, bias and RMS (per cent), then chi-squared."""
    return [
        number_cell(summary["mean_abs_error_percent"], ".1f"),
        number_cell(summary["bias_percent"], "+.1f"),
        number_cell(summary["rms_percent"], ".1f"),
        number_cell(summary["chi2"], ".3g"),
    ]


def summaries(rows: Sequence[Mapping[str, Any]]) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    """``(summary, groups)``: :func:`error_summary` per quantity, overall and per group."""
    quantities = list(dict.fromkeys(row["quantity"] for row in rows))

    def per_quantity(subset: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
        return {
            q: error_summary([r for r in subset if r["quantity"] == q])
            for q in quantities
            if any(r["quantity"] == q for r in subset)
        }

    groups = list(dict.fromkeys(row["group"] for row in rows))
    return per_quantity(rows), {g: per_quantity([r for r in rows if r["group"] == g]) for g in groups}


def curve_variations(series: Series, points: int) -> dict[str, tuple[str, dict[str, Any], list[float], list[str]]]:
    """Per group, a dense predicted curve over the impact speed: ``(scene, values, speeds, notes)``.

    A group has one when its shots share one scene and set ``impact.speed`` to at least two speeds; the other
    columns are the group's common value, or for a number that differs from shot to shot (a measured mass)
    its mean, which the notes name.  Groups of other shots (different scenes, differing texts) have none.
    """
    curves: dict[str, tuple[str, dict[str, Any], list[float], list[str]]] = {}
    if points < 2:
        return curves
    for group in series.groups:
        shots = [shot for shot in series.shots if shot.group == group]
        cells = [shot.values.get("impact.speed") for shot in shots]
        if len({shot.scene for shot in shots}) != 1 or any(not _is_number(s) for s in cells):
            continue
        speeds = [float(s) for s in cells if s is not None]
        if len(set(speeds)) < 2:
            continue
        values, notes = _common_values(shots)
        if values is None:
            continue
        low, high = min(speeds), max(speeds)
        grid = [float(f"{v:.6g}") for v in np.linspace(low, high, points)]
        curves[group] = (shots[0].scene, values, grid, notes)
    return curves


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _common_values(shots: Sequence[Shot]) -> tuple[dict[str, Any] | None, list[str]]:
    values: dict[str, Any] = {}
    notes = []
    keys = dict.fromkeys(key for shot in shots for key in shot.values if key != "impact.speed")
    for key in keys:
        cells = [shot.values.get(key) for shot in shots]
        if all(cell == cells[0] for cell in cells):
            if cells[0] is not None:
                values[key] = cells[0]
        elif all(_is_number(cell) for cell in cells):
            values[key] = float(f"{float(np.mean([float(c) for c in cells if c is not None])):.6g}")
            notes.append(f"{key} = {values[key]:g}, the mean of the group's shots")
        else:
            return None, []
    return values, notes


@dataclass
class Validation:
    """A series' predictions against its measurements (:func:`validate`)."""

    series: Series
    settings: list[tuple[str, Any]]
    rows: list[dict[str, Any]]
    summary: dict[str, Any]
    groups: dict[str, dict[str, Any]]
    curves: dict[str, dict[str, Any]] = field(default_factory=dict)
    runs: int = 0
    formulas: list[dict[str, Any]] | None = None
    formulas_refused: list[str] = field(default_factory=list)

    @property
    def failed(self) -> list[str]:
        """Labels of the shots whose run failed."""
        return list(dict.fromkeys(row["label"] for row in self.rows if row["end_reason"] == "failed"))

    def record(self) -> dict[str, Any]:
        """The JSON object ``--json`` prints: ``shots``, ``summary``, ``groups`` (and the rest)."""
        return {
            "series": self.series.source,
            "set": [f"{key}={json.dumps(value)}" for key, value in self.settings],
            "shots": self.rows,
            "summary": self.summary,
            "groups": self.groups,
            "curves": self.curves,
            "runs": self.runs,
            **({} if self.formulas is None else {"formulas": self.formulas, "formulas_refused": self.formulas_refused}),
        }


def validate(
    series: Series,
    overrides: Overrides | None,
    store: RunStore,
    pool: Pool | None = None,
    curve_points: int = CURVE_POINTS,
    with_formulas: bool = False,
) -> Validation:
    """Run every shot of ``series`` (``overrides``, ``--set``, on every shot; a column beats them for its own
    shot) and, per group, ``curve_points`` impact speeds of its predicted curve; all in one batch of runs.
    ``with_formulas``: each measured depth predicted by the empirical formulas too."""
    settings = list(overrides.items() if isinstance(overrides, Mapping) else overrides or [])
    curves = curve_variations(series, curve_points)
    parts = series.parts(settings)
    for scene, values, speeds, _ in curves.values():
        curve = Series(series.source, [Shot("curve", "", scene, values, ())])
        parts += curve.parts(settings, [{"impact.speed": speed} for speed in speeds])
    sweep = combined(series, parts)
    result = run_sweep(sweep, store, pool)
    rows = prediction_rows(series, result)
    summary, groups = summaries(rows)
    drawn: dict[str, dict[str, Any]] = {}
    start = len(series.shots)
    for group, (_, _, speeds, notes) in curves.items():
        indices = range(start, start + len(speeds))
        drawn[group] = {
            "impact_speed": speeds,
            **{q: [run_value(result, i, q) for i in indices] for q in series.quantities},
            "notes": notes,
        }
        start += len(speeds)
    validation = Validation(series, settings, rows, summary, groups, drawn, runs=len(set(sweep.keys())))
    if with_formulas:
        from .formulas import formula_rows

        validation.formulas, validation.formulas_refused = formula_rows(series, result.sweep.scenes)
    return validation


def formula_table(validation: Validation) -> list[str]:
    """The model's error on the measured depths beside each formula's: shots, mean |error|, bias, RMS (per cent)
    and how many shots lie inside every range the formula checks."""
    rows = validation.formulas or []
    table = []
    if "depth" in validation.summary:
        model = validation.summary["depth"]
        table.append(["the model (DAFL run)", model["shots"], *error_cells(model)[:3], "-"])
    for name in dict.fromkeys(row["formula"] for row in rows):
        mine = [row for row in rows if row["formula"] == name]
        summary = error_summary(mine)
        table.append([name, summary["shots"], *error_cells(summary)[:3], sum(row["valid"] for row in mine)])
    header = ["depth by", "shots", "mean abs error (%)", "bias (%)", "RMS (%)", "shots inside its ranges"]
    return markdown_table(header, table)


def summary_table(summary: Mapping[str, Any], groups: Mapping[str, Mapping[str, Any]]) -> list[str]:
    """The summary as markdown lines: per quantity, the whole series and then each group."""
    rows = []
    for scope, per_quantity in [("all", summary), *groups.items()]:
        for quantity, s in per_quantity.items():
            rows.append(
                [
                    quantity if scope == "all" else f"{quantity}, {scope}",
                    f"{s['shots']} ({s['failed']} failed)" if s["failed"] else s["shots"],
                    *error_cells(s),
                ]
            )
        if len(groups) == 1:
            break  # one group: its lines would repeat the series'
    return markdown_table(["quantity", "shots", "mean abs error (%)", "bias (%)", "RMS (%)", "chi-squared"], rows)


def settings_lines(settings: Sequence[tuple[str, Any]]) -> list[str]:
    """What a report says of ``--set``: applied to every shot, beaten by a column for its own shot."""
    if not settings:
        return []
    shown = ", ".join(f"`{key}={json.dumps(value)}`" for key, value in settings)
    return [f"Set on every shot: {shown} (a column of the series beats it for its own shot).", ""]


def markdown(validation: Validation) -> str:
    """``validate.md``: the shots' table, the summary, the settings and the figure."""
    name = Path(validation.series.source).name
    lines = [f"# {name}: {len(validation.series.shots)} shots, predicted against measured", ""]
    lines += settings_lines(validation.settings)
    ends, notes = end_cells([(row["end_reason"], row["warnings"]) for row in validation.rows])
    lines += markdown_table(
        [
            "shot",
            "group",
            "quantity",
            "impact speed (m/s)",
            "predicted",
            "measured",
            "error (%)",
            "residual / sigma",
            "end",
        ],
        [
            [
                row["label"],
                row["group"],
                row["quantity"],
                number_cell(row["impact_speed"], "g"),
                number_cell(row["predicted"], ".4g"),
                number_cell(row["measured"], ".4g"),
                number_cell(row["error_percent"], "+.1f"),
                number_cell(row["residual_sigmas"], ".3g"),
                end,
            ]
            for row, end in zip(validation.rows, ends)
        ],
    )
    lines += ["", "Units: SI (m, m/s, s, kg; angles in degrees). Error: (predicted - measured) / measured.", ""]
    lines += [*summary_table(validation.summary, validation.groups), ""]
    if notes:
        lines += ["Warnings:", "", *[f"{i}. {note}" for i, note in enumerate(notes, 1)], ""]
    if validation.formulas is not None:
        lines += ["Depth by the empirical formulas (penetrate formulas), beside the model's:", ""]
        lines += [*formula_table(validation), ""]
        lines += [f"Not described by the formulas: {line}" for line in validation.formulas_refused]
    for group, curve in validation.curves.items():
        if curve["notes"]:
            lines += [f"The predicted curve of {group}: " + "; ".join(curve["notes"]) + ".", ""]
    lines += [
        f"Runs: {validation.runs} (the shots, and the predicted curves).",
        "",
        "![parity and speed](validate.png)",
        "",
    ]
    return "\n".join(lines)


def write_validation(validation: Validation, out: str | os.PathLike) -> None:
    """``validate.csv`` (one row per measurement), ``validate.json``, ``validate.md`` and ``validate.png`` in
    ``out``, each written atomically."""
    import pandas as pd

    table = pd.DataFrame([{**row, "warnings": "; ".join(w for w in row["warnings"] if w)} for row in validation.rows])
    figures = {"validate.png": lambda path: figure(validation.rows, {"": validation.curves}, path)}
    write_report(out, Report("validate", markdown(validation), table, validation.record(), figures))


def figure(
    rows: Sequence[Mapping[str, Any]],
    curves: Mapping[str, Mapping[str, Mapping[str, Any]]],
    path: Path,
    colour_by: str = "group",
) -> None:
    """Per quantity, a parity panel (predicted against measured, with the +-10 % and +-20 % lines) and the
    quantity against the impact speed (measured points, predictions, each group's predicted curve).

    ``rows`` may carry a ``law`` (a comparison): ``colour_by`` names the field the colours follow, and
    ``curves`` holds each colour's curves by group.
    """
    from ...viz.figures import axis_label, legend_outside, quantity_unit, save_figure, subplots

    quantities = list(dict.fromkeys(row["quantity"] for row in rows))
    fig, axes = subplots(len(quantities), 2, figsize=(12.0, 4.6 * len(quantities)), squeeze=False)
    colours = list(dict.fromkeys(str(row[colour_by]) for row in rows))
    palette = {name: f"C{i % 10}" for i, name in enumerate(colours)}
    for (parity, speed), quantity in zip(axes, quantities):
        unit = quantity_unit(quantity)
        done = [r for r in rows if r["quantity"] == quantity and r["predicted"] is not None]
        values = [v for r in done for v in (r["predicted"], r["measured"])] or [0.0, 1.0]
        low, high = min(0.0, min(values)), max(values) * 1.08
        line = np.array([low, high])
        parity.plot(line, line, color="black", lw=1)
        for factor, style in ((0.1, "--"), (0.2, ":")):
            for sign in (1, -1):
                parity.plot(line, line * (1 + sign * factor), color="grey", lw=0.8, ls=style)
        parity.text(high / 1.2, high, "+20 % ", fontsize=7, color="grey", ha="right", va="top")
        parity.text(high, high * 0.8, "-20 % ", fontsize=7, color="grey", ha="right", va="bottom")
        for name in colours:
            mine = [r for r in done if str(r[colour_by]) == name]
            if not mine:
                continue
            parity.plot(
                [r["measured"] for r in mine], [r["predicted"] for r in mine], "o", color=palette[name], label=name
            )
            speed.plot(
                [r["impact_speed"] for r in mine], [r["predicted"] for r in mine], "x", color=palette[name], ms=7
            )
            for group, curve in curves.get(name, curves.get("", {})).items():
                if colour_by == "group" and group != name:
                    continue
                speed.plot(
                    curve["impact_speed"],
                    curve.get(quantity),
                    "-",
                    color=palette[name],
                    lw=1.2,
                    label=f"{name}, predicted",
                )
        measured = [r for r in rows if r["quantity"] == quantity]
        speed.plot(
            [r["impact_speed"] for r in measured],
            [r["measured"] for r in measured],
            "o",
            mfc="none",
            mec="black",
            label="measured",
        )
        parity.set(
            xlim=(low, high),
            ylim=(low, high),
            xlabel=axis_label(f"measured {quantity}", unit),
            ylabel=axis_label(f"predicted {quantity}", unit),
            title="predicted against measured (lines: equal, +-10 %, +-20 %)",
        )
        speed.set(
            xlabel=axis_label("impact speed", "m/s"),
            ylabel=axis_label(quantity, unit),
            title="against impact speed (o measured, x predicted, lines: predicted)",
        )
        for ax in (parity, speed):
            ax.grid(alpha=0.3)
            ax.title.set_fontsize(9)
        legend_outside(parity)
        legend_outside(speed)
    fig.tight_layout()
    save_figure(fig, path)
