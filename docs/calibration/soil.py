"""The soil fitted to Forrestal and Luk's five measured shots (docs/evidence-calibration.md).

Run from the repository root: ``python -m docs.calibration.soil`` (about a minute from an empty store; runs are kept in
``runs/calibration-soil-store`` and found again).  Every fit is ``penetrate fit``'s own
(:func:`cases.studies.measured.fit.fit`), at the shipped numerics of the five scenes; the observations are
the measured distances travelled (path length of the centre of mass), without a stated
uncertainty, so the standard errors come from the residual scatter.  Prints markdown: the fits
(A and B together; B alone; A alone; a Coulomb friction coefficient), the leave-one-out table
of the B-alone fit, and the B that the two oblique shots alone would need.
"""

from __future__ import annotations

import math

import numpy as np

from cases import load_scene, run_scene, summarise
from cases.run import RunStore
from cases.studies import Pool
from cases.studies.measured.fit import NotIdentifiable, fit

MEASURED = {2: 4.98, 3: 5.18, 4: 5.18, 5: 5.02, 6: 4.82}  # m, distance travelled (path length)
PAPER = {2: 5.05, 3: 5.00, 4: 5.05, 5: 5.01, 6: 5.00}  # m, the paper's predictions
SOIL = {"A": 1.718, "sigma_0": 10e6, "B": 1.227, "rho_0": 1860.0}  # the paper's constants
STORE = RunStore("runs/calibration-soil-store")
POOL = Pool(progress=False)


def scene(test: int) -> str:
    return f"cases/forrestal_luk_test{test}.toml"


def observations(tests) -> list[str]:
    return [f"{scene(t)}:path_length={MEASURED[t]}" for t in tests]


def run_fit(parameters: list[str], tests, overrides=()) -> object:
    return fit(scene(2), [("target.law", SOIL), *overrides], parameters, observations(tests), STORE, POOL)


def fitted_cells(result, mark: str = "") -> str:
    return ", ".join(f"{mark}{row['fitted']:.3f}" for row in result.observations)


def residual_cells(result, mark: str = "") -> str:
    return ", ".join(f"{mark}{row['residual']:+.3f}" for row in result.observations)


def main() -> None:
    tests = list(MEASURED)
    print(
        "| fit | parameter(s) | value +- standard error | fitted path lengths (m), tests 2-6 | residuals (m) "
        "| RMS (m) | runs |"
    )
    print("|---|---|---|---|---|---|---|")
    try:
        # the two are nearly collinear on these shots: where along the valley the fit stops moves with changes
        # far below the runs' accuracy (another machine's round-off), so its figures are marked ~ (not compared
        # by docs/regenerate.py --check); docs/evidence-calibration.md says so
        both = run_fit(["target.law.A=0.5:4", "target.law.B=0.3:3"], tests)
        values = "; ".join(
            f"{k.rsplit('.', 1)[1]} = ~{v:.3f} +- ~{both.standard_errors[k]:.3f}" for k, v in both.parameters.items()
        )
        print(
            f"| A and B | `A`, `B` | {values} (correlation ~{both.correlation[0][1]:+.3f}) | "
            f"{fitted_cells(both, '~')} | {residual_cells(both, '~')} | "
            f"~{_rms(both):.3f} | ~{both.runs} |"
        )
    except NotIdentifiable as error:
        print(f"| A and B | `A`, `B` | not identifiable: {error} | - | - | - | - |")
    for name, parameters, overrides in (
        ("B alone (A = 1.718)", ["target.law.B=0.3:3"], ()),
        ("A alone (B = 1.227)", ["target.law.A=0.5:4"], ()),
        (
            "friction alone (A, B the paper's)",
            ["effects.friction.coefficient=0:0.5"],
            [("effects.friction", {"model": "coulomb", "coefficient": 0.05})],
        ),
    ):
        # the runs a fit takes hang on its stopping test, which round-off tips: another machine's took 35 runs
        # where this one took 30 for the same value to every printed digit, so the count is marked ~ (not compared)
        result = run_fit(parameters, tests, overrides)
        key = next(iter(result.parameters))
        error = result.standard_errors[key]
        value = result.parameters[key]
        value = 0.0 if abs(value) < 1e-9 else value  # a bound reached to round-off
        shown = f"{value:.4g} +- {error:.2g}" if error is not None else f"{value:.4g}"
        if result.notes and any("bound" in n for n in result.notes):
            shown += " (at its bound)"
        print(
            f"| {name} | `{key}` | {shown} | {fitted_cells(result)} | "
            f"{residual_cells(result)} | {_rms(result):.3f} | ~{result.runs} |"
        )
    print()
    print("Leave one out (B alone, A = 1.718): fitted on the other four, the left-out shot predicted:")
    print()
    print("| left out | B from the other four | predicted (m) | measured (m) | error (m) |")
    print("|---|---|---|---|---|")
    errors = []
    for left in tests:
        result = run_fit(["target.law.B=0.3:3"], [t for t in tests if t != left])
        b = result.parameters["target.law.B"]
        value = summarise(run_scene(load_scene(scene(left), [("target.law", {**SOIL, "B": b})]))).path_length
        errors.append(value - MEASURED[left])
        print(f"| test {left} | {b:.3f} | {value:.3f} | {MEASURED[left]} | {value - MEASURED[left]:+.3f} |")
    print()
    print(f"Leave-one-out RMS error: {math.sqrt(np.mean(np.square(errors))):.3f} m.")
    print()
    oblique = run_fit(["target.law.B=0.05:3"], [3, 4])
    normal = run_fit(["target.law.B=0.3:3"], [2, 5, 6])
    print(
        f"The oblique shots alone (tests 3 and 4) need B = {oblique.parameters['target.law.B']:.3f} "
        f"(residuals {residual_cells(oblique)} m); the three normal-incidence shots alone give "
        f"B = {normal.parameters['target.law.B']:.3f} (residuals {residual_cells(normal)} m)."
    )


def _rms(result) -> float:
    return math.sqrt(np.mean([row["residual"] ** 2 for row in result.observations]))


if __name__ == "__main__":
    main()
