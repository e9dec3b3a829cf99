"""What the contact width changes: ``penetrate contact``.

A scene runs with the contact width ``w`` (``effects.contact_width``: the normal velocity over which a
surface point's stress rises from 0 to the full law) halved again and again, and with ``w = 0``, the
sharp switch of the paper's law, all at one fine RK4 step, so that the step error is far below the
differences shown.  The table gives, for each width, the depth, the path length, the axis turn and
(for unstable runs) the convergence speed, and their differences from the sharp run; for a plain
normal impact also the independent 1-D integration with the same width.  The differences fall as
``w`` does: the continuous law converges to the sharp one.  (The sharp run's own step error is
larger than the continuous runs' at the same step: its switch chatters once the attack angle has
decayed, so its axis turn converges at first order in the step.)
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from ..run import RunStore, atomic_write_text, convergence_speed, prepare_projectile
from ..scene import Overrides
from .accuracy import is_plain_normal_impact
from .pool import Pool
from .reference import axial_depth_1d
from .speeds import is_unstable
from .sweep import Sweep, Variation, run_sweep

__all__ = ["contact_study", "DEFAULT_WIDTHS", "DEFAULT_STEP"]

DEFAULT_WIDTHS = (3.0, 1.5, 0.75, 0.375, 0.1875)
DEFAULT_STEP = 2.5e-6


def contact_study(scene: str | os.PathLike, overrides: Overrides | None, store: RunStore, out: str | os.PathLike,
                  widths: Sequence[float] = DEFAULT_WIDTHS, step: float = DEFAULT_STEP,
                  pool: Pool | None = None) -> pd.DataFrame:
    """Run ``scene`` at each contact width and the sharp law; write ``contact.md`` and ``contact.csv``."""
    values = [*sorted(set(widths), reverse=True), 0.0]
    variations = [Variation({"effects.contact_width": w, "numerics.integrator": "rk4", "numerics.time_step": step})
                  for w in values]
    sweep = Sweep.from_file(scene, overrides, variations)
    result = run_sweep(sweep, store, pool)
    rows = []
    for i, (w, run) in enumerate(zip(values, result.runs)):
        if run.failed:
            raise RuntimeError(f"the run at contact width {w:g} m/s failed: {run.error}")
        s = run.summary
        rows.append({"contact_width": w, "depth": s.depth, "path_length": s.path_length,
                     "axis_angle_change": s.axis_angle_change, "end_reason": s.end_reason, "steps": s.steps,
                     "integration_time": s.integration_time,
                     "convergence_speed": convergence_speed(result.history(i)) if is_unstable(s.axis_angle_change)
                     else math.nan})
    table = pd.DataFrame(rows)
    sharp = table.iloc[-1]
    for name in ("depth", "path_length", "axis_angle_change", "convergence_speed"):
        table[f"{name}_change"] = table[name] - sharp[name]
    base = sweep.scenes[0]
    if is_plain_normal_impact(base):
        prepared = prepare_projectile(base)
        table["depth_1d"] = [axial_depth_1d(prepared.profile, base.target.build(), prepared.mass.mass,
                                            base.impact.speed, base.numerics.stop_speed, contact_width=w)[0]
                             for w in values]
    out = Path(out)
    atomic_write_text(out / "contact.csv", table.to_csv(index=False))
    atomic_write_text(out / "contact.md", _markdown(table, base.name or Path(scene).stem, step))
    return table


def _markdown(table: pd.DataFrame, name: str, step: float) -> str:
    reference = "depth_1d" in table
    lines = [f"# Contact width: {name}", "",
             f"RK4 at {step:g} s on the scene's mesh; the last row is the sharp law (`contact_width = 0`). Changes"
             " are from the sharp run (m, deg, m/s).", "",
             "| contact width (m/s) | depth (m) | change | path (m) | change | axis turn (deg) | change |"
             " convergence speed (m/s) | change |" + (" 1-D depth, same width (m) |" if reference else ""),
             "|---|---|---|---|---|---|---|---|---|" + ("---|" if reference else "")]
    for _, row in table.iterrows():
        cells = [f"{row['contact_width']:g}", f"{row['depth']:.6f}", f"{row['depth_change']:+.2e}",
                 f"{row['path_length']:.6f}", f"{row['path_length_change']:+.2e}", f"{row['axis_angle_change']:.4f}",
                 f"{row['axis_angle_change_change']:+.2e}", _number(row["convergence_speed"], ".2f"),
                 _number(row["convergence_speed_change"], "+.2e")]
        if reference:
            cells.append(f"{row['depth_1d']:.6f}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _number(value: float, spec: str) -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else format(value, spec)
