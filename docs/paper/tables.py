"""The tables of docs/paper.md, from the study's own results (results.json, variants.json).

Run from the repository root: ``python -m docs.paper.tables p3|family|variants``.  The
figures come from the JSON files ``penetrate paper`` and ``penetrate paper --variants`` write
beside this script, so the page and the study cannot disagree; the paper's published numbers
are its Table 4 and its critical speed of #3 (docs/validation.md).
"""

from __future__ import annotations

import json
import statistics
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
NAMES = {0.4448: "#1", 0.5042: "#2", 0.5636: "#3", 0.623: "#4"}
PAPER_TABLE4 = {1100: 888, 1120: 326, 1140: 324, 1160: 323, 1180: 322, 1200: 322}  # m/s, #3 at 1 degree
PAPER_CRITICAL = (1100, 1120)  # m/s: #3 stable at 1100, unstable at 1120
PAPER_CONVERGENT = 322  # m/s: "about 322"


def _load(name: str) -> dict:
    return json.loads((HERE / name).read_text())


def _name(ratio: float) -> str:
    return NAMES.get(ratio, f"{ratio * 100:.2f} %")


def p3() -> None:
    """#3 against the paper: critical speed, characteristic convergent velocity, Table 4."""
    results = _load("results.json")
    i = results["ratios"].index(0.5636)
    critical = results["critical_velocity"][i]
    low, high = results["critical_bracket"][i]
    convergent = results["characteristic_convergent_velocity"]
    one, others = (
        convergent["attack 1"][i],
        [
            convergent["attack 5"][i],
            *convergent["attack 1, oblique 10"][i : i + 1],
            *convergent["attack 1, oblique 20"],
            *convergent["attack 1, oblique 30"],
        ],
    )
    paper_runs = {run["impact.speed"]: run for run in results["runs"]["paper speeds @ 0.5636"]}
    later = [paper_runs[v]["convergence_speed"] for v in (1120, 1140, 1160, 1180, 1200)]
    print("| quantity | paper | ours | gap |")
    print("|---|---|---|---|")
    middle = sum(PAPER_CRITICAL) / 2
    print(
        f"| critical impact velocity, 1 degree | {PAPER_CRITICAL[0]}-{PAPER_CRITICAL[1]} m/s | {critical:.0f} m/s "
        f"({low:g}-{high:g}) | {critical / middle - 1:+.0%} |"
    )
    print(
        f"| characteristic convergent velocity | about {PAPER_CONVERGENT} m/s | {one:.0f} m/s (1 degree), "
        f"{min(others):.0f}-{max(others):.0f} m/s (5 degrees; 1 degree with 10, 20 or 30 degrees oblique) | "
        f"{min([one, *others]) / PAPER_CONVERGENT - 1:+.0%} to {max([one, *others]) / PAPER_CONVERGENT - 1:+.0%} |"
    )
    run = paper_runs[1100]
    print(
        f"| convergent velocity at 1100 m/s | {PAPER_TABLE4[1100]} m/s (stable run) "
        f"| {run['convergence_speed']:.0f} m/s "
        f"({'unstable' if run['unstable'] else 'stable'}) | - |"
    )
    paper_later = [PAPER_TABLE4[v] for v in (1120, 1140, 1160, 1180, 1200)]
    gaps = [ours / paper - 1 for ours, paper in zip(later, paper_later)]
    print(
        f"| convergent velocity at 1120-1200 m/s | {', '.join(map(str, paper_later))} m/s | "
        f"{', '.join(f'{v:.0f}' for v in later)} m/s | {min(gaps):+.0%} to {max(gaps):+.0%} |"
    )


def family() -> None:
    """The family's characteristic speeds against Lc/L, and the linear fits."""
    results = _load("results.json")
    convergent = results["characteristic_convergent_velocity"]
    print("| projectile | Lc/L (%) | critical (m/s) | convergent, 1 deg | 5 deg | 1 deg + 10 deg oblique | spread |")
    print("|---|---|---|---|---|---|---|")
    for i, ratio in enumerate(results["ratios"]):
        values = [convergent[key][i] for key in ("attack 1", "attack 5", "attack 1, oblique 10")]
        spread = (max(values) - min(values)) / statistics.mean(values)
        name = NAMES.get(ratio, "")
        print(
            f"| {name} | {ratio * 100:.2f} | {results['critical_velocity'][i]:.0f} | "
            + " | ".join(f"{v:.0f}" for v in values)
            + f" | {spread:.1%} |"
        )
    fits = results["fits"]
    print()
    print(
        "Linear fits against Lc/L: "
        + "; ".join(
            f"{name} = {fit['slope']:.0f} Lc/L + {fit['intercept']:.0f} m/s (R^2 = {fit['r2']:.3f})"
            for name, fit in fits.items()
        )
        + "."
    )
    scales = results["inertia_scales"]
    print()
    print(
        "#3's critical speed with its transverse inertia scaled: "
        + ", ".join(f"{v:.0f} m/s scaled by {s:g}" for s, v in zip(scales, results["critical_with_scaled_inertia"]))
        + f" (1x: {results['critical_velocity'][results['ratios'].index(0.5636)]:.0f} m/s)."
    )


def variants() -> None:
    """Characteristic convergent velocity of each variant, with its fit against Lc/L."""
    data = _load("variants.json")
    names = [_name(r) for r in data["ratios"]]
    print("| variant | " + " | ".join(names) + " | fit vs Lc/L (R^2) |")
    print("|---|" + "---|" * (len(names) + 1))
    for variant, values in data["characteristic_convergent_velocity"].items():
        cells = ["(not buildable)" if v is None else f"{v:.0f}" for v in values]
        print(f"| {variant} | " + " | ".join(cells) + f" | {data['fits'][variant]['r2']:.3f} |")
    print()
    print(
        "Distance travelled (m) by #3 at 400 m/s (stable runs): "
        + "; ".join(
            f"{variant} {lengths[data['ratios'].index(0.5636)]:.2f}"
            for variant, lengths in data["path_length_at_400"].items()
        )
        + "."
    )


if __name__ == "__main__":
    tables = {"p3": p3, "family": family, "variants": variants}
    if len(sys.argv) != 2 or sys.argv[1] not in tables:
        sys.exit(f"usage: python -m docs.paper.tables {'|'.join(tables)}")
    tables[sys.argv[1]]()
