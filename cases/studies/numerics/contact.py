"""What the two switch widths change: ``penetrate contact`` and ``penetrate entry``.

A scene runs with the contact incidence ``delta`` (``effects.contact_incidence``: the contact width,
the normal velocity over which a surface point's stress rises from 0 to the full law, is ``delta``
times the body's speed ``|V| + |omega| r_max``) halved again and again, and with the sharp switch of
the paper's law (``delta = 0`` and ``effects.contact_width = 0``), all at one fine RK4 step, so that
the step error is far below the differences shown.  The table gives, for each incidence, the depth,
the path length, the axis turn and (for unstable runs) the convergence speed, and their differences
from the sharp run; for a plain normal impact also the independent 1-D integration with the same
contact width.  The differences fall as ``delta`` does: the continuous law converges to the sharp
one.  (The sharp run's own step error is
larger than the continuous runs' at the same step: its switch chatters once the attack angle has
decayed, so its axis turn converges at first order in the step.)

The entry study runs a scene at several entry smoothings (``numerics.entry_smoothing``: the length over
which a surface point enters the target, in units of its own size) and several RK4 steps: how much
each smoothing moves the result (its values at the finest step) and how fast RK4's time error falls
with it (each step against the finest step at the same smoothing).  Entry switches a point's load on
within a fraction of a step when the smoothing is short, and a step that straddles many such entries
has an error of no clean order; a longer smoothing overlaps the entries of neighbouring points.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from fem_loads import ResistanceLaw

from ...reference.normal_impact import axial_depth_1d, is_plain_normal_impact
from ...run import RunStore, convergence_speed, prepare_projectile
from ...scene import Overrides
from ..engine.pool import Pool
from ..engine.report import Report, markdown_table, number_cell, write_report
from ..engine.sweep import Sweep, Variation, run_sweep
from ..speeds.instability import is_unstable

__all__ = [
    "contact_study",
    "entry_study",
    "DEFAULT_INCIDENCES",
    "DEFAULT_STEP",
    "DEFAULT_SMOOTHINGS",
    "DEFAULT_ENTRY_STEPS",
]

DEFAULT_INCIDENCES = (0.02, 0.01, 0.005, 0.0025, 0.00125)
DEFAULT_STEP = 2.5e-6
DEFAULT_SMOOTHINGS = (1.0, 2.0, 4.0, 8.0)
DEFAULT_ENTRY_STEPS = (1e-4, 5e-5, 2.5e-5, 1.25e-5, 6.25e-6, 3.125e-6)


def contact_study(
    scene: str | os.PathLike,
    overrides: Overrides | None,
    store: RunStore,
    out: str | os.PathLike,
    incidences: Sequence[float] = DEFAULT_INCIDENCES,
    step: float = DEFAULT_STEP,
    pool: Pool | None = None,
) -> pd.DataFrame:
    """Run ``scene`` at each contact incidence (no fixed width) and the sharp law; write ``contact.md``
    and ``contact.csv``."""
    values = [*sorted(set(incidences), reverse=True), 0.0]
    variations = [
        Variation(
            {
                "effects.contact_width": 0.0,
                "effects.contact_incidence": d,
                "numerics.integrator": "rk4",
                "numerics.time_step": step,
            }
        )
        for d in values
    ]
    sweep = Sweep.from_file(scene, overrides, variations)
    result = run_sweep(sweep, store, pool)
    rows = []
    for i, (w, s) in enumerate(zip(values, result.summaries([f"at contact incidence {w:g}" for w in values]))):
        rows.append(
            {
                "contact_incidence": w,
                "depth": s.depth,
                "path_length": s.path_length,
                "axis_angle_change": s.axis_angle_change,
                "end_reason": s.end_reason,
                "steps": s.steps,
                "integration_time": s.integration_time,
                "convergence_speed": convergence_speed(result.history(i))
                if is_unstable(s.axis_angle_change)
                else math.nan,
            }
        )
    table = pd.DataFrame(rows)
    sharp = table.iloc[-1]
    for name in ("depth", "path_length", "axis_angle_change", "convergence_speed"):
        table[f"{name}_change"] = table[name] - sharp[name]
    base = sweep.scenes[0]
    if is_plain_normal_impact(base):
        prepared = prepare_projectile(base)
        law = base.target.build()
        assert isinstance(law, ResistanceLaw)  # a plain normal impact's target has no layers
        table["depth_1d"] = [
            axial_depth_1d(
                prepared.profile,
                law,
                prepared.mass.mass,
                base.impact.speed,
                base.stop_speed,
                contact_incidence=w,
            )[0]
            for w in values
        ]
    write_report(out, Report("contact", _markdown(table, base.name or Path(scene).stem, step), table))
    return table


def _markdown(table: pd.DataFrame, name: str, step: float) -> str:
    reference = "depth_1d" in table
    lines = [
        f"# Contact incidence: {name}",
        "",
        f"RK4 at {step:g} s on the scene's mesh, no fixed contact width; the last row is the sharp law"
        " (`contact_incidence = 0`). Changes are from the sharp run (m, deg, m/s);"
        " changes below round-off (1e-12 of the value) are 0.",
        "",
    ]
    header = ["contact incidence", *CHANGES_HEADER] + (["1-D depth, same width (m)"] if reference else [])
    rows = [
        [number_cell(row["contact_incidence"], "g"), *_change_cells(row)]
        + ([number_cell(row["depth_1d"], ".6f")] if reference else [])
        for _, row in table.iterrows()
    ]
    lines += markdown_table(header, rows)
    return "\n".join(lines) + "\n"


def entry_study(
    scene: str | os.PathLike,
    overrides: Overrides | None,
    store: RunStore,
    out: str | os.PathLike,
    smoothings: Sequence[float] = DEFAULT_SMOOTHINGS,
    steps: Sequence[float] = DEFAULT_ENTRY_STEPS,
    pool: Pool | None = None,
) -> pd.DataFrame:
    """Run ``scene`` at each entry smoothing and RK4 step; write ``entry.md`` and ``entry.csv``.

    One row per (smoothing, step): the depth, path length, axis turn and (unstable runs) convergence
    speed; ``*_time_error``: the difference from the finest step at the same smoothing (relative for
    the depth and path); ``*_change``: the finest step's value less that of the smallest smoothing.
    """
    smoothings, steps = sorted(set(smoothings)), sorted(set(steps), reverse=True)
    values = [(e, h) for e in smoothings for h in steps]
    variations = [
        Variation({"numerics.entry_smoothing": e, "numerics.integrator": "rk4", "numerics.time_step": h})
        for e, h in values
    ]
    sweep = Sweep.from_file(scene, overrides, variations)
    result = run_sweep(sweep, store, pool)
    rows = []
    labels = [f"at entry smoothing {e:g}, step {h:g} s" for e, h in values]
    for i, ((e, h), s) in enumerate(zip(values, result.summaries(labels))):
        rows.append(
            {
                "entry_smoothing": e,
                "time_step": h,
                "depth": s.depth,
                "path_length": s.path_length,
                "axis_angle_change": s.axis_angle_change,
                "steps": s.steps,
                "energy_rejections": s.energy_rejections,
                "integration_time": s.integration_time,
                "convergence_speed": convergence_speed(result.history(i))
                if is_unstable(s.axis_angle_change)
                else math.nan,
            }
        )
    table = pd.DataFrame(rows)
    finest = table[table["time_step"] == steps[-1]].set_index("entry_smoothing")
    for name, relative in (
        ("depth", True),
        ("path_length", True),
        ("axis_angle_change", False),
        ("convergence_speed", False),
    ):
        at_finest = table["entry_smoothing"].map(finest[name])
        error = (table[name] - at_finest).abs()
        table[f"{name}_time_error"] = error / at_finest if relative else error
        table[f"{name}_change"] = at_finest - finest[name].iloc[0]
    write_report(out, Report("entry", _entry_markdown(table, sweep.scenes[0].name or Path(scene).stem), table))
    return table


def _entry_markdown(table: pd.DataFrame, name: str) -> str:
    steps = sorted(table["time_step"].unique(), reverse=True)
    finest = table[table["time_step"] == steps[-1]]
    smallest = finest["entry_smoothing"].iloc[0]
    lines = [
        f"# Entry smoothing: {name}",
        "",
        f"RK4 on the scene's mesh. At the finest step ({steps[-1]:g} s), each smoothing's result and its"
        f" change from smoothing {smallest:g} (m, deg, m/s):",
        "",
    ]
    changes = [[number_cell(row["entry_smoothing"], "g"), *_change_cells(row)] for _, row in finest.iterrows()]
    lines += markdown_table(["entry smoothing", *CHANGES_HEADER], changes)
    lines += [
        "",
        "Time error of each step against the finest step at the same smoothing: relative depth error /"
        " axis-turn error (deg); `*`: the energy guard retook steps.",
        "",
    ]
    time_errors = []
    for e, group in table.groupby("entry_smoothing"):
        group = group.set_index("time_step")
        cells = [
            f"{number_cell(group.loc[h, 'depth_time_error'], '.1e')}"
            f" / {number_cell(group.loc[h, 'axis_angle_change_time_error'], '.1e')}"
            + ("*" if group.loc[h, "energy_rejections"] else "")
            for h in steps[:-1]
        ]
        time_errors.append([number_cell(e, "g"), *cells])
    lines += markdown_table(["entry smoothing", *(f"{h:g} s" for h in steps[:-1])], time_errors)
    return "\n".join(lines) + "\n"


#: the columns of a row of :func:`_change_cells`: each quantity and its change
CHANGES_HEADER = (
    "depth (m)",
    "change",
    "path (m)",
    "change",
    "axis turn (deg)",
    "change",
    "convergence speed (m/s)",
    "change",
)


def _change_cells(row: pd.Series) -> list[str]:
    """The cells under :data:`CHANGES_HEADER`: the depth, path length, axis turn and convergence speed of ``row``,
    each followed by its :func:`_change`."""
    return [
        number_cell(row["depth"], ".6f"),
        _change(row, "depth"),
        number_cell(row["path_length"], ".6f"),
        _change(row, "path_length"),
        number_cell(row["axis_angle_change"], ".4f"),
        _change(row, "axis_angle_change"),
        number_cell(row["convergence_speed"], ".2f"),
        _change(row, "convergence_speed"),
    ]


#: a change below this fraction of the value is round-off (the summation order of two runs of one
#: setting), shown as 0: its digits would differ between machines and mean nothing
ROUND_OFF = 1e-12


def _change(row: pd.Series, name: str) -> str:
    """``row[name + '_change']`` to three digits, 0 where it is at the level of round-off."""
    change = row[f"{name}_change"]
    if isinstance(change, float) and not math.isnan(change) and abs(change) <= ROUND_OFF * abs(row[name]):
        change = 0.0
    return number_cell(change, "+.2e")
