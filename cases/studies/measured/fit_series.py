"""Fits to a test series: the shots a hold-out leaves in are fitted, the held-out shots predicted, and a k-fold
cross-validation says how well such a fit predicts shots it has not seen (``penetrate fit --series``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...run import RunStore
from ...scene import InputError, Overrides
from ..engine.pool import Pool
from ..engine.sweep import run_sweep
from .fit import NotIdentifiable, fit_bases
from .fit_model import Observation
from .fit_report import FitResult
from .series import Series, combined, finite_number
from .validate import error_summary, prediction_rows

__all__ = ["HOLDOUT_KINDS", "Holdout", "parse_holdout", "split_series", "fit_series"]


#: how ``--holdout`` names the shots kept out of the fit
HOLDOUT_KINDS = ("label", "group", "fraction")


@dataclass(frozen=True)
class Holdout:
    """Shots kept out of a fit: by ``label`` or ``group`` (``names``), or a random ``fraction`` of them."""

    kind: str
    names: tuple[str, ...] = ()
    fraction: float = 0.0


def parse_holdout(text: str) -> Holdout:
    """``label=A,B``, ``group=G`` or ``fraction=0.3`` -> :class:`Holdout`."""
    what = f"--holdout {text!r}"
    kind, _, raw = text.partition("=")
    kind = kind.strip()
    if kind not in HOLDOUT_KINDS or not raw.strip():
        raise InputError(f"{what}: expected label=A,B,..., group=G,... or fraction=F (0 < F < 1)")
    if kind == "fraction":
        fraction = finite_number(raw, what)
        if not 0 < fraction < 1:
            raise InputError(f"{what}: the fraction must lie strictly between 0 and 1")
        return Holdout(kind, fraction=fraction)
    names = tuple(name.strip() for name in raw.split(",") if name.strip())
    return Holdout(kind, names)


def split_series(series: Series, holdout: Holdout | None, seed: int = 0) -> tuple[list[str], list[str]]:
    """``(training, held out)`` labels of ``series`` under ``holdout``, each in the series' order; refused in
    one line when a name matches no shot or nothing is left to fit."""
    if holdout is None:
        return series.labels, []
    if holdout.kind == "fraction":
        count = max(1, round(holdout.fraction * len(series.shots)))
        chosen = set(np.random.default_rng(seed).permutation(len(series.shots))[:count].tolist())
        held = [shot.label for i, shot in enumerate(series.shots) if i in chosen]
    else:
        known = series.labels if holdout.kind == "label" else series.groups
        unknown = [name for name in holdout.names if name not in known]
        if unknown:
            raise InputError(
                f"--holdout {holdout.kind}={','.join(holdout.names)}: no shot has the {holdout.kind} {unknown[0]!r}"
                f" (the series' {holdout.kind}s: {', '.join(known)})"
            )
        attribute = "label" if holdout.kind == "label" else "group"
        held = [shot.label for shot in series.shots if getattr(shot, attribute) in holdout.names]
    training = [label for label in series.labels if label not in held]
    if not training:
        raise InputError(f"--holdout: every shot of {Path(series.source).name} is held out; leave some to fit")
    return training, held


def fit_series(
    series: Series,
    overrides: Overrides | None,
    parameters: Sequence[str],
    store: RunStore,
    pool: Pool | None = None,
    *,
    holdout: Holdout | None = None,
    folds: int = 0,
    seed: int = 0,
    step: float | None = None,
    max_evaluations: int = 30,
) -> FitResult:
    """Fit ``parameters`` to the measured shots of ``series`` that ``holdout`` leaves in (the training shots).

    The held-out shots are then predicted at the fitted values, and before the fit at each shot's own values (its
    scene and columns, nothing of the fit set: ``penetrate validate``'s run of it), and reported apart from the
    fit (``FitResult.predictions``).  ``folds`` >= 2 adds a k-fold cross-validation of the training shots
    (``FitResult.cross_validation``): each fold fitted on the others and predicted, which says how well the
    calibration predicts shots it has not seen.  ``seed`` draws a held-out fraction and the folds.
    """
    if not parameters:
        raise InputError("--param: give at least one parameter, KEY=LO:HI (without one, use penetrate validate)")
    settings = list(overrides.items() if isinstance(overrides, Mapping) else overrides or [])
    for text in parameters:
        key = text.partition("=")[0].strip()
        clash = [c for c in series.columns if c == key or c.startswith(f"{key}.") or key.startswith(f"{c}.")]
        if clash:
            raise InputError(
                f"--param {text!r}: the series sets {clash[0]} per shot (a column), which the fit would override;"
                " drop the column or fit another key"
            )
    training, held = split_series(series, holdout, seed)
    if folds and not 2 <= folds <= len(training):
        raise InputError(f"--folds {folds}: must lie in 2..{len(training)} (the training shots)")
    result = _fit_shots(series.subset(training), settings, parameters, store, pool, step, max_evaluations)
    if held:
        kept_out = series.subset(held)
        result.predictions = {
            "held_out": held,
            **_predict(kept_out, settings, result.parameters, store, pool),
        }
    if folds:
        result.cross_validation = _cross_validate(
            series.subset(training), settings, parameters, store, pool, folds, seed, step, max_evaluations
        )
    return result


def _observations(series: Series) -> list[Observation]:
    return [Observation(shot.label, m.quantity, m.value, m.sigma) for shot in series.shots for m in shot.measurements]


def _fit_shots(
    series: Series,
    settings: list[tuple[str, Any]],
    parameters: Sequence[str],
    store: RunStore,
    pool: Pool | None,
    step: float | None,
    max_evaluations: int,
) -> FitResult:
    notes = []
    if settings:
        shown = ", ".join(f"{key}={value}" for key, value in settings)
        notes.append(f"--set {shown} applies to every shot (a column of the series beats it for its own shot)")
    return fit_bases(
        series.bases(settings),
        parameters,
        _observations(series),
        store,
        pool,
        step=step,
        max_evaluations=max_evaluations,
        notes=notes,
    )


def _predict(
    series: Series,
    settings: list[tuple[str, Any]],
    fitted: dict[str, float],
    store: RunStore,
    pool: Pool | None,
) -> dict[str, Any]:
    """The shots of ``series`` predicted at the fitted values and before the fit: their rows and error summaries
    per quantity.

    Before the fit, each shot is its own scene with nothing of the fit set (the run ``penetrate validate`` makes
    of it): a fitted key keeps the shot's own value, one its scene or a column gives or a formula fills in (such
    as concrete's ``S`` from its compressive strength), which may differ from shot to shot.  The fit's start
    (``FitResult.starts``) is the first training shot's value alone."""
    result = run_sweep(combined(series, series.parts(settings, [fitted, {}])), store, pool)
    rows = prediction_rows(series, result)
    start_rows = prediction_rows(series, result, offset=len(series.shots))
    return {
        "rows": rows,
        "summary": _per_quantity(rows),
        "start_rows": start_rows,
        "start_summary": _per_quantity(start_rows),
    }


def _per_quantity(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    quantities = dict.fromkeys(row["quantity"] for row in rows)
    return {q: error_summary([r for r in rows if r["quantity"] == q]) for q in quantities}


def _cross_validate(
    series: Series,
    settings: list[tuple[str, Any]],
    parameters: Sequence[str],
    store: RunStore,
    pool: Pool | None,
    folds: int,
    seed: int,
    step: float | None,
    max_evaluations: int,
) -> dict[str, Any]:
    """k-fold cross-validation: each fold of the shots predicted by a fit to the others."""
    order = np.random.default_rng(seed).permutation(len(series.shots))
    assignment = {series.shots[int(i)].label: k % folds for k, i in enumerate(order)}
    entries, rows = [], []
    for fold in range(folds):
        left_out = [label for label in series.labels if assignment[label] == fold]
        kept = [label for label in series.labels if assignment[label] != fold]
        try:
            result = _fit_shots(series.subset(kept), settings, parameters, store, pool, step, max_evaluations)
        except NotIdentifiable as exc:
            raise NotIdentifiable(f"fold {fold + 1} of {folds} (left out: {', '.join(left_out)}): {exc}") from None
        predicted = _predict(series.subset(left_out), settings, result.parameters, store, pool)
        fold_rows = [{"fold": fold + 1, **row} for row in predicted["rows"]]
        rows += fold_rows
        entries.append(
            {
                "fold": fold + 1,
                "left_out": left_out,
                "parameters": result.parameters,
                "standard_errors": result.standard_errors,
                "converged": result.converged,
            }
        )
    return {"folds": entries, "rows": rows, "summary": _per_quantity(rows), "seed": seed}
