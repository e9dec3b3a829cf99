"""Run one scene under several resistance laws, side by side: ``penetrate compare``."""

from __future__ import annotations

import os
from pathlib import Path

import pandas as pd

from fem_loads.resistance import resistance_law

from .results import atomic_write_text, save_figure
from .sweep import RunStore, Sweep, Variation, run_sweep

__all__ = ["compare_laws"]

COLUMNS = ("end_reason", "depth", "path_length", "final_time", "max_attack_angle", "axis_angle_change")


def compare_laws(scene: str | os.PathLike, overrides: list[str], laws: list[str], store: RunStore,
                 out: str | os.PathLike, workers: int | None = None, scheduler: str | None = None,
                 progress: bool = True) -> pd.DataFrame:
    """Run ``scene`` once per named law; write ``compare.csv``, ``compare.md`` and ``compare.png`` in ``out``."""
    named = [(name, resistance_law(name)) for name in laws]  # unknown names fail before any run
    sweep = Sweep.from_file(scene, overrides, [Variation({"target.law": name}) for name, _ in named])
    table = run_sweep(sweep, store, workers=workers, scheduler=scheduler, progress=progress)
    table.insert(1, "A_sigma_0", [law.static_stress for _, law in named])
    table.insert(2, "B_rho_0", [law.dynamic_density for _, law in named])
    out = Path(out)
    atomic_write_text(out / "compare.csv", table.to_csv(index=False))
    shown = ["target.law", "A_sigma_0", "B_rho_0", *[c for c in COLUMNS if c in table]]
    lines = [f"# {sweep.scenes[0].name or Path(scene).stem} under {len(laws)} resistance laws", "",
             "| " + " | ".join(shown) + " |", "|" + "---|" * len(shown)]
    for _, row in table.iterrows():
        cells = [f"{row[c]:.4g}" if isinstance(row[c], float) else str(row[c]) for c in shown]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "Units: Pa, kg/m^3, m, m, s, deg, deg.", "", "![speed against depth](compare.png)", ""]
    atomic_write_text(out / "compare.md", "\n".join(lines))
    _figure(table, store, out / "compare.png")
    return table


def _figure(table: pd.DataFrame, store: RunStore, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
    for _, row in table.iterrows():
        if isinstance(row.get("error"), str):
            continue
        h = store.history(row["key"])
        axes[0].plot(h["tip_depth"], h["speed"], label=row["target.law"])
        axes[1].plot(h["position_x"], -h["position_z"], label=row["target.law"])
    axes[0].set(xlabel="depth of the nose tip (m)", ylabel="speed (m/s)", title="speed against depth")
    axes[1].set(xlabel="horizontal position X (m)", ylabel="depth of the centre of mass (m)", title="trajectory")
    axes[1].invert_yaxis()
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)
