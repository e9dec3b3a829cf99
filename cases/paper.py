"""Reproduce the paper's instability study: ``penetrate paper``.

Runs (through the resumable run store) and writes under ``out``:

* ``results.md``: every table, with the paper's published numbers beside ours;
* ``*.png``: the figures (trajectories, axis and attack angle against speed,
  speed, moment and resistance-centre histories, characteristic speeds
  against ``Lc/L`` with linear fits);
* ``results.json``: the numbers behind them.

All runs use :data:`STUDY_NUMERICS` (10 mm -> 20 mm mesh, 1e-5 s -> 2e-5 s
step); ``results.md`` includes the check that this changes the results of
projectile #3 near its critical speed by far less than the effects studied.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from . import scene_path
from .results import atomic_write_text, attack_angle_peak, save_figure
from .studies import (CONVERGENCE_THRESHOLD, convergence_speed, find_critical_velocities, is_unstable)
from .sweep import RunStore, Sweep, Variation, grid, run_sweep

__all__ = ["reproduce", "PAPER_RATIOS", "STUDY_NUMERICS"]

STUDY_NUMERICS = ["numerics.mesh_size=0.02", "numerics.time_step=2e-5"]
FINE_NUMERICS = ["numerics.mesh_size=0.01", "numerics.time_step=1e-5"]
PAPER_RATIOS = (0.4448, 0.4745, 0.5042, 0.5339, 0.5636, 0.5933, 0.6230)
NUMBERED = {0.4448: "#1", 0.5042: "#2", 0.5636: "#3", 0.6230: "#4"}
SCAN = list(range(400, 2001, 100))
WIDE = list(range(200, 1601, 200))
PUBLISHED_TABLE4_P3 = {1100: 888, 1120: 326, 1140: 324, 1160: 323, 1180: 322, 1200: 322}


def label(ratio: float) -> str:
    tag = NUMBERED.get(ratio)
    return f"{tag} ({100 * ratio:.2f} %)" if tag else f"{100 * ratio:.2f} %"


@dataclass
class Study:
    store: RunStore
    workers: int | None
    scheduler: str | None
    progress: bool

    def base(self, ratio: float, *extra: str) -> Sweep:
        overrides = STUDY_NUMERICS + [f"projectile.centre_of_mass_ratio={ratio}", 'name="paper"', *extra]
        return Sweep.from_file(scene_path("paper_p3"), overrides)

    def runs(self, bases: Sequence[Sweep], variations: Sequence[Sequence[Variation]]) -> list[pd.DataFrame]:
        """One parallel sweep over several bases; a table per base."""
        pairs = [(b, v) for b, vs in zip(bases, variations) for v in vs]
        table = run_sweep(Sweep.combined(pairs), self.store, workers=self.workers, scheduler=self.scheduler,
                          progress=self.progress)
        out, start = [], 0
        for vs in variations:
            out.append(table.iloc[start:start + len(vs)].reset_index(drop=True))
            start += len(vs)
        return out

    def history(self, key: str) -> pd.DataFrame:
        return self.store.history(key)


def _convergence_rows(study: Study, table: pd.DataFrame, varied: str) -> list[dict]:
    rows = []
    for _, row in table.iterrows():
        if isinstance(row.get("error"), str):
            rows.append({varied: row[varied], "error": row["error"]})
            continue
        history = study.history(row["key"])
        peak = attack_angle_peak(history)
        rows.append({
            varied: row[varied],
            "peak": (float(history["total_attack_angle"].iloc[peak]), float(history["speed"].iloc[peak])),
            "unstable": is_unstable(row["axis_angle_change"]),
            "convergence_speed": convergence_speed(history, CONVERGENCE_THRESHOLD),
            "max_attack_angle": row["max_attack_angle"],
            "axis_angle_change": row["axis_angle_change"],
            "end_reason": row["end_reason"],
            "key": row["key"],
        })
    return rows


def characteristic(rows: list[dict]) -> float | None:
    """Median convergence speed of the unstable runs that converged inside the target."""
    values = [r["convergence_speed"] for r in rows if r.get("unstable") and r.get("convergence_speed")]
    return float(np.median(values)) if values else None


def _fit(x: Sequence[float], y: Sequence[float]) -> dict:
    x, y = np.asarray(x, float), np.asarray(y, float)
    slope, intercept = np.polyfit(x, y, 1)
    residual = y - (slope * x + intercept)
    r2 = 1 - residual @ residual / ((y - y.mean()) @ (y - y.mean()))
    return {"slope": float(slope), "intercept": float(intercept), "r2": float(r2)}


def _cell(row: dict) -> str:
    """``impact -> convergent`` for a Table-4 cell, marking stable, exited and failed runs."""
    if "error" in row:
        return f"{row['impact.speed']:.0f} -> failed ({row['error'].split(':')[0]})"
    return (f"{row['impact.speed']:.0f} -> {_fmt(row.get('convergence_speed'))}"
            + ("" if row.get("unstable") else " (stable)")
            + (" (exited)" if row.get("end_reason") == "exited" else ""))


def _interpolate(xs: Sequence[float], ys: Sequence[float | None], x: float) -> float | None:
    points = [(a, v) for a, v in zip(xs, ys) if v is not None]
    if not points or not points[0][0] <= x <= points[-1][0]:
        return None
    return float(np.interp(x, [a for a, _ in points], [v for _, v in points]))


def _fmt(value, digits=0) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    return f"{value:.{digits}f}"


# --------------------------------------------------------------------------- figures


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _angle_figure(study: Study, runs: list[tuple[str, str]], title: str, path: Path) -> None:
    """Trajectory, axis angle and attack angle against speed for several runs (label, key)."""
    plt = _plt()
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    for name, key in runs:
        h = study.history(key)
        axes[0].plot(h["position_x"], -h["position_z"], label=name)
        axes[1].plot(h["speed"], h["axis_angle"], label=name)
        axes[2].plot(h["speed"], h["attack_angle"], label=name)
    axes[0].set(xlabel="horizontal position X (m)", ylabel="depth of the centre of mass (m)",
                title="trajectory")
    axes[0].invert_yaxis()
    axes[0].set_aspect("equal", adjustable="datalim")
    axes[1].set(xlabel="speed (m/s)", ylabel="axis angle (deg)", title="axis angle")
    axes[2].set(xlabel="speed (m/s)", ylabel="attack angle (deg)", title="attack angle")
    for ax in axes[1:]:
        ax.invert_xaxis()
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[2].legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def _history_figure(study: Study, runs: list[tuple[str, str]], centre: float, title: str, path: Path) -> None:
    plt = _plt()
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    for name, key in runs:
        h = study.history(key)
        pitch = np.hypot(h["moment_y"], h["moment_z"]) / 1e3
        axes[0].plot(h["time"] * 1e3, h["speed"], label=name)
        axes[1].plot(h["time"] * 1e3, pitch, label=name)
        axes[2].plot(h["time"] * 1e3, h["resistance_centre_from_tip"], label=name)
    axes[2].axhline(centre, color="k", lw=0.8, ls="--", label="centre of mass")
    axes[0].set(xlabel="time (ms)", ylabel="speed (m/s)", title="speed")
    axes[1].set(xlabel="time (ms)", ylabel="|transverse moment| (kN m)", title="moment about the centre of mass")
    axes[2].set(xlabel="time (ms)", ylabel="resistance centre behind the tip (m)", title="resistance centre",
                ylim=(0.0, 0.93))
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def _speeds_figure(ratios, criticals, convergents, fits, path: Path) -> None:
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
    x = np.array(ratios) * 100
    for ax, values, fit, name in ((axes[0], criticals, fits["critical"], "critical impact velocity"),
                                  (axes[1], convergents, fits["convergent"], "characteristic convergent velocity")):
        ax.plot(x, values, "o", label="this code")
        xs = np.linspace(x.min(), x.max(), 10)
        ax.plot(xs, fit["slope"] * xs / 100 + fit["intercept"], "-",
                label=f"linear fit, R^2 = {fit['r2']:.3f}")
        ax.set(xlabel="Lc/L (%)", ylabel=f"{name} (m/s)", title=name)
        ax.grid(alpha=0.3)
    axes[0].plot([56.36], [1110], "s", color="C3", label="paper, #3 (1100-1120)")
    axes[1].plot([56.36], [322], "s", color="C3", label="paper, #3")
    for ax in axes:
        ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def _boundary(ratio: float):
    from .prediction import turn_boundary
    from .runner import prepare_projectile, scene_loads
    from .scene import load_scene

    scene = load_scene(scene_path("paper_p3"), STUDY_NUMERICS + [f"projectile.centre_of_mass_ratio={ratio}"])
    prepared = prepare_projectile(scene)
    return turn_boundary(scene_loads(scene, prepared), prepared.mass.mass, attack_angles=tuple(range(1, 31)))


def _boundary_figure(study: Study, boundary, rows: list[dict], path: Path) -> None:
    """V_turn(alpha) and V0(alpha) of #3 with the unstable runs' paths in the (alpha, V) plane."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7.5, 5))
    a = np.array(boundary.attack_angles, float)
    for values, name in ((boundary.non_rotating, "non-rotating crossing V0"),
                         (boundary.steady_turn, "steady-turn boundary V_turn")):
        v = np.array([np.nan if x is None else x for x in values], float)
        ax.plot(a, v, "o-", label=name)
    for row in rows:
        if row["unstable"]:
            h = study.history(row["key"])
            ax.plot(h["total_attack_angle"], h["speed"], lw=0.8, alpha=0.7,
                    label=f"run at {row['impact.speed']:.0f} m/s")
    ax.set(xlabel="attack angle (deg)", ylabel="speed (m/s)", xlim=(0, 31), ylim=(0, 2000),
           title="projectile #3: load-only boundaries and unstable runs")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


# --------------------------------------------------------------------------- the study


def reproduce(out: str | Path, store: RunStore, workers: int | None = None, scheduler: str | None = None,
              progress: bool = True) -> dict:
    """Run the whole study and write its tables and figures into ``out``."""
    start = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    study = Study(store, workers, scheduler, progress)
    ratios = list(PAPER_RATIOS)
    p3 = ratios.index(0.5636)

    # 1. critical impact velocity at 1 degree, every projectile, plus #3 with scaled inertia
    inertia_scales = (0.67, 1.5)
    bases = [study.base(r) for r in ratios]
    bases += [study.base(0.5636, f"projectile.transverse_inertia_scale={k}") for k in inertia_scales]
    searches = find_critical_velocities(bases, store, SCAN, 5.0, workers, scheduler, progress)
    critical = [s.critical_velocity for s in searches[:len(ratios)]]
    inertia_critical = [s.critical_velocity for s in searches[len(ratios):]]

    # 2. six impact speeds 20 m/s apart around each critical speed (1 degree attack)
    around = []
    for c in critical:
        centre = 20 * round((c or 1000) / 20)
        around.append([centre + d for d in (-40, -20, 0, 20, 40, 60)])
    # paper's Table 4 speeds for #3, the 5-degree scan and 1 degree + 10 degrees oblique for everyone,
    # 20 and 30 degrees oblique for #3
    oblique = {10: ratios, 20: [0.5636], 30: [0.5636]}
    jobs: list[tuple[str, float, Sweep, list[Variation]]] = []
    for r, speeds in zip(ratios, around):
        jobs.append(("attack 1", r, study.base(r), grid({"impact.speed": speeds})))
        jobs.append(("attack 5", r, study.base(r, "impact.attack_angle=5"), grid({"impact.speed": WIDE})))
    jobs.append(("paper speeds", 0.5636, study.base(0.5636), grid({"impact.speed": list(PUBLISHED_TABLE4_P3)})))
    for angle, which in oblique.items():
        for r in which:
            jobs.append((f"attack 1, oblique {angle}", r, study.base(r, f"impact.oblique_angle={angle}"),
                         grid({"impact.speed": WIDE})))
    # an oblique angle alone (no attack angle), #3: does it disturb less than an attack angle?
    for angle in (10, 30):
        jobs.append((f"attack 0, oblique {angle}", 0.5636,
                     study.base(0.5636, "impact.attack_angle=0", f"impact.oblique_angle={angle}"),
                     grid({"impact.speed": WIDE})))
    # numerical check: #3 near its critical speed at the shipped (finer) numerics
    check_speeds = [around[p3][1], around[p3][3]]
    fine = Sweep.from_file(scene_path("paper_p3"), FINE_NUMERICS + ["projectile.centre_of_mass_ratio=0.5636"])
    jobs.append(("fine numerics", 0.5636, fine, grid({"impact.speed": check_speeds})))
    tables = study.runs([j[2] for j in jobs], [j[3] for j in jobs])
    results: dict[tuple[str, float], list[dict]] = {}
    for (kind, r, _, _), table in zip(jobs, tables):
        results[(kind, r)] = _convergence_rows(study, table, "impact.speed")

    # 3. characteristic convergent velocities
    disturbances = ["attack 1", "attack 5", "attack 1, oblique 10"]
    convergent = {d: [characteristic(results[(d, r)]) for r in ratios] for d in disturbances}
    convergent["attack 1, oblique 20"] = [characteristic(results[("attack 1, oblique 20", 0.5636)])]
    convergent["attack 1, oblique 30"] = [characteristic(results[("attack 1, oblique 30", 0.5636)])]
    for angle in (10, 30):
        kind = f"attack 0, oblique {angle}"
        convergent[kind] = [characteristic(results[(kind, 0.5636)])]
    headline = convergent["attack 1"]
    fits = {"critical": _fit(ratios, critical), "convergent": _fit(ratios, headline)}

    # 3b. the loads-only prediction (no trajectory), every projectile
    boundaries = [_boundary(r) for r in ratios]
    _boundary_figure(study, boundaries[p3], results[("attack 1", 0.5636)], out / "turn_boundary_p3.png")

    # 4. figures
    for r, rows in ((r, results[("attack 1", r)]) for r in ratios):
        runs = [(f"{row['impact.speed']:.0f} m/s", row["key"]) for row in rows]
        name = f"angles_{100 * r:.2f}".replace(".", "_")
        _angle_figure(study, runs, f"Lc/L = {label(r)}, 1 degree attack: six impact speeds around the critical",
                      out / f"{name}.png")
    _angle_figure(study, [(f"{row['impact.speed']:.0f} m/s", row["key"]) for row in results[("attack 5", 0.5636)]],
                  "projectile #3, 5 degrees attack", out / "angles_p3_attack5.png")
    obl = []
    for angle in (10, 20, 30):
        for row in results[(f"attack 1, oblique {angle}", 0.5636)]:
            if row["impact.speed"] in (800, 1200):
                obl.append((f"{angle} deg oblique, {row['impact.speed']:.0f} m/s", row["key"]))
    _angle_figure(study, obl, "projectile #3, 1 degree attack with 10, 20 and 30 degrees oblique",
                  out / "angles_p3_oblique.png")
    rows3 = results[("attack 1", 0.5636)]
    stable = [row for row in rows3 if not row["unstable"]]
    unstable = [row for row in rows3 if row["unstable"]]
    pair = ([max(stable, key=lambda row: row["impact.speed"])] if stable else []) + (
        [min(unstable, key=lambda row: row["impact.speed"])] if unstable else [])
    lc = 0.5636 * 0.93
    _history_figure(study, [(f"{row['impact.speed']:.0f} m/s", row["key"]) for row in pair], lc,
                    "projectile #3 just below and above its critical speed (1 degree attack)",
                    out / "histories_p3_critical.png")
    paper_pair = [row for row in results[("paper speeds", 0.5636)] if row["impact.speed"] in (1100, 1120)]
    _history_figure(study, [(f"{row['impact.speed']:.0f} m/s", row["key"]) for row in paper_pair], lc,
                    "projectile #3 at the paper's 1100 and 1120 m/s (1 degree attack)",
                    out / "histories_p3_paper_speeds.png")
    _history_figure(study, [(f"{row['impact.speed']:.0f} m/s", row["key"]) for row in results[("attack 5", 0.5636)]],
                    lc, "projectile #3, 5 degrees attack", out / "histories_p3_attack5.png")
    _history_figure(study, obl, lc, "projectile #3, 1 degree attack with 10, 20 and 30 degrees oblique",
                    out / "histories_p3_oblique.png")
    _speeds_figure(ratios, critical, headline, fits, out / "speeds_vs_lc.png")

    record = {
        "ratios": ratios, "critical_velocity": critical,
        "critical_bracket": [s.bracket for s in searches[:len(ratios)]],
        "characteristic_convergent_velocity": convergent, "fits": fits,
        "inertia_scales": list(inertia_scales), "critical_with_scaled_inertia": inertia_critical,
        "fold_speed": [b.fold_speed for b in boundaries],
        "fold_attack_angle": [b.fold_attack_angle for b in boundaries],
        "runs": {f"{k[0]} @ {k[1]}": v for k, v in results.items()},
        "wall_time": time.perf_counter() - start,
    }
    atomic_write_text(out / "results.json", json.dumps(record, indent=1, default=str) + "\n")
    atomic_write_text(out / "results.md", _markdown(record, results, ratios, critical, convergent, fits,
                                                    searches, inertia_scales, inertia_critical, boundaries))
    return record


def _markdown(record, results, ratios, critical, convergent, fits, searches, inertia_scales,
              inertia_critical, boundaries) -> str:
    lines = ["# The paper's instability study, regenerated", "",
             "Generated by `penetrate paper` (cases/paper.py); do not edit by hand. "
             f"Numerics of every run: `{' '.join(STUDY_NUMERICS)}` unless stated. "
             f"Convergence threshold {CONVERGENCE_THRESHOLD} deg. Wall time {record['wall_time']:.0f} s "
             "(runs already in the store are reused).", ""]

    lines += ["## Critical impact velocity and characteristic convergent velocity (1 degree attack)", "",
              "| projectile (Lc/L) | critical (m/s) | bracket (m/s) | convergent, 1 deg (m/s) |"
              " convergent, 5 deg (m/s) | convergent, 1 deg + 10 deg oblique (m/s) | spread |",
              "|---|---|---|---|---|---|---|"]
    for i, r in enumerate(ratios):
        values = [convergent[d][i] for d in ("attack 1", "attack 5", "attack 1, oblique 10")]
        known = [v for v in values if v]
        spread = f"{(max(known) - min(known)) / np.mean(known):.1%}" if len(known) > 1 else "-"
        bracket = searches[i].bracket
        lines.append(f"| {label(r)} | {_fmt(critical[i])} | {bracket[0]:g}-{bracket[1]:g} | "
                     + " | ".join(_fmt(v) for v in values) + f" | {spread} |" if bracket else
                     f"| {label(r)} | - | - | " + " | ".join(_fmt(v) for v in values) + f" | {spread} |")
    lines += ["", f"Linear fits against Lc/L: critical = {fits['critical']['slope']:.0f} Lc/L + "
              f"{fits['critical']['intercept']:.0f} m/s (R^2 = {fits['critical']['r2']:.3f}); "
              f"convergent = {fits['convergent']['slope']:.0f} Lc/L + {fits['convergent']['intercept']:.0f} m/s "
              f"(R^2 = {fits['convergent']['r2']:.3f}).", "",
              "![critical and convergent velocity against Lc/L](speeds_vs_lc.png)", ""]

    lines += ["## Projectile #3 against the paper's Table 4", "",
              "| impact speed (m/s) | paper: convergent (m/s) | ours: convergent (m/s) | ours: stable? |"
              " ours: max attack (deg) | ours: axis turn (deg) |", "|---|---|---|---|---|---|"]
    for row in results[("paper speeds", 0.5636)]:
        v = row["impact.speed"]
        lines.append(f"| {v:.0f} | {PUBLISHED_TABLE4_P3[int(v)]} | {_fmt(row['convergence_speed'])} | "
                     f"{'unstable' if row['unstable'] else 'stable'} | {row['max_attack_angle']:.2f} | "
                     f"{row['axis_angle_change']:.1f} |")
    lines.append("")

    lines += ["## Convergent velocity against impact velocity (the paper's Table 4 layout)", ""]
    for kind in ("attack 1", "attack 5", "attack 1, oblique 10"):
        lines += [f"### {kind} deg" if "oblique" not in kind else f"### {kind} deg", "",
                  "| projectile | " + " | ".join(["impact (m/s) -> convergent (m/s)"]) + " |", "|---|---|"]
        for r in ratios:
            cells = [_cell(row) for row in results[(kind, r)]]
            lines.append(f"| {label(r)} | " + "; ".join(cells) + " |")
        lines.append("")
    for kind in ("attack 1, oblique 20", "attack 1, oblique 30", "attack 0, oblique 10", "attack 0, oblique 30"):
        cells = [_cell(row) for row in results[(kind, 0.5636)]]
        lines += [f"Projectile #3, {kind} deg: " + "; ".join(cells) + f". Characteristic: "
                  f"{_fmt(convergent[kind][0])} m/s.", ""]

    lines += ["## The convergent velocity from the loads alone", "",
              "Steady-turn boundary `V_turn(alpha)` (cases/prediction.py): the lowest speed at which a fully"
              " embedded projectile can hold a steady turn at some attack angle (its minimum over alpha, the"
              " fold), against the trajectory-measured characteristic convergent velocity (1 degree attack).", "",
              "| projectile | measured (m/s) | fold of the steady-turn boundary (m/s) | at attack angle (deg) |"
              " prediction / measured |", "|---|---|---|---|---|"]
    for r, b, measured in zip(ratios, boundaries, convergent["attack 1"]):
        ratio = b.fold_speed / measured if (b.fold_speed and measured) else None
        lines.append(f"| {label(r)} | {_fmt(measured)} | {_fmt(b.fold_speed)} | {_fmt(b.fold_attack_angle, 1)} |"
                     f" {_fmt(ratio, 3)} |")
    lines += ["", "Where the attack angle of the unstable 1-degree runs peaks, against the steady-turn boundary at"
              " that angle (medians over the unstable runs):", "",
              "| projectile | peak attack angle (deg) | speed at the peak (m/s) | V_turn at that angle (m/s) |"
              " V_turn / speed at the peak |", "|---|---|---|---|---|"]
    for r, b in zip(ratios, boundaries):
        peaks = [row["peak"] for row in results[("attack 1", r)] if row.get("unstable")]
        if not peaks:
            continue
        angle = float(np.median([p[0] for p in peaks]))
        speed = float(np.median([p[1] for p in peaks]))
        v_turn = _interpolate(b.attack_angles, b.steady_turn, angle)
        lines.append(f"| {label(r)} | {angle:.1f} | {speed:.0f} | {_fmt(v_turn)} | "
                     f"{_fmt(v_turn / speed if v_turn else None, 3)} |")
    b3 = boundaries[ratios.index(0.5636)]
    lines += ["", "Projectile #3, the boundaries against the attack angle (m/s):", "",
              "| attack angle (deg) | " + " | ".join(f"{a:g}" for a in b3.attack_angles) + " |",
              "|---|" + "---|" * len(b3.attack_angles),
              "| non-rotating crossing | " + " | ".join(_fmt(v) for v in b3.non_rotating) + " |",
              "| steady-turn boundary | " + " | ".join(_fmt(v) for v in b3.steady_turn) + " |", "",
              "![steady-turn boundary of #3](turn_boundary_p3.png)", ""]

    lines += ["## Transverse moment of inertia of #3", "",
              "| transverse inertia scale | critical impact velocity (m/s) |", "|---|---|",
              f"| 1.0 | {_fmt(critical[ratios.index(0.5636)])} |"]
    for k, c in zip(inertia_scales, inertia_critical):
        lines.append(f"| {k} | {_fmt(c)} |")
    lines.append("")

    fine = results[("fine numerics", 0.5636)]
    coarse = {row["impact.speed"]: row for row in results[("attack 1", 0.5636)]}
    lines += ["## Numerical check (#3 near its critical speed)", "",
              "| impact speed (m/s) | numerics | max attack (deg) | axis turn (deg) | convergent (m/s) |",
              "|---|---|---|---|---|"]
    for row in fine:
        v = row["impact.speed"]
        for name, r in (("study: 20 mm, 2e-5 s", coarse[v]), ("shipped: 10 mm, 1e-5 s", row)):
            lines.append(f"| {v:.0f} | {name} | {r['max_attack_angle']:.3f} | {r['axis_angle_change']:.2f} | "
                         f"{_fmt(r['convergence_speed'], 1)} |")
    lines.append("")

    lines += ["## Figures", ""]
    for r in ratios:
        name = f"angles_{100 * r:.2f}".replace(".", "_")
        lines.append(f"![{label(r)}]({name}.png)")
    lines += ["", "![#3 at 5 degrees](angles_p3_attack5.png)", "",
              "![#3 with oblique angles](angles_p3_oblique.png)", "",
              "![#3 near critical](histories_p3_critical.png)", "",
              "![#3 at the paper's speeds](histories_p3_paper_speeds.png)", "",
              "![#3 at 5 degrees: histories](histories_p3_attack5.png)", "",
              "![#3 with oblique angles: histories](histories_p3_oblique.png)", ""]
    return "\n".join(lines)


# --------------------------------------------------------------------------- the paper's variants

VARIANTS = {
    "paper default": [],
    "Coulomb friction, mu = 0.10": ["effects.friction.model=coulomb", "effects.friction.coefficient=0.1"],
    "capped friction, tau_s = 10 MPa": ['effects.friction={model = "capped", coefficient = 0.1, cap = 10e6}'],
    "conical nose, 12.92 deg": ['projectile.nose={shape = "cone", half_angle = 12.92}'],
    "soil, dynamic cavity expansion": ["target.law=soil_dynamic_cavity_expansion"],
    "softer soil": ["target.law=softer_soil"],
}
VARIANT_SPEEDS = list(range(200, 2001, 200))


def _path_at(table: pd.DataFrame, speed: float) -> float | None:
    row = table.loc[table["impact.speed"] == speed].iloc[0]
    failed = isinstance(row.get("error"), str)
    return None if failed else float(row["path_length"])


def reproduce_variants(out: str | Path, store: RunStore, workers: int | None = None, scheduler: str | None = None,
                       progress: bool = True) -> dict:
    """The paper's variants (friction, conical nose, other soils): convergent velocities for the family.

    Every variant runs the seven projectiles at 1 degree attack over 200-2000 m/s;
    writes ``variants.md``, ``variants.json`` and ``variants.png`` into ``out``.
    """
    start = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    study = Study(store, workers, scheduler, progress)
    ratios = list(PAPER_RATIOS)
    jobs = [(name, r, study.base(r, *overrides), grid({"impact.speed": VARIANT_SPEEDS}))
            for name, overrides in VARIANTS.items() for r in ratios]
    tables = study.runs([j[2] for j in jobs], [j[3] for j in jobs])
    results = {(name, r): _convergence_rows(study, table, "impact.speed")
               for (name, r, _, _), table in zip(jobs, tables)}
    characteristic_by = {name: [characteristic(results[(name, r)]) for r in ratios] for name in VARIANTS}
    depth_at = {name: [_path_at(table, 400) for (n, _, _, _), table in zip(jobs, tables) if n == name]
                for name in VARIANTS}

    plt = _plt()
    fig, ax = plt.subplots(figsize=(7.5, 5))
    for name, values in characteristic_by.items():
        ax.plot([100 * r for r in ratios], [np.nan if v is None else v for v in values], "o-", label=name)
    ax.set(xlabel="Lc/L (%)", ylabel="characteristic convergent velocity (m/s)",
           title="the paper's variants, 1 degree attack")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, out / "variants.png")
    plt.close(fig)

    lines = ["# The paper's variants, regenerated", "",
             "Generated by `penetrate paper --variants` (cases/paper.py); do not edit by hand. Every variant: the"
             " seven projectiles at 1 degree attack, normal incidence, impact speeds 200-2000 m/s (200 apart),"
             f" numerics `{' '.join(STUDY_NUMERICS)}`. Characteristic convergent velocity: median over the unstable"
             " runs that converged inside the target.", "",
             "## Characteristic convergent velocity against Lc/L (m/s)", "",
             "| variant | " + " | ".join(label(r) for r in ratios) + " | linear fit (R^2) |",
             "|---|" + "---|" * (len(ratios) + 1)]
    fits = {}
    for name, values in characteristic_by.items():
        known = [(r, v) for r, v in zip(ratios, values) if v is not None]
        fit = _fit([r for r, _ in known], [v for _, v in known]) if len(known) >= 3 else None
        fits[name] = fit
        fit_text = f"{fit['slope']:.0f} Lc/L + {fit['intercept']:.0f} ({fit['r2']:.3f})" if fit else "-"
        lines.append(f"| {name} | " + " | ".join(_fmt(v) for v in values) + f" | {fit_text} |")
    lines += ["", "![variants](variants.png)", "",
              "## Distance travelled at 400 m/s (m), stable runs", "",
              "| variant | " + " | ".join(label(r) for r in ratios) + " |", "|---|" + "---|" * len(ratios)]
    for name, values in depth_at.items():
        lines.append(f"| {name} | " + " | ".join(_fmt(v, 2) for v in values) + " |")
    lines += ["", "## Convergent velocity against impact velocity", ""]
    for name in VARIANTS:
        lines += [f"### {name}", "", "| projectile | impact (m/s) -> convergent (m/s) |", "|---|---|"]
        for r in ratios:
            cells = [_cell(row) for row in results[(name, r)]]
            lines.append(f"| {label(r)} | " + "; ".join(cells) + " |")
        lines.append("")
    record = {"ratios": ratios, "characteristic_convergent_velocity": characteristic_by, "fits": fits,
              "path_length_at_400": depth_at, "wall_time": time.perf_counter() - start}
    lines.insert(2, f"Wall time {record['wall_time']:.0f} s (runs already in the store are reused).")
    lines.insert(3, "")
    atomic_write_text(out / "variants.json", json.dumps(record, indent=1, default=str) + "\n")
    atomic_write_text(out / "variants.md", "\n".join(lines) + "\n")
    return record
