"""The probability that #3 turns unstable, against its impact speed, under scattered disturbances
(docs/evidence-ensembles.md).

Run from the repository root: ``python -m docs.ensembles.study`` (a few minutes on 2 cores from an
empty store; runs are kept in ``runs/ensembles-store`` and found again).  Three ensembles of
``penetrate ensemble``'s own code (:func:`cases.studies.ensemble.study.run_ensemble`), one per scale
of the initial attack angle (half-normal, 0.5, 1 and 2 degrees), each with the impact speed uniform
over 700-1400 m/s and the soil's ``B`` uniform within +-10 % of the paper's, 512 runs of a
scrambled Sobol' design, at the paper study's numerics (docs/paper.md).  Writes the figures
beside this script and prints markdown: the 50 % points against the deterministic critical
speeds, the curves, and how the band narrows with the runs per bin.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
import pandas as pd

from cases.run import RunStore
from cases.studies import Pool, Sweep, find_critical_velocity
from cases.studies.ensemble.sampling import wilson_interval
from cases.studies.ensemble.study import run_ensemble
from cases.studies.paper.plan import STUDY_NUMERICS
from cases.viz.figures import legend_outside, save_figure, subplots
from docs.measure import stamp

HERE = Path(__file__).resolve().parent

SCENE = "cases/paper_p3.toml"
SOIL = {"A": 1.718, "sigma_0": 10e6, "B": 1.227, "rho_0": 1860.0}
STUDY = [*STUDY_NUMERICS.items(), ("target.law", SOIL)]  # the paper study's numerics
SCALES = (0.5, 1.0, 2.0)  # deg, half-normal scale of the initial attack angle
RUNS = 512
EDGES = np.arange(700.0, 1400.0 + 1.0, 50.0)
STORE = RunStore("runs/ensembles-store")
POOL = Pool(progress=False)
MEDIAN_FACTOR = math.sqrt(2.0) * 0.4769362762044699  # the half-normal's median over its scale: sqrt(2) erfinv(1/2)


def samples(scale: float) -> list[str]:
    b = SOIL["B"]
    return [
        "impact.speed=uniform:700:1400",
        f"impact.attack_angle=halfnormal:{scale:g}",
        f"target.law.B=uniform:{0.9 * b:.6g}:{1.1 * b:.6g}",
    ]


def fifty_percent_point(speeds: np.ndarray, unstable: np.ndarray) -> float | None:
    """The speed where a logistic fit of P(unstable) against the speed crosses 1/2 (m/s)."""
    from scipy.optimize import minimize

    x = (speeds - 1000.0) / 100.0

    def negative_log_likelihood(theta):
        z = theta[0] + theta[1] * x
        return float(np.sum(np.logaddexp(0.0, z) - unstable * z))

    fit = minimize(
        negative_log_likelihood,
        np.array([0.0, 1.0]),
        method="Nelder-Mead",
        options={"xatol": 1e-8, "fatol": 1e-10, "maxiter": 4000},
    )
    a, b = fit.x
    return None if b <= 0 else 1000.0 - 100.0 * a / b


def critical(angle: float) -> float:
    """The deterministic critical speed of #3 at ``angle`` degrees, the paper's soil (m/s)."""
    base = Sweep.from_file(SCENE, [*STUDY, ("impact.attack_angle", round(angle, 6))])
    return find_critical_velocity(base, STORE, (400.0, 2400.0), 5.0, POOL).critical_velocity


def main() -> None:
    tables, walls = {}, {}
    for scale in SCALES:
        start = time.perf_counter()
        run_ensemble(
            SCENE,
            STUDY,
            samples(scale),
            RUNS,
            STORE,
            HERE / f"scale_{scale:g}",
            seed=1,
            design="sobol",
            by="impact.speed=700:1400:50",
            pool=POOL,
        )
        walls[scale] = time.perf_counter() - start
        tables[scale] = pd.read_csv(HERE / f"scale_{scale:g}" / "ensemble.csv")
    print(
        "| attack-angle scale (deg) | median angle (deg) | 50 % point (m/s) | critical at the median angle (m/s) "
        "| critical at 1 deg (m/s) | P(unstable), 95 % interval, all runs | wall time |"
    )
    print("|---|---|---|---|---|---|---|")
    at_one = critical(1.0)
    for scale, table in tables.items():
        speeds, unstable = table["impact.speed"].to_numpy(float), table["unstable"].to_numpy(bool)
        point = fifty_percent_point(speeds, unstable)
        median = MEDIAN_FACTOR * scale
        low, high = wilson_interval(int(unstable.sum()), len(unstable))
        print(
            f"| {scale:g} | {median:.3f} | {'-' if point is None else f'{point:.0f}'} | {critical(median):.1f} | "
            f"{at_one:.1f} | {unstable.mean():.3f} ({float(low):.3f}-{float(high):.3f}) | {walls[scale]:.0f} s |"
        )
    print()
    print(stamp())
    print()
    curve_figure(tables)
    print("![P(unstable) against the impact speed](ensembles/curves.png)")
    print()
    print(
        "How the band narrows: the 95 % half-width of P(unstable) in the 50 m/s bin nearest to 50 % (scale "
        "1 degree), from the first N runs of the Sobol' design (a prefix of one sequence):"
    )
    print()
    print("| runs in the ensemble | runs in the bin | P(unstable) in the bin | 95 % half-width |")
    print("|---|---|---|---|")
    table = tables[1.0]
    speeds, unstable = table["impact.speed"].to_numpy(float), table["unstable"].to_numpy(bool)
    shares = [unstable[(speeds >= lo) & (speeds < hi)].mean() for lo, hi in zip(EDGES[:-1], EDGES[1:])]
    k = int(np.argmin(np.abs(np.array(shares) - 0.5)))
    lo, hi = EDGES[k], EDGES[k + 1]
    for n in (32, 64, 128, 256, 512):
        inside = unstable[:n][(speeds[:n] >= lo) & (speeds[:n] < hi)]
        a, b = wilson_interval(int(inside.sum()), len(inside))
        print(
            f"| {n} | {len(inside)} ({lo:.0f}-{hi:.0f} m/s) | {inside.mean():.3f} | {(float(b) - float(a)) / 2:.3f} |"
        )
    print()
    needed = math.ceil(1.959964**2 * 0.25 / 0.05**2)
    print(
        f"A +-5 % band at P = 1/2 needs {needed} runs in the bin (the normal approximation "
        f"1.96^2 p (1 - p) / 0.05^2); over 700-1400 m/s in 50 m/s bins that is {needed * (len(EDGES) - 1)} runs, "
        "or fewer where only the bins near the transition need it."
    )


def curve_figure(tables: dict) -> None:
    figure, axes = subplots(figsize=(7.0, 4.4))
    middles = 0.5 * (EDGES[:-1] + EDGES[1:])
    for scale, table in tables.items():
        speeds, unstable = table["impact.speed"].to_numpy(float), table["unstable"].to_numpy(bool)
        counts = [
            (int(unstable[(speeds >= lo) & (speeds < hi)].sum()), int(((speeds >= lo) & (speeds < hi)).sum()))
            for lo, hi in zip(EDGES[:-1], EDGES[1:])
        ]
        p = np.array([k / n if n else np.nan for k, n in counts])
        low, high = zip(*[wilson_interval(k, n) if n else (np.nan, np.nan) for k, n in counts])
        (line,) = axes.plot(middles, p, marker="o", label=f"attack angle half-normal, scale {scale:g} deg")
        axes.fill_between(middles, np.array(low, float), np.array(high, float), color=line.get_color(), alpha=0.18)
    axes.axhline(0.5, color="grey", lw=0.8, ls=":")
    axes.set(
        xlabel="impact speed (m/s)",
        ylabel="P(unstable) (-)",
        ylim=(-0.02, 1.02),
        title=f"#3: probability of instability ({RUNS} runs each; B +-10 %; 95 % Wilson bands)",
    )
    axes.grid(alpha=0.3)
    legend_outside(axes, fontsize=8)
    figure.tight_layout()
    save_figure(figure, HERE / "curves.png")


if __name__ == "__main__":
    main()
