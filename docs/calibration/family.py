"""The family's unknown interior calibrated on #3 alone, and the other members predicted (docs/evidence-calibration.md).

Run from the repository root: ``python -m docs.calibration.family`` (several minutes from an empty
store; runs are kept in ``runs/calibration-family-store``); it writes ``family.json`` beside itself, and
``python -m docs.calibration.family --from-json`` prints the same tables from it (docs/paper.md).  The one
parameter is a common factor on the
transverse moment of inertia, ``projectile.transverse_inertia_scale``, fitted by ``penetrate fit``'s
own code to #3's two published numbers: its critical impact velocity (stable at 1100, unstable at
1120 m/s: 1110 +- 10 m/s) and its characteristic convergent velocity (about 322 m/s; +- 10 m/s).
Every run uses the paper study's numerics (docs/paper.md), so the uncalibrated speeds to compare
are those of docs/paper/results.json.  Prints markdown: the fit, then each member's predicted
critical and convergent speeds beside the uncalibrated ones.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from cases.run import RunStore
from cases.studies import Pool, Sweep, find_critical_velocity, measure_convergent_velocity
from cases.studies.measured.fit import fit
from cases.studies.paper.plan import STUDY_NUMERICS

STUDY = list(STUDY_NUMERICS.items())  # the paper study's numerics
KEY = "projectile.transverse_inertia_scale"
OBSERVED = ["critical_velocity=1110+-10", "characteristic_convergent_velocity=322+-10"]
STORE = RunStore("runs/calibration-family-store")
POOL = Pool(progress=False)
RECORD = Path(__file__).with_name("family.json")
NAMES = {0.4448: "#1", 0.5042: "#2", 0.5636: "#3", 0.623: "#4"}


def speeds(ratio: float, scale: float) -> tuple[float | None, float | None]:
    """Critical and characteristic convergent velocity of the family member at ``ratio`` (m/s)."""
    overrides = [*STUDY, ("projectile.centre_of_mass_ratio", ratio), (KEY, scale)]
    base = Sweep.from_file("cases/paper_p3.toml", overrides)
    critical = find_critical_velocity(base, STORE, (200.0, 2400.0), 5.0, POOL).critical_velocity
    convergent = measure_convergent_velocity(base, STORE, pool=POOL).characteristic_convergent_velocity
    return critical, convergent


def calibrate() -> dict:
    """Fit the factor on #3, predict every member; the record ``family.json`` keeps."""
    result = fit("cases/paper_p3.toml", [*STUDY, (KEY, 1.5)], [f"{KEY}=1:3"], OBSERVED, STORE, POOL)
    scale = result.parameters[KEY]
    scaled = round(scale, 2)  # the shipped scenes carry the factor to two decimals
    uncalibrated = json.loads(Path("docs/paper/results.json").read_text())
    members = []
    for i, ratio in enumerate(uncalibrated["ratios"]):
        critical, convergent = speeds(ratio, scaled)
        members.append(
            {
                "ratio": ratio,
                "critical_uncalibrated": uncalibrated["critical_velocity"][i],
                "critical_predicted": critical,
                "convergent_uncalibrated": uncalibrated["characteristic_convergent_velocity"]["attack 1"][i],
                "convergent_predicted": convergent,
            }
        )
    return {
        "key": KEY,
        "value": scale,
        "standard_error": result.standard_errors[KEY],
        "shipped": scaled,
        "runs": result.runs,
        "observations": result.observations,
        "members": members,
    }


def table(record: dict) -> None:
    """The calibration and the predictions, as markdown."""
    print(
        f"Fitted on #3 alone: `{record['key']}` = {record['value']:.3f} +- {record['standard_error']:.3f} "
        f"({record['runs']} runs)."
    )
    print()
    print("| #3 | published | calibrated model | residual |")
    print("|---|---|---|---|")
    for row in record["observations"]:
        print(
            f"| {row['quantity'].replace('_', ' ')} | {row['observed']:g} +- {row['sigma']:g} m/s | "
            f"{row['fitted']:.1f} m/s | {row['residual']:+.1f} m/s |"
        )
    print()
    print(
        f"Each member with the factor {record['shipped']:g} (predictions: only #3 entered the fit), beside the "
        "uncalibrated model (factor 1, docs/paper/results.json):"
    )
    print()
    print(
        "| projectile | Lc/L (%) | critical, uncalibrated (m/s) | critical, predicted (m/s) | "
        "convergent, uncalibrated (m/s) | convergent, predicted (m/s) |"
    )
    print("|---|---|---|---|---|---|")
    for m in record["members"]:
        shown = [("-" if v is None else f"{v:.1f}") for v in (m["critical_predicted"], m["convergent_predicted"])]
        print(
            f"| {NAMES.get(m['ratio'], '')} | {m['ratio'] * 100:.2f} | {m['critical_uncalibrated']:.1f} | {shown[0]} | "
            f"{m['convergent_uncalibrated']:.1f} | {shown[1]} |"
        )


def main() -> None:
    if sys.argv[1:] == ["--from-json"]:
        record = json.loads(RECORD.read_text())
    else:
        record = calibrate()
        RECORD.write_text(json.dumps(record, indent=1) + "\n")
    table(record)


if __name__ == "__main__":
    main()
