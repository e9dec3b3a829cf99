"""Run one scene under several resistance laws, side by side: ``penetrate compare``."""

from __future__ import annotations

import os
from pathlib import Path

import pandas as pd

from fem_loads.resistance import resistance_law

from ..run import RunStore, atomic_write_text
from ..scene import Overrides
from ..viz.figures import legend_outside, save_figure, subplots
from .pool import Pool
from .sweep import Sweep, SweepResult, Variation, run_sweep

__all__ = ["compare_laws", "COLUMNS"]

COLUMNS = ("end_reason", "depth", "path_length", "final_time", "max_attack_angle", "axis_angle_change")
UNITS = "Units: Pa, kg/m^3, m, m, s, deg, deg."


def compare_laws(
    scene: str | os.PathLike,
    overrides: Overrides | None,
    laws: list[str],
    store: RunStore,
    out: str | os.PathLike,
    pool: Pool | None = None,
) -> pd.DataFrame:
    """Run ``scene`` once per named law; write ``compare.csv``, ``compare.md`` and ``compare.png`` in ``out``.

    Raises
    ------
    fem_loads.UnknownLawError
        For a name that is not a known law, before any run.
    """
    named = [(name, resistance_law(name)) for name in laws]
    sweep = Sweep.from_file(scene, overrides, [Variation({"target.law": name}) for name, _ in named])
    result = run_sweep(sweep, store, pool)
    table = result.table()
    table.insert(1, "A_sigma_0", [law.static_stress for _, law in named])
    table.insert(2, "B_rho_0", [law.dynamic_density for _, law in named])
    out = Path(out)
    atomic_write_text(out / "compare.csv", table.to_csv(index=False))
    atomic_write_text(out / "compare.md", _markdown(table, sweep.scenes[0].name or Path(scene).stem, len(laws)))
    _figure(result, laws, out / "compare.png")
    return table


def _markdown(table: pd.DataFrame, name: str, count: int) -> str:
    shown = ["target.law", "A_sigma_0", "B_rho_0", *[c for c in COLUMNS if c in table]]
    lines = [f"# {name} under {count} resistance laws", "", "| " + " | ".join(shown) + " |", "|" + "---|" * len(shown)]
    for _, row in table.iterrows():
        cells = [f"{row[c]:.4g}" if isinstance(row[c], float) else str(row[c]) for c in shown]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", UNITS, "", "![speed against depth](compare.png)", ""]
    return "\n".join(lines)


def _figure(result: SweepResult, laws: list[str], path: Path) -> None:
    fig, axes = subplots(1, 2, figsize=(12.5, 4.4))
    for i, (law, run) in enumerate(zip(laws, result.runs)):
        if run.failed:
            continue
        h = result.history(i)
        axes[0].plot(h["tip_depth"], h["speed"], label=law)
        axes[1].plot(h["position_x"], -h["position_z"], label=law)
    axes[0].set(xlabel="depth of the nose tip (m)", ylabel="speed (m/s)", title="speed against depth")
    axes[1].set(xlabel="horizontal position X (m)", ylabel="depth of the centre of mass (m)", title="trajectory")
    axes[1].invert_yaxis()
    for ax in axes:
        ax.grid(alpha=0.3)
    legend_outside(axes[1])  # the same laws in both panels: one legend, right of the panels
    fig.tight_layout()
    save_figure(fig, path)
