"""``penetrate paper``: run the study (or its variants) and write its tables, figures and numbers."""

from __future__ import annotations

import functools
import time
from collections.abc import Callable
from pathlib import Path

from ...run import RunStore
from ..engine.pool import Pool, map_local
from ..engine.report import Report, write_report
from ..reduced.turn_boundary import TurnBoundary
from ..speeds.characteristic import find_critical_velocities
from . import figures
from .analysis import Study, characteristic, linear_fit, load_boundary
from .plan import INERTIA_SCALES, P3, PAPER_RATIOS, SCAN, VARIANTS, critical_bases, label, speed_groups, variant_groups
from .report import Runs, StudyResults, figure_name, results_markdown, variants_markdown

__all__ = ["reproduce", "reproduce_variants"]

HEADLINE = ("attack 1", "attack 5", "attack 1, oblique 10")
SINGLE = ("attack 1, oblique 20", "attack 1, oblique 30", "attack 0, oblique 10", "attack 0, oblique 30")


def reproduce(out: str | Path, store: RunStore, pool: Pool | None = None) -> dict:
    """Run the whole study and write ``results.md``, ``results.json`` and the figures into ``out``."""
    start = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    study = Study(store, pool or Pool())
    ratios = list(PAPER_RATIOS)
    # 1. the critical impact velocity at 1 degree of every projectile, and of #3 with scaled inertia
    searches = find_critical_velocities(critical_bases(), store, SCAN, 5.0, pool)
    critical = [s.critical_velocity for s in searches[: len(ratios)]]
    inertia_critical = [s.critical_velocity for s in searches[len(ratios) :]]
    # 2. every other run, now that the critical speeds are known
    runs = study.run(speed_groups(critical))
    # 3. characteristic convergent velocities, fits and the load-only prediction
    convergent = {d: [characteristic(runs[(d, r)]) for r in ratios] for d in HEADLINE}
    convergent.update({d: [characteristic(runs[(d, P3)])] for d in SINGLE})
    fits = {"critical": linear_fit(ratios, critical), "convergent": linear_fit(ratios, convergent["attack 1"])}
    # one projectile's boundary per local worker: the pool's width, on this machine even with a cluster
    boundaries = map_local(load_boundary, [(r,) for r in ratios], study.pool.width)
    drawn = _figures(study, runs, ratios, critical, convergent, fits, boundaries)
    wall_time = time.perf_counter() - start
    record = {
        "ratios": ratios,
        "critical_velocity": critical,
        "critical_bracket": [s.bracket for s in searches[: len(ratios)]],
        "characteristic_convergent_velocity": convergent,
        "fits": fits,
        "inertia_scales": list(INERTIA_SCALES),
        "critical_with_scaled_inertia": inertia_critical,
        "fold_speed": [b.fold_speed for b in boundaries],
        "fold_attack_angle": [b.fold_attack_angle for b in boundaries],
        "runs": {f"{kind} @ {ratio}": [run.record() for run in group] for (kind, ratio), group in runs.items()},
        "wall_time": wall_time,
    }
    write_report(
        out,
        Report(
            "results",
            results_markdown(
                StudyResults(
                    ratios,
                    runs,
                    searches,
                    critical,
                    convergent,
                    fits,
                    INERTIA_SCALES,
                    inertia_critical,
                    boundaries,
                    wall_time,
                )
            ),
            record=record,
            figures=drawn,
        ),
        study.pool.width,
    )
    return record


def _figures(
    study: Study,
    runs: Runs,
    ratios: list[float],
    critical: list[float | None],
    convergent: dict[str, list[float | None]],
    fits: dict[str, dict],
    boundaries: list[TurnBoundary],
) -> dict[str, Callable[[Path], None]]:
    """The study's figures by file name, each a function that draws it into the path it is given (a module's
    function with its data bound, so that the study's workers can draw them)."""
    drawn: dict[str, Callable[[Path], None]] = {}
    p3_boundary = boundaries[ratios.index(P3)]
    p3_runs = runs[("attack 1", P3)]
    drawn["turn_boundary_p3.png"] = functools.partial(figures.boundary_figure, study, p3_boundary, p3_runs)
    for r in ratios:
        named = [(f"{run.speed:.0f} m/s", run.key) for run in runs[("attack 1", r)]]
        title = f"Lc/L = {label(r)}, 1 degree attack: six impact speeds around the critical"
        drawn[f"{figure_name(r)}.png"] = functools.partial(figures.angle_figure, study, named, title)
    attack5 = [(f"{run.speed:.0f} m/s", run.key) for run in runs[("attack 5", P3)]]
    attack5_title = "projectile #3, 5 degrees attack"
    drawn["angles_p3_attack5.png"] = functools.partial(figures.angle_figure, study, attack5, attack5_title)
    oblique = [
        (f"{angle} deg oblique, {run.speed:.0f} m/s", run.key)
        for angle in (10, 20, 30)
        for run in runs[(f"attack 1, oblique {angle}", P3)]
        if run.speed in (800, 1200)
    ]
    oblique_title = "projectile #3, 1 degree attack with 10, 20 and 30 degrees oblique"
    drawn["angles_p3_oblique.png"] = functools.partial(figures.angle_figure, study, oblique, oblique_title)
    p3 = runs[("attack 1", P3)]
    stable, unstable = [run for run in p3 if not run.unstable], [run for run in p3 if run.unstable]
    pair = ([max(stable, key=lambda run: run.speed)] if stable else []) + (
        [min(unstable, key=lambda run: run.speed)] if unstable else []
    )
    centre = P3 * 0.93
    paper_pair = [(f"{run.speed:.0f} m/s", run.key) for run in runs[("paper speeds", P3)] if run.speed in (1100, 1120)]
    histories = {
        "histories_p3_critical.png": (
            [(f"{run.speed:.0f} m/s", run.key) for run in pair],
            "projectile #3 just below and above its critical speed (1 degree attack)",
        ),
        "histories_p3_paper_speeds.png": (
            paper_pair,
            "projectile #3 at the paper's 1100 and 1120 m/s (1 degree attack)",
        ),
        "histories_p3_attack5.png": (attack5, "projectile #3, 5 degrees attack"),
        "histories_p3_oblique.png": (oblique, oblique_title),
    }
    for name, (named, title) in histories.items():
        drawn[name] = functools.partial(figures.history_figure, study, named, centre, title)
    drawn["speeds_vs_lc.png"] = functools.partial(figures.speeds_figure, ratios, critical, convergent["attack 1"], fits)
    return drawn


def reproduce_variants(out: str | Path, store: RunStore, pool: Pool | None = None) -> dict:
    """The paper's variants (friction, conical nose, other soils): convergent velocities for the family.

    Every variant runs the seven projectiles at 1 degree attack over 200-2000 m/s;
    writes ``variants.md``, ``variants.json`` and ``variants.png`` into ``out``.
    """
    start = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    ratios = list(PAPER_RATIOS)
    runs = Study(store, pool or Pool()).run(variant_groups())
    characteristic_by = {name: [characteristic(runs[(name, r)]) for r in ratios] for name in VARIANTS}
    path_at_400 = {
        name: [next(run.path_length for run in runs[(name, r)] if run.speed == 400) for r in ratios]
        for name in VARIANTS
    }
    fits = {}
    for name, values in characteristic_by.items():
        known = [(r, v) for r, v in zip(ratios, values) if v is not None]
        fits[name] = linear_fit([r for r, _ in known], [v for _, v in known]) if len(known) >= 3 else None
    wall_time = time.perf_counter() - start
    record = {
        "ratios": ratios,
        "characteristic_convergent_velocity": characteristic_by,
        "fits": fits,
        "path_length_at_400": path_at_400,
        "wall_time": wall_time,
    }
    markdown = variants_markdown(ratios, runs, characteristic_by, fits, path_at_400, wall_time)
    drawn = {"variants.png": lambda path: figures.variants_figure(ratios, characteristic_by, path)}
    write_report(out, Report("variants", markdown, record=record, figures=drawn))
    return record
