"""The report of a fit: its table (markdown), its record (JSON) and its figure, observed against fitted."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..engine.report import Report, markdown_table, number_cell, write_report


@dataclass
class FitResult:
    """The fitted parameters, their standard errors and correlation, each observation's fit, the runs used."""

    parameters: dict[str, float]
    standard_errors: dict[str, float | None]
    correlation: list[list[float]] | None
    observations: list[dict[str, Any]]
    runs: int
    new_runs: int
    evaluations: int
    cost: float
    message: str = ""
    notes: list[str] = field(default_factory=list)
    converged: bool = True
    starts: dict[str, float] = field(default_factory=dict)
    #: the held-out shots of a series predicted at the fitted values (and at the starts); not part of the fit
    predictions: dict[str, Any] | None = None
    #: k-fold cross-validation of the training shots
    cross_validation: dict[str, Any] | None = None

    def record(self) -> dict:
        """The JSON record: parameters, standard_errors, observations, runs (and the rest)."""
        return {
            "converged": self.converged,
            "parameters": self.parameters,
            "standard_errors": self.standard_errors,
            "correlation": self.correlation,
            "observations": self.observations,
            "runs": self.runs,
            "new_runs": self.new_runs,
            "evaluations": self.evaluations,
            "cost": self.cost,
            "message": self.message,
            "notes": self.notes,
            "starts": self.starts,
            "predictions": self.predictions,
            "cross_validation": self.cross_validation,
        }


def _prediction_lines(result: FitResult) -> list[str]:
    """The held-out predictions and the cross-validation, each apart from the fit and labelled so."""
    from .validate import summary_table

    lines: list[str] = []
    if result.predictions is not None:
        p = result.predictions
        lines += [
            "",
            f"## Predictions of the {len(p['held_out'])} held-out shots (not fitted)",
            "",
            "Predicted at the fitted values, and at the scenes' own values (before the fit), against the"
            " measurements the fit did not see:",
            "",
        ]
        lines += markdown_table(
            [
                "shot",
                "quantity",
                "impact speed (m/s)",
                "measured",
                "predicted",
                "error (%)",
                "before the fit",
                "error (%)",
            ],
            [
                [
                    row["label"],
                    row["quantity"],
                    number_cell(row["impact_speed"], "g"),
                    number_cell(row["measured"], ".4g"),
                    number_cell(row["predicted"], ".4g"),
                    number_cell(row["error_percent"], "+.1f"),
                    number_cell(start["predicted"], ".4g"),
                    number_cell(start["error_percent"], "+.1f"),
                ]
                for row, start in zip(p["rows"], p["start_rows"])
            ],
        )
        lines += ["", "Held out, at the fitted values:", "", *summary_table(p["summary"], {})]
        lines += ["", "Held out, at the scenes' own values:", "", *summary_table(p["start_summary"], {})]
    if result.cross_validation is not None:
        cv = result.cross_validation
        lines += [
            "",
            f"## {len(cv['folds'])}-fold cross-validation of the training shots (predictions, not fitted)",
            "",
        ]
        lines += markdown_table(
            ["fold", "left out", *(f"`{k}`" for k in result.parameters)],
            [
                [
                    fold["fold"],
                    ", ".join(fold["left_out"]),
                    *(
                        f"{number_cell(value, '.6g')} +- {number_cell(fold['standard_errors'][key], '.3g')}"
                        for key, value in fold["parameters"].items()
                    ),
                ]
                for fold in cv["folds"]
            ],
        )
        lines += ["", "Each fold predicted by the fit to the others:", "", *summary_table(cv["summary"], {})]
    return lines


def write_fit(result: FitResult, out: Path, scene: str) -> None:
    """``fit.json``, ``fit.md`` and ``fit.png`` (observed against fitted) in ``out``, each written atomically."""
    figures = {"fit.png": lambda path: _figure(result, path)}
    write_report(out, Report("fit", _markdown(result, scene), record=result.record(), figures=figures))


def _markdown(result: FitResult, scene: str) -> str:
    lines = [f"# Fit of {scene}", ""]
    if not result.converged:
        lines += [f"**{result.notes[0]}**", ""]
    lines += markdown_table(
        ["parameter", "value", "standard error", "start"],
        [
            [
                f"`{key}`",
                number_cell(value, ".6g"),
                number_cell(result.standard_errors[key], ".3g"),
                number_cell(result.starts.get(key), ".6g"),
            ]
            for key, value in result.parameters.items()
        ],
    )
    if result.correlation is not None and len(result.parameters) > 1:
        keys = list(result.parameters)
        lines += ["", "Correlation of the parameters:", ""]
        lines += markdown_table(
            ["", *(f"`{k}`" for k in keys)],
            [[f"`{k}`", *(number_cell(c, "+.3f") for c in row)] for k, row in zip(keys, result.correlation)],
        )
    lines += ["", "The fit's own residuals (the observations it was fitted to):", ""]
    lines += markdown_table(
        ["scene", "quantity", "impact speed (m/s)", "observed", "sigma", "fitted", "residual"],
        [
            [
                row["scene"],
                row["quantity"],
                number_cell(row["impact_speed"], "g"),
                number_cell(row["observed"], ".6g"),
                number_cell(row["sigma"], ".4g"),
                number_cell(row["fitted"], ".6g"),
                number_cell(row["residual"], "+.4g"),
            ]
            for row in result.observations
        ],
    )
    lines += [
        "",
        f"Runs: {result.runs} ({result.new_runs} made by this fit, the rest found in the run store); "
        f"{result.evaluations} points of the model evaluated; least squares: {result.message}",
    ]
    if result.notes:
        lines += ["", *[f"* {note}" for note in result.notes]]
    lines += _prediction_lines(result)
    lines += ["", "![observed against fitted](fit.png)", ""]
    return "\n".join(lines)


def _figure(result: FitResult, path: Path) -> None:
    """Each observation against its fitted value, with its sigma."""
    from ...viz.figures import axis_label, quantity_unit, save_figure, subplots

    figure, axes = subplots(figsize=(5.5, 4.5))
    observed = np.array([row["observed"] for row in result.observations])
    fitted = np.array([row["fitted"] for row in result.observations])
    sigmas = np.array([np.nan if row["sigma"] is None else row["sigma"] for row in result.observations])
    axes.errorbar(observed, fitted, xerr=np.nan_to_num(sigmas), fmt="o", color="tab:blue", capsize=3)
    low, high = float(min(observed.min(), fitted.min())), float(max(observed.max(), fitted.max()))
    pad = 0.05 * (high - low or abs(high) or 1.0)
    axes.plot([low - pad, high + pad], [low - pad, high + pad], color="grey", lw=1, ls="--")
    for row, x, y in zip(result.observations, observed, fitted):
        axes.annotate(
            f"{Path(row['scene']).stem}: {axis_label(row['quantity'], quantity_unit(row['quantity']))}",
            (x, y),
            fontsize=7,
            xytext=(4, 4),
            textcoords="offset points",
        )
    # one unit on the axes when the quantities share it; else each point's label carries its own
    units = {quantity_unit(row["quantity"]) for row in result.observations}
    shared = units.pop() if len(units) == 1 else "each point's unit"
    axes.set_xlabel(axis_label("observed", shared))
    axes.set_ylabel(axis_label("fitted", shared))
    axes.set_title("observed against fitted (bars: sigma)", fontsize=10)
    figure.tight_layout()
    save_figure(figure, path)
