"""What accuracy costs in time: ``penetrate accuracy``.

A scene runs over a grid of discretisation settings, each against a reference:

* **mesh axis**: mesh size x geometry order (flat or quadratic) x normal model
  (``mesh`` or ``exact``), at the finest time setting;
* **quadrature axis**: mesh size x facet quadrature degree (more points per
  facet on the same mesh), at the finest time setting;
* **time axis**: RK4 steps and Dormand-Prince tolerances, at the finest mesh setting;
* **combined**: mesh size x RK4 step with the default geometry, where a user's
  cheapest setting for an accuracy lies;
* **scene**: the scene's own numerics, to show where they sit.

Beside the grid, the report gives the **time convergence on each mesh**: every
RK4 run with the default geometry against the finest step on the same mesh (its
time error alone), the observed order between successive halvings, and the mesh
error of that mesh (its finest step against the reference), where the time error
stops mattering.

The reference is the independent 1-D integration with exact nose entry for a
normal impact without disturbance or effects (its depth is exact to 1e-12);
otherwise the finest RK4 run on the finest mesh, with a Richardson estimate of
its own error from the three finest steps.  For every setting the table gives the relative depth
error, the error of the final axis angle (deg), for unstable scenes the error of
the convergence speed, the integration time and the wall time, and marks the
Pareto front: the settings that no other setting beats in both depth error and
integration time.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from ...reference.normal_impact import is_plain_normal_impact, scene_depth_1d
from ...run import RunStore, convergence_speed, prepare_projectile
from ...scene import InputError, Overrides, Scene
from ...viz.figures import legend_outside, save_figure, subplots
from ..engine.pool import Pool
from ..engine.report import Report, markdown_table, number_cell, write_report
from ..engine.sweep import Sweep, Variation, end_cells, run_sweep
from ..speeds.instability import is_unstable

__all__ = [
    "accuracy_study",
    "time_convergence",
    "default_ladders",
    "DEFAULT_RTOLS",
    "DEFAULT_QUADRATURE_ORDERS",
]

#: the default mesh ladder starts at this many diameters and halves three times (0.04 m for a 95.2 mm body)
SIZE_PER_DIAMETER = 0.42
#: the default step ladder starts at this fraction of the time the body takes to travel its own length at the
#: impact speed, and halves five times (2e-4 s for test 2's 1.4 m at 280 m/s)
STEP_PER_TRANSIT = 1 / 25
DEFAULT_RTOLS = (1e-3, 1e-4, 1e-5, 1e-6)
DEFAULT_QUADRATURE_ORDERS = (4, 6)


def _one_digit(value: float) -> float:
    """``value`` to one significant digit."""
    return float(f"{value:.0e}")


def default_ladders(scene: Scene) -> tuple[list[float], list[float]]:
    """The mesh sizes and RK4 steps of a study of ``scene`` scaled to it: four mesh sizes halving from
    :data:`SIZE_PER_DIAMETER` diameters, six steps halving from :data:`STEP_PER_TRANSIT` of the time the body
    takes to travel its own length at the impact speed (the first of each to one significant digit)."""
    profile = prepare_projectile(scene).profile
    size = _one_digit(SIZE_PER_DIAMETER * 2 * profile.radius)
    step = _one_digit(STEP_PER_TRANSIT * profile.length / scene.impact.speed)
    return [size / 2**k for k in range(4)], [step / 2**k for k in range(6)]


def _settings(
    sizes: Sequence[float],
    steps: Sequence[float],
    rtols: Sequence[float],
    quadrature_orders: Sequence[int] = DEFAULT_QUADRATURE_ORDERS,
) -> list[dict]:
    """The grid: four axes through the finest setting, each refining one thing, plus the product.

    ``mesh``: size x geometry order x normal model at the finest step; ``quadrature``:
    size x quadrature order (second-order geometry, exact normals) at the finest step;
    ``time``: the step (and adaptive tolerances) on the finest mesh; ``combined``: size x
    step with the default geometry, where a user's cheapest setting for an accuracy lies.
    A setting already on an earlier axis is not repeated.
    """
    finest_step, finest_size = min(steps), min(sizes)
    default = {"numerics.geometry_order": 2, "numerics.normals": "exact", "numerics.quadrature_order": 2}
    rk4 = {"numerics.integrator": "rk4"}
    candidates: list[tuple[str, dict[str, object]]] = []
    for size in sizes:
        for order in (1, 2):
            for normals in ("mesh", "exact"):
                candidates.append(
                    (
                        "mesh",
                        {
                            "numerics.mesh_size": size,
                            "numerics.geometry_order": order,
                            "numerics.normals": normals,
                            "numerics.quadrature_order": 2,
                            **rk4,
                            "numerics.time_step": finest_step,
                        },
                    )
                )
    for size in sizes:
        for quadrature in quadrature_orders:
            candidates.append(
                (
                    "quadrature",
                    {
                        "numerics.mesh_size": size,
                        **default,
                        "numerics.quadrature_order": quadrature,
                        **rk4,
                        "numerics.time_step": finest_step,
                    },
                )
            )
    for step in steps:
        candidates.append(("time", {"numerics.mesh_size": finest_size, **default, **rk4, "numerics.time_step": step}))
    for rtol in rtols:
        candidates.append(
            (
                "time",
                {"numerics.mesh_size": finest_size, **default, "numerics.integrator": "dopri54", "numerics.rtol": rtol},
            )
        )
    for size in sizes:
        for step in steps:
            candidates.append(("combined", {"numerics.mesh_size": size, **default, **rk4, "numerics.time_step": step}))
    settings, seen = [], set()
    for axis, values in candidates:
        token = tuple(sorted(values.items()))
        if token not in seen:
            seen.add(token)
            settings.append({"axis": axis, **values})
    return settings


def accuracy_study(
    scene: str | os.PathLike,
    overrides: Overrides | None,
    store: RunStore,
    out: str | os.PathLike,
    sizes: Sequence[float] | None = None,
    steps: Sequence[float] | None = None,
    rtols: Sequence[float] = DEFAULT_RTOLS,
    pool: Pool | None = None,
    quadrature_orders: Sequence[int] = DEFAULT_QUADRATURE_ORDERS,
) -> tuple[pd.DataFrame, dict]:
    """Run the grid, compare with the reference, write ``accuracy.md``, ``.csv`` and ``.png`` into ``out``.

    ``sizes`` and ``steps`` default to ladders scaled to the scene (:func:`default_ladders`).
    """
    if sizes is None or steps is None:
        default_sizes, default_steps = default_ladders(Sweep.from_file(scene, overrides).scenes[0])
        sizes, steps = sizes or default_sizes, steps or default_steps
    settings = _settings(sizes, steps, rtols, quadrature_orders)
    # the scene's own numerics as they are, to show where they sit against the front
    settings.append({"axis": "scene"})
    variations = [Variation({k: v for k, v in s.items() if k != "axis"}) for s in settings]
    try:
        sweep = Sweep.from_file(scene, overrides, variations)
    except InputError as exc:
        raise InputError(f"{exc} (the study's ladders: --sizes {_listed(sizes)}, --steps {_listed(steps)})") from None
    result = run_sweep(sweep, store, pool)
    table = result.table()
    table.insert(0, "axis", [s["axis"] for s in settings])
    if "error" in table and table["error"].notna().any():
        failed = table[table["error"].notna()]
        raise RuntimeError(f"{len(failed)} accuracy runs failed, e.g. {failed['error'].iloc[0]}")
    own = table["axis"] == "scene"
    for name in ("mesh_size", "geometry_order", "normals", "quadrature_order", "integrator", "time_step", "rtol"):
        column = f"numerics.{name}"
        if column not in table:
            table[column] = np.nan
        table[column] = table[column].astype(object)
        table.loc[own, column] = getattr(sweep.scenes[-1].numerics, name)
    # the time axis: RK4 on the finest mesh with the default geometry, on whichever axis each run is
    on_time_axis = (
        (table["axis"] != "scene")
        & (table["numerics.integrator"] == "rk4")
        & (table["numerics.mesh_size"] == min(sizes))
        & (table["numerics.geometry_order"] == 2)
        & (table["numerics.normals"] == "exact")
        & (table["numerics.quadrature_order"] == 2)
    )
    finest = table[on_time_axis].drop_duplicates("key").sort_values("numerics.time_step")
    # the scene counts as unstable when its most accurate run is
    unstable = is_unstable(float(finest["axis_angle_change"].iloc[0]))
    table["convergence_speed"] = [convergence_speed(store.history(k)) if unstable else np.nan for k in table["key"]]
    finest = table.loc[finest.index]
    reference = _reference(sweep, finest)
    table["depth_error"] = (table["depth"] - reference["depth"]).abs() / reference["depth"]
    table["axis_angle_error"] = (table["axis_angle_change"] - reference["axis_angle_change"]).abs()
    table["convergence_speed_error"] = (table["convergence_speed"] - reference["convergence_speed"]).abs()
    is_ref = (table["key"] == finest["key"].iloc[0]) & (reference["kind"] == "finest setting")
    table.loc[is_ref, ["depth_error", "axis_angle_error", "convergence_speed_error"]] = np.nan
    table["pareto"] = _pareto(table["depth_error"].to_numpy(), table["integration_time"].to_numpy())
    _write(table, reference, sweep.scenes[0], Path(out))
    return table, reference


def time_convergence(table: pd.DataFrame) -> pd.DataFrame:
    """RK4's time error on each mesh: each step against the finest step on the same mesh.

    Rows are the RK4 runs with the default geometry (second order, exact normals, degree-2
    quadrature) of an accuracy table, by mesh size and decreasing step.  ``*_time_error`` is the
    difference from the finest step of that mesh (relative for the depth, deg for the axis angle,
    m/s for the convergence speed); ``*_order`` is ``log2`` of the ratio of successive errors (the
    observed order of the halving that reached the row); ``mesh_error`` is the relative depth
    error of that mesh's finest step against the study's reference, the floor below which a
    shorter step buys nothing.
    """
    default = (
        (table["axis"] != "scene")
        & (table["numerics.integrator"] == "rk4")
        & (table["numerics.geometry_order"] == 2)
        & (table["numerics.normals"] == "exact")
        & (table["numerics.quadrature_order"] == 2)
    )
    runs = table[default].drop_duplicates("key")
    rows = []
    for _size, group in runs.groupby("numerics.mesh_size", sort=False):
        group = group.sort_values("numerics.time_step", ascending=False)
        if len(group) < 2:
            continue
        finest = group.iloc[-1]
        for name, column in (
            ("depth", "depth"),
            ("axis_angle", "axis_angle_change"),
            ("convergence_speed", "convergence_speed"),
        ):
            error = (group[column] - finest[column]).abs().to_numpy(dtype=float, copy=True)
            if name == "depth":
                error = error / finest["depth"]
            error[-1] = np.nan
            group = group.assign(**{f"{name}_time_error": error})
            with np.errstate(divide="ignore", invalid="ignore"):
                order = np.log2(error[:-1] / error[1:])
            group = group.assign(**{f"{name}_order": np.concatenate([[np.nan], order])})
        group = group.assign(mesh_error=finest["depth_error"])
        rows.append(group.iloc[:-1])
    columns = [
        "numerics.mesh_size",
        "numerics.time_step",
        "steps",
        "depth_time_error",
        "depth_order",
        "axis_angle_time_error",
        "axis_angle_order",
        "convergence_speed_time_error",
        "convergence_speed_order",
        "mesh_error",
        "integration_time",
    ]
    if not rows:
        return pd.DataFrame(columns=columns)
    return (
        pd.concat(rows)[columns]
        .sort_values(["numerics.mesh_size", "numerics.time_step"], ascending=[False, False])
        .reset_index(drop=True)
    )


def _reference(sweep: Sweep, finest: pd.DataFrame) -> dict:
    """The exact 1-D reference of a plain normal impact, else the finest run with a Richardson estimate."""
    base = sweep.scenes[0]
    if is_plain_normal_impact(base):
        depth = scene_depth_1d(base, prepare_projectile(base))
        return {
            "kind": "1-D integration with exact nose entry and the same contact width (exact)",
            "depth": depth,
            "axis_angle_change": 0.0,
            "convergence_speed": np.nan,
            "depth_uncertainty": 0.0,
        }
    q = finest["depth"].to_numpy()
    reference = {
        "kind": "finest setting",
        "depth": float(q[0]),
        "axis_angle_change": float(finest["axis_angle_change"].iloc[0]),
        "convergence_speed": float(finest["convergence_speed"].iloc[0]),
    }
    if len(q) >= 3 and q[1] != q[2]:
        ratio = (q[2] - q[1]) / (q[1] - q[0]) if q[1] != q[0] else math.inf
        order = math.log2(abs(ratio)) if ratio not in (0, math.inf) and abs(ratio) > 1 else 1.0
        reference["richardson_order"] = order
        reference["depth_uncertainty"] = abs(q[1] - q[0]) / (2**order - 1)
    else:
        reference["depth_uncertainty"] = float("nan")
    return reference


def _listed(values: Sequence[float]) -> str:
    return ",".join(f"{v:g}" for v in values)


def _pareto(error: np.ndarray, cost: np.ndarray) -> np.ndarray:
    """True where no other setting is both at least as accurate and at least as cheap (and better in one)."""
    front = np.zeros(len(error), dtype=bool)
    for i in range(len(error)):
        if not np.isfinite(error[i]):
            continue
        dominated = (error <= error[i]) & (cost <= cost[i]) & ((error < error[i]) | (cost < cost[i]))
        front[i] = not dominated.any()
    return front


def _label(row: pd.Series) -> str:
    quadrature = int(row["numerics.quadrature_order"])
    geometry = (
        f"{row['numerics.mesh_size'] * 1e3:g} mm P{int(row['numerics.geometry_order'])} {row['numerics.normals']}"
        + (f" q{quadrature}" if quadrature != 2 else "")
    )
    if row["numerics.integrator"] == "dopri54":
        return f"{geometry}, dopri rtol {row['numerics.rtol']:g}"
    return f"{geometry}, rk4 {row['numerics.time_step']:g} s"


def _write(table: pd.DataFrame, reference: dict, scene: Scene, out: Path) -> None:
    figures = {"accuracy.png": lambda path: _figure(table, scene, path)}
    write_report(out, Report("accuracy", _markdown(table, reference, scene), table, figures=figures))


def _figure(table: pd.DataFrame, scene: Scene, path: Path) -> None:
    """Each setting's error against its integration time, and the Pareto front."""
    fig, ax = subplots(figsize=(9.5, 5.5))
    for (axis, integrator), group in table.groupby(["axis", "numerics.integrator"]):
        ax.loglog(group["integration_time"], group["depth_error"], "o", label=f"{axis} axis, {integrator}")
    front = table[table["pareto"]].sort_values("integration_time")
    ax.loglog(front["integration_time"], front["depth_error"], "k--", lw=1, label="Pareto front")
    ax.set(
        xlabel="integration time (s)", ylabel="relative depth error (-)", title=f"{scene.name}: accuracy against time"
    )
    ax.grid(alpha=0.3, which="both")
    legend_outside(ax)
    fig.tight_layout()
    save_figure(fig, path)


def _markdown(table: pd.DataFrame, reference: dict, scene: Scene) -> str:
    lines = [
        f"# Accuracy against time: {scene.name or 'scene'}",
        "",
        f"Reference: {reference['kind']}, depth {reference['depth']:.6f} m"
        + (
            f" (Richardson estimate of its own error {reference['depth_uncertainty']:.2g} m)"
            if reference.get("depth_uncertainty")
            else ""
        )
        + ".",
        "",
    ]
    header = [
        "axis",
        "setting",
        "end",
        "surface points",
        "steps",
        "depth (m)",
        "depth error",
        "axis angle error (deg)",
        "convergence speed error (m/s)",
        "integration (s)",
        "wall (s)",
        "Pareto",
    ]
    ends, notes = end_cells([(str(row["end_reason"]), json.loads(row["warnings"])) for _, row in table.iterrows()])
    rows = [
        [
            row["axis"],
            _label(row),
            end,
            row["surface_points"],
            row["steps"],
            number_cell(row["depth"], ".6f"),
            number_cell(row["depth_error"], ".2e"),
            number_cell(row["axis_angle_error"], ".2e"),
            number_cell(row["convergence_speed_error"], ".2g"),
            number_cell(row["integration_time"], ".2f"),
            number_cell(row["wall_time"], ".2f"),
            "yes" if row["pareto"] else "",
        ]
        for (_, row), end in zip(table.iterrows(), ends)
    ]
    lines += markdown_table(header, rows)
    if notes:
        lines += ["", "Warnings (the end column points to them):", "", *[f"{i}. {n}" for i, n in enumerate(notes, 1)]]
    lines += ["", "![depth error against integration time](accuracy.png)", ""]
    lines += _time_convergence_markdown(time_convergence(table))
    return "\n".join(lines)


def _time_convergence_markdown(convergence: pd.DataFrame) -> list[str]:
    if convergence.empty:
        return []
    lines = [
        "## Time convergence on each mesh",
        "",
        "RK4 with the default geometry: each step against the finest step on the same mesh (the time"
        " error alone), the observed order of each halving, and the mesh's own depth error (its finest"
        " step against the reference), below which a shorter step buys nothing.",
        "",
    ]
    header = [
        "mesh",
        "step (s)",
        "steps",
        "depth time error",
        "order",
        "axis angle time error (deg)",
        "order",
        "convergence speed time error (m/s)",
        "order",
        "mesh error (depth)",
        "integration (s)",
    ]
    rows = [
        [
            f"{number_cell(row['numerics.mesh_size'] * 1e3, 'g')} mm",
            number_cell(row["numerics.time_step"], "g"),
            int(row["steps"]),
            number_cell(row["depth_time_error"], ".2e"),
            number_cell(row["depth_order"], ".1f", missing=""),
            number_cell(row["axis_angle_time_error"], ".2e"),
            number_cell(row["axis_angle_order"], ".1f", missing=""),
            number_cell(row["convergence_speed_time_error"], ".2g"),
            number_cell(row["convergence_speed_order"], ".1f", missing=""),
            number_cell(row["mesh_error"], ".2e", missing="reference"),
            number_cell(row["integration_time"], ".2f"),
        ]
        for _, row in convergence.iterrows()
    ]
    lines += [*markdown_table(header, rows), ""]
    return lines
