"""The figures of the paper's study: trajectories and angles, load histories, characteristic speeds."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ...viz.figures import legend_outside, save_figure, subplots
from ..reduced.turn_boundary import TurnBoundary
from .analysis import PaperRun, Study

__all__ = ["angle_figure", "history_figure", "speeds_figure", "boundary_figure", "variants_figure"]


def angle_figure(study: Study, runs: Sequence[tuple[str, str]], title: str, path: Path) -> None:
    """Trajectory, axis angle and attack angle against speed for several runs (label, key)."""
    fig, axes = subplots(1, 3, figsize=(16.5, 4.6))
    for name, key in runs:
        h = study.history(key)
        axes[0].plot(h["position_x"], -h["position_z"], label=name)
        axes[1].plot(h["speed"], h["axis_angle"], label=name)
        axes[2].plot(h["speed"], h["attack_angle"], label=name)
    axes[0].set(xlabel="horizontal position X (m)", ylabel="depth of the centre of mass (m)", title="trajectory")
    axes[0].invert_yaxis()
    axes[0].set_aspect("equal", adjustable="datalim")
    axes[1].set(xlabel="speed (m/s)", ylabel="axis angle (deg)", title="axis angle")
    axes[2].set(xlabel="speed (m/s)", ylabel="attack angle (deg)", title="attack angle")
    for ax in axes[1:]:
        ax.invert_xaxis()
    for ax in axes:
        ax.grid(alpha=0.3)
    legend_outside(axes[2])  # the same runs in every panel: one legend, right of the panels
    fig.suptitle(title)
    fig.tight_layout()
    save_figure(fig, path)


def history_figure(study: Study, runs: Sequence[tuple[str, str]], centre: float, title: str, path: Path) -> None:
    """Speed, transverse moment and resistance centre against time for several runs (label, key)."""
    fig, axes = subplots(1, 3, figsize=(16.5, 4.6))
    for name, key in runs:
        h = study.history(key)
        pitch = np.hypot(h["moment_y"], h["moment_z"]) / 1e3
        axes[0].plot(h["time"] * 1e3, h["speed"], label=name)
        axes[1].plot(h["time"] * 1e3, pitch, label=name)
        axes[2].plot(h["time"] * 1e3, h["resistance_centre_from_tip"], label=name)
    axes[2].axhline(centre, color="k", lw=0.8, ls="--", label="centre of mass")
    axes[0].set(xlabel="time (ms)", ylabel="speed (m/s)", title="speed")
    axes[1].set(xlabel="time (ms)", ylabel="|transverse moment| (kN m)", title="moment about the centre of mass")
    axes[2].set(
        xlabel="time (ms)", ylabel="resistance centre behind the tip (m)", title="resistance centre", ylim=(0.0, 0.93)
    )
    for ax in axes:
        ax.grid(alpha=0.3)
    legend_outside(axes[2])  # the runs of every panel and the centre of mass: one legend
    fig.suptitle(title)
    fig.tight_layout()
    save_figure(fig, path)


def speeds_figure(
    ratios: Sequence[float],
    criticals: Sequence[float | None],
    convergents: Sequence[float | None],
    fits: dict,
    path: Path,
) -> None:
    """Critical and characteristic convergent velocity against Lc/L with their linear fits and the paper's #3."""
    fig, axes = subplots(1, 2, figsize=(14, 4.4))
    x = np.array(ratios) * 100
    for ax, values, fit, name in (
        (axes[0], criticals, fits["critical"], "critical impact velocity"),
        (axes[1], convergents, fits["convergent"], "characteristic convergent velocity"),
    ):
        ax.plot(x, values, "o", label="this code")
        xs = np.linspace(x.min(), x.max(), 10)
        ax.plot(xs, fit["slope"] * xs / 100 + fit["intercept"], "-", label=f"linear fit, R^2 = {fit['r2']:.3f}")
        ax.set(xlabel="Lc/L (%)", ylabel=f"{name} (m/s)", title=name)
        ax.grid(alpha=0.3)
    axes[0].plot([56.36], [1110], "s", color="C3", label="paper, #3 (1100-1120)")
    axes[1].plot([56.36], [322], "s", color="C3", label="paper, #3")
    for ax in axes:
        legend_outside(ax)
    fig.tight_layout()
    save_figure(fig, path)


def boundary_figure(study: Study, boundary: TurnBoundary, runs: Sequence[PaperRun], path: Path) -> None:
    """V_turn(alpha) and V0(alpha) of #3 with the unstable runs' paths in the (alpha, V) plane."""
    fig, ax = subplots(figsize=(9.5, 5))
    a = np.array(boundary.attack_angles, float)
    for values, name in (
        (boundary.non_rotating, "non-rotating crossing V0"),
        (boundary.steady_turn, "steady-turn boundary V_turn"),
    ):
        ax.plot(a, np.array([np.nan if v is None else v for v in values], float), "o-", label=name)
    for run in runs:
        if run.unstable:
            h = study.history(run.key)
            ax.plot(h["total_attack_angle"], h["speed"], lw=0.8, alpha=0.7, label=f"run at {run.speed:.0f} m/s")
    ax.set(
        xlabel="attack angle (deg)",
        ylabel="speed (m/s)",
        xlim=(0, 31),
        ylim=(0, 2000),
        title="projectile #3: load-only boundaries and unstable runs",
    )
    ax.grid(alpha=0.3)
    legend_outside(ax)
    fig.tight_layout()
    save_figure(fig, path)


def variants_figure(ratios: Sequence[float], characteristic_by: dict[str, list[float | None]], path: Path) -> None:
    """The characteristic convergent velocity of every variant against Lc/L."""
    fig, ax = subplots(figsize=(9.5, 5))
    for name, values in characteristic_by.items():
        ax.plot([100 * r for r in ratios], [np.nan if v is None else v for v in values], "o-", label=name)
    ax.set(
        xlabel="Lc/L (%)",
        ylabel="characteristic convergent velocity (m/s)",
        title="the paper's variants, 1 degree attack",
    )
    ax.grid(alpha=0.3)
    legend_outside(ax)
    fig.tight_layout()
    save_figure(fig, path)
