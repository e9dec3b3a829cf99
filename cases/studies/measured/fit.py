"""Calibration: numeric scene keys fitted to observed quantities by bounded least squares.

The model maps the parameters (any numeric scene keys, each within its bounds) to the
observations (a quantity of a run's summary, or a characteristic speed, of one or
several scenes; the parameters apply to every scene).  The fit minimises the sum of the
squared residuals ``(fitted - observed) / sigma`` with :func:`scipy.optimize.least_squares`
inside the bounds.  Every model evaluation is a set of runs made through the run store
and the worker pool (:func:`~cases.studies.engine.sweep.run_sweep`), so a fit run again makes no
new run and a killed fit continues where it stopped.

The Jacobian is a forward difference, all its columns in one batch of runs, with a step of
a fixed fraction of each parameter's range: small for the quantities of a run, which are
smooth in the parameters (the load is continuous), large for the characteristic speeds,
which a search finds only to its resolution.  The parameters' covariance is
``(J^T J)^-1`` of the weighted Jacobian at the solution when the observations give their
sigmas; without sigmas it is scaled by the residual variance (it then needs more
observations than parameters).  A parameter is not identifiable when the observations do
not move with it (a flat column) or move with a combination of the others (collinear
columns, or fewer observations than parameters, which counting shows before any run): the fit
then stops with a message and no number, rather than return a value the data do not determine.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ...run import RunStore
from ...scene import InputError, Overrides, apply_overrides, dotted_key, read_scene_data, scene_from_dict
from ..engine.pool import Pool, study_progress
from .fit_model import DIGITS, STUDY_QUANTITIES, FitModel, Observation, Parameter

# the report is written by its own module; fit.write_fit stays its public name
from .fit_report import FitResult, write_fit
from .series import RUN_QUANTITIES, finite_number

__all__ = [
    "Parameter",
    "Observation",
    "FitResult",
    "NotIdentifiable",
    "parse_parameter",
    "parse_observation",
    "fit",
    "write_fit",
    "RUN_QUANTITIES",
    "STUDY_QUANTITIES",
    "check_counts",
    "fit_bases",
    "finite_number",
    "DIGITS",
]

#: forward-difference step, as a fraction of each parameter's range
RUN_STEP = 1e-3
STUDY_STEP = 0.05
#: a Jacobian whose normalised columns have a singular value below this fraction of the largest is collinear
COLLINEAR = 1e-3
#: a column that moves no observation by more than this (in sigmas, over the whole range) is flat
FLAT = 1e-6
#: least-squares stopping tolerances (scipy's): a step below 1e-4 of the parameters (in units of their
#: ranges), or a relative fall of the cost below 1e-8, ends the fit; each iteration costs a batch of
#: runs, and a parameter known to 1e-4 of its range is known better than the data give it
XTOL, FTOL, GTOL = 1e-4, 1e-8, 1e-10


class NotIdentifiable(ValueError):
    """The observations do not determine a parameter (flat or collinear Jacobian); exit code 1."""


def _scene_value(data: dict, key: str) -> Any:
    node: Any = data
    for part in key.split("."):
        node = node.get(part) if isinstance(node, dict) else None
    return node


def parse_parameter(text: str, scenes: dict[str, dict]) -> Parameter:
    """``KEY=LO:HI`` -> :class:`Parameter`; the key must hold a number inside the bounds in every scene."""
    what = f"--param {text!r}"
    key, _, bounds = text.partition("=")
    parts = bounds.split(":")
    if not key.strip() or len(parts) != 2:
        raise InputError(f"{what}: expected KEY=LO:HI, e.g. target.law.B=0.3:3")
    key = ".".join(dotted_key(key, what))
    low, high = (finite_number(p, what) for p in parts)
    if not low < high:
        raise InputError(f"{what}: need LO < HI")
    starts = []
    for name, data in scenes.items():
        value = _scene_value(scene_from_dict(data, name).model_dump(), key)  # the scene's defaults count
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InputError(
                f"{what}: {name} holds no number at {key}, and the key must hold one"
                f" (set one first with --set {key}=VALUE;"
                " a law given by name needs its coefficients, e.g. --set 'target.law={A = 1.1,"
                " sigma_0 = 15.6e6, B = 1.2, rho_0 = 1900}')"
            )
        if not low <= value <= high:
            raise InputError(f"{what}: {name} has {key} = {value:g}: the start must lie inside {low:g}:{high:g}")
        starts.append(float(value))
    return Parameter(key, low, high, starts[0])


def parse_observation(text: str, default_scene: str) -> Observation:
    """``[SCENE:]QUANTITY=VALUE[+-SIGMA[%]]`` -> :class:`Observation` (SCENE a scene file; default the fit's own;
    ``SIGMA%`` a sigma relative to the value)."""
    what = f"--observe {text!r}"
    left, _, right = text.partition("=")
    if not right:
        raise InputError(f"{what}: expected [SCENE:]QUANTITY=VALUE[+-SIGMA], e.g. depth=5.5+-0.05")
    scene, _, quantity = left.rpartition(":")
    scene, quantity = scene.strip() or default_scene, quantity.strip()
    known = RUN_QUANTITIES + STUDY_QUANTITIES
    if quantity not in known:
        raise InputError(f"{what}: unknown quantity {quantity!r} (allowed: {', '.join(known)})")
    value_text, _, sigma_text = right.partition("+-")
    value = finite_number(value_text, what)
    sigma = None
    if sigma_text:
        relative = sigma_text.strip().endswith("%")
        sigma = finite_number(sigma_text.strip().removesuffix("%"), what)
        if not sigma > 0:
            raise InputError(f"{what}: the standard deviation must be > 0")
        if relative:
            if value == 0:
                raise InputError(f"{what}: a relative sigma of an observed 0 is 0; give it in SI units")
            sigma = sigma / 100 * abs(value)
    return Observation(scene, quantity, value, sigma)


def _sigmas(observations: Sequence[Observation]) -> np.ndarray:
    return np.array([1.0 if o.sigma is None else o.sigma for o in observations])


def check_counts(parameters: Sequence[Parameter], observations: Sequence[Observation]) -> None:
    """Refuse, before any run, a fit that counting alone shows the observations cannot determine: fewer
    observations than parameters (each observation fixes at most one combination of them).

    As many observations as parameters are enough to fit; the standard errors then need every sigma, since
    the residual variance that stands in for missing sigmas needs more observations than parameters (the fit
    says so in a note and reports none).
    """
    count, given = len(parameters), len(observations)
    if given >= count:
        return
    names = ", ".join(p.key for p in parameters)
    plural = "s" if given != 1 else ""
    raise NotIdentifiable(
        f"not identifiable: {count} parameters ({names}) from {given} observation{plural}; {count} parameters"
        f" need at least {count} observations (--observe; {count + 1} for standard errors without sigmas),"
        " or fix a parameter with --set"
    )


def _check_identifiable(
    jacobian: np.ndarray, parameters: Sequence[Parameter], observations: Sequence[Observation], where: str
) -> None:
    """Refuse a flat or collinear weighted Jacobian (in unit values) with one line naming the parameters."""
    names = [p.key for p in parameters]
    check_counts(parameters, observations)
    norms = np.linalg.norm(jacobian, axis=0)
    for name, norm in zip(names, norms):
        if not norm > FLAT:
            raise NotIdentifiable(
                f"not identifiable: no observation changes with {name} {where} (flat Jacobian);"
                " observe a quantity it moves, or fix it with --set"
            )
    if len(parameters) > 1:
        singular = np.linalg.svd(jacobian / norms, compute_uv=False)
        if singular[-1] < COLLINEAR * singular[0]:
            correlation = np.corrcoef(jacobian.T) if jacobian.shape[0] > 1 else None
            pair = ""
            if correlation is not None:
                off = np.abs(correlation - np.eye(len(names)))
                i, j = np.unravel_index(np.nanargmax(off), off.shape)
                pair = f" ({names[i]} and {names[j]} move the observations together)"
            raise NotIdentifiable(
                f"not identifiable: the observations fix only a combination of "
                f"{', '.join(names)}{pair}, collinear Jacobian {where} (singular values "
                f"{singular[0]:.3g} and {singular[-1]:.3g}); add an observation that tells them"
                " apart, or fix one with --set"
            )


def fit(
    scene: str | os.PathLike,
    overrides: Overrides | None,
    parameters: Sequence[str],
    observations: Sequence[str],
    store: RunStore,
    pool: Pool | None = None,
    *,
    resolution: float = 5.0,
    step: float | None = None,
    max_evaluations: int = 30,
    progress: Callable[[str], None] | None = None,
) -> FitResult:
    """Fit ``parameters`` (``KEY=LO:HI`` texts) to ``observations`` (``[SCENE:]QUANTITY=VALUE[+-SIGMA]`` texts).

    Parameters
    ----------
    scene, overrides
        The fit's scene file and its ``--set`` overrides; the overrides apply to every scene an
        observation names (the report says so).
    parameters, observations : sequence of str
        The command line's ``--param`` and ``--observe`` texts.
    store : RunStore
        Where runs are found and kept.
    pool : Pool, optional
        Where the runs go.
    resolution : float
        Resolution of a critical-speed search (m/s).
    step : float, optional
        Forward-difference step as a fraction of each range (default :data:`RUN_STEP`, or
        :data:`STUDY_STEP` when a characteristic speed is observed).
    max_evaluations : int
        Model evaluations (points) at most.

    Raises
    ------
    InputError
        Bad parameters or observations (exit code 2).
    NotIdentifiable
        A parameter the observations do not determine (exit code 1).
    """
    scene = str(scene)
    if not parameters:
        raise InputError(
            "--param: give at least one parameter, KEY=LO:HI (for predictions against measurements without a"
            " fit, use penetrate validate with a series file)"
        )
    if not observations:
        raise InputError("--observe: give at least one observation, [SCENE:]QUANTITY=VALUE[+-SIGMA]")
    observed = [parse_observation(text, scene) for text in observations]
    bases: dict[str, dict] = {}
    for name in dict.fromkeys([scene, *(o.scene for o in observed)]):
        if not Path(name).is_file():
            raise InputError(f"--observe: scene file {name!r} not found (give an existing scene file before the colon)")
        data = apply_overrides(read_scene_data(name), overrides, name)
        scene_from_dict(data, name)  # a bad scene or override fails here, before any run
        bases[name] = data
    notes = _observation_notes(observed, bases, overrides)
    return fit_bases(
        bases,
        parameters,
        observed,
        store,
        pool,
        resolution=resolution,
        step=step,
        max_evaluations=max_evaluations,
        notes=notes,
    )


def _observation_notes(
    observed: Sequence[Observation], bases: dict[str, dict], overrides: Overrides | None
) -> list[str]:
    """What the report must say of the observations: ``--set`` applied to every scene, and observations of one
    quantity of one run (the same scene after ``--set``), which count as repeats of one shot."""
    notes = []
    settings = list(overrides.items() if isinstance(overrides, Mapping) else overrides or [])
    scenes = list(dict.fromkeys(o.scene for o in observed))
    if settings and len(observed) > 1:
        shown = ", ".join(f"{key}={value}" for key, value in settings)
        notes.append(
            f"--set {shown} applies to every observation's scene ({len(scenes)} scene"
            f"{'s' if len(scenes) != 1 else ''}); to give each shot its own values, use a series file (fit --series)"
        )
    seen: dict[tuple[str, str], int] = {}
    for index, o in enumerate(observed, start=1):
        first = seen.setdefault((o.scene, o.quantity), index)
        if first != index:
            notes.append(
                f"observations {first} and {index} are the same quantity of the same run ({Path(o.scene).name}):"
                " the fit treats them as repeated measurements of one shot"
            )
    return notes


def fit_bases(
    bases: dict[str, dict],
    parameters: Sequence[str],
    observed: Sequence[Observation],
    store: RunStore,
    pool: Pool | None = None,
    *,
    resolution: float = 5.0,
    step: float | None = None,
    max_evaluations: int = 30,
    notes: Sequence[str] = (),
    labels: dict[str, str] | None = None,
) -> FitResult:
    """:func:`fit` of observations of scenes given as nested dictionaries (``bases``, by the name each
    :attr:`Observation.scene` gives); ``labels`` names them in the report (default: the names)."""
    fitted = [parse_parameter(text, bases) for text in parameters]
    if len({p.key for p in fitted}) != len(fitted):
        raise InputError("--param: give each key once")
    check_counts(fitted, observed)  # after the input's own checks (exit code 2), before any run
    if step is None:
        step = STUDY_STEP if any(o.quantity in STUDY_QUANTITIES for o in observed) else RUN_STEP
    model = FitModel(bases, fitted, observed, store, pool, resolution)
    y = np.array([o.value for o in observed])
    sigma = _sigmas(observed)

    def residuals(unit: np.ndarray) -> np.ndarray:
        return (model([unit])[0] - y) / sigma

    def jacobian(unit: np.ndarray) -> np.ndarray:
        # forward differences, stepping inwards at the upper bound; all columns in one batch of runs
        steps = np.where(unit + step <= 1.0, step, -step)
        points = [unit] + [unit + np.eye(len(unit))[k] * steps[k] for k in range(len(unit))]
        values = model(points)
        return np.column_stack([(values[k + 1] - values[0]) / steps[k] for k in range(len(unit))]) / sigma[:, None]

    from scipy.optimize import least_squares

    start = np.array([(p.start - p.low) / (p.high - p.low) for p in fitted])
    with study_progress("fit"):  # one progress bar for every batch of runs of the fit
        _check_identifiable(jacobian(start), fitted, observed, "at the start")
        solution = least_squares(
            residuals,
            start,
            jac=jacobian,
            bounds=(0.0, 1.0),
            method="trf",
            x_scale=1.0,
            xtol=XTOL,
            ftol=FTOL,
            gtol=GTOL,
            max_nfev=max_evaluations,
        )
        final_jacobian = jacobian(solution.x)
        _check_identifiable(final_jacobian, fitted, observed, "at the solution")
        fitted_values = model([solution.x])[0]
    values = {p.key: p.value(float(u)) for p, u in zip(fitted, solution.x)}
    widths = np.array([p.high - p.low for p in fitted])
    jac_physical = final_jacobian / widths  # d(residual)/d(parameter)
    notes = list(notes)
    converged = bool(solution.status > 0)
    if not converged:
        notes.insert(
            0,
            f"NOT CONVERGED: the least-squares fit stopped after {solution.nfev} evaluations of the model"
            f" ({solution.message}); the values below are where it stopped, not a fit: raise --max-evaluations",
        )
    covariance = None
    try:
        covariance = np.linalg.inv(jac_physical.T @ jac_physical)
    except np.linalg.LinAlgError:
        notes.append("the Jacobian at the solution is singular: no standard errors")
    if covariance is not None and any(o.sigma is None for o in observed):
        dof = len(observed) - len(fitted)
        if dof > 0:
            covariance = covariance * float(solution.fun @ solution.fun) / dof
            notes.append(
                "no sigmas given: standard errors scaled by the residual variance"
                f" ({dof} degree{'s' if dof != 1 else ''} of freedom)"
            )
        else:
            covariance = None
            notes.append("no sigmas given and no more observations than parameters: no standard errors")
    at_bound = [p.key for p, u in zip(fitted, solution.x) if u <= 1e-9 or u >= 1 - 1e-9]
    if at_bound:
        notes.append(f"at a bound of its range: {', '.join(at_bound)} (widen the range, or the data push it there)")
    errors: dict[str, float | None] = {p.key: None for p in fitted}
    correlation = None
    if covariance is not None:
        se = np.sqrt(np.clip(np.diag(covariance), 0, None))
        errors = {p.key: float(s) for p, s in zip(fitted, se)}
        correlation = (covariance / np.outer(se, se)).round(6).tolist() if np.all(se > 0) else None
    speeds = {name: scene_from_dict(data, name).impact.speed for name, data in bases.items()}
    rows = [
        {
            "scene": (labels or {}).get(o.scene, o.scene),
            "quantity": o.quantity,
            "impact_speed": speeds[o.scene],
            "observed": o.value,
            "sigma": o.sigma,
            "fitted": float(f),
            "residual": float(f - o.value),
        }
        for o, f in zip(observed, fitted_values)
    ]
    return FitResult(
        values,
        errors,
        correlation,
        rows,
        runs=len(model.keys),
        new_runs=model.new_runs,
        evaluations=len(model.cache),
        cost=float(solution.cost),
        message=solution.message,
        notes=notes,
        converged=converged,
        starts={p.key: p.start for p in fitted},
    )
