"""The tables of docs/accuracy.md, from the studies' own results (``accuracy.csv``).

Run from the repository root, after ``penetrate accuracy ... --out docs/accuracy/NAME``::

    python -m docs.accuracy.tables mesh docs/accuracy/test2      # error by mesh, geometry, points
    python -m docs.accuracy.tables time docs/accuracy/test2      # the time axis on the finest mesh
    python -m docs.accuracy.tables shipped docs/accuracy/test2 docs/accuracy/test5 ...

The figures come from the CSV each study writes beside its report, so the page and the study
cannot disagree.  Times carry their unit (``s``): they are the machine's, and the docs check
skips them; errors are printed to two digits.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

from cases.studies import end_cells
from cases.studies.numerics.accuracy import time_convergence
from docs.measure import stamp


def _points_per_facet(degree: float) -> int:
    """Points per triangle of the facet quadrature of ``degree``: scikit-fem's rule, as fem_loads.quadrature uses."""
    from skfem.quadrature import get_quadrature
    from skfem.refdom import RefTri

    return get_quadrature(RefTri, int(degree))[0].shape[1]


def _read(study: Path) -> tuple[pd.DataFrame, str]:
    table = pd.read_csv(study / "accuracy.csv")
    reference = next(line for line in (study / "accuracy.md").read_text().splitlines() if line.startswith("Reference:"))
    return table, reference


def _error(value: float) -> str:
    return "-" if not np.isfinite(value) else ("0" if value == 0 else f"{value:.1e}")


def _orders(errors: list[float]) -> str:
    """log2 of successive ratios: the observed order of each halving of the mesh size."""
    orders = [
        math.log2(a / b) for a, b in zip(errors, errors[1:]) if np.isfinite(a) and np.isfinite(b) and a > 0 and b > 0
    ]
    return ", ".join(f"{o:.1f}" for o in orders)


def _turns(table: pd.DataFrame) -> bool:
    return bool((table["axis_angle_error"].fillna(0) > 0).any())


def mesh(study: Path) -> None:
    """Depth (and axis-turn) error at the finest step against mesh size, for each geometry and quadrature."""
    table, reference = _read(study)
    rows = table[table["axis"].isin(["mesh", "quadrature"])]
    sizes = sorted(rows["numerics.mesh_size"].unique(), reverse=True)
    step = rows["numerics.time_step"].iloc[0]
    turns = _turns(table)
    print(
        f"{reference} Each cell: the setting's relative depth error at RK4 {step:g} s"
        + (
            "; in brackets, its axis-turn error (deg), marked ~: round-off alone (another processor's, or the impact"
            " speed 1e-13 apart) moves a turning run's axis by up to about 1e-3 deg on the coarse meshes."
            if turns
            else "."
        )
    )
    print()
    print("| normals, order, points per facet | " + " | ".join(f"{s * 1e3:g} mm" for s in sizes) + " | order |")
    print("|---|" + "---|" * (len(sizes) + 1))
    keys = ["numerics.normals", "numerics.geometry_order", "numerics.quadrature_order"]
    order = {("mesh", 1): 0, ("exact", 1): 1, ("mesh", 2): 2, ("exact", 2): 3}
    groups = sorted(rows.groupby(keys), key=lambda g: (g[0][2], order[(g[0][0], int(g[0][1]))]))
    for (normals, geometry, quadrature), group in groups:
        by_size = group.set_index("numerics.mesh_size")
        depth = [float(by_size["depth_error"].get(s, np.nan)) for s in sizes]
        cells = []
        for s, d in zip(sizes, depth):
            if s not in by_size.index:
                cells.append("")
            elif not np.isfinite(d):  # the finest setting is the reference of a non-plain scene
                cells.append("reference")
            else:
                turn = _error(float(by_size.loc[s, "axis_angle_error"]))
                cells.append(_error(d) + (f" ({'~' if turn[0].isdigit() else ''}{turn})" if turns else ""))
        label = (
            f"{normals}, P{int(geometry)}"
            + (" (flat facets)" if geometry == 1 and normals == "mesh" else "")
            + f", {_points_per_facet(quadrature)}"
        )
        # flat facets with their own normals do not converge to the exact surface: no order
        orders = "" if (geometry == 1 and normals == "mesh") else _orders(depth)
        print(f"| {label} | " + " | ".join(cells) + f" | {orders} |")


def time(study: Path) -> None:
    """The time axis on the finest mesh, and RK4's time error alone on every mesh."""
    table, reference = _read(study)
    finest = table["numerics.mesh_size"].min()
    axis = table[table["axis"] == "time"].copy()
    axis["order"] = axis["numerics.integrator"].map({"rk4": 0, "dopri54": 1})
    axis = axis.sort_values(["order", "numerics.time_step", "numerics.rtol"], ascending=[True, False, False])
    turns = _turns(table)
    unstable = table["convergence_speed"].notna().any()
    print(f"{reference} On the {finest * 1e3:g} mm mesh (P2, exact normals, 3 points per facet):")
    print()
    print(
        "| integrator | end | steps | energy retakes | depth error | "
        + ("axis-turn error (deg) | " if turns else "")
        + ("convergence-speed error (m/s) | " if unstable else "")
        + "integration |"
    )
    print("|---|---|---|---|---|" + ("---|" if turns else "") + ("---|" if unstable else "") + "---|")
    ends, notes = end_cells([(str(row["end_reason"]), json.loads(row["warnings"])) for _, row in axis.iterrows()])
    for (_, row), end in zip(axis.iterrows(), ends):
        setting = (
            f"RK4 {row['numerics.time_step']:g} s"
            if row["numerics.integrator"] == "rk4"
            else f"Dormand-Prince rtol {row['numerics.rtol']:g}"
        )
        cells = [setting, end, str(int(row["steps"])), str(int(row["energy_rejections"])), _error(row["depth_error"])]
        if turns:
            cells.append(_error(row["axis_angle_error"]))
        if unstable:
            cells.append(_error(row["convergence_speed_error"]))
        cells.append(f"{row['integration_time']:.2f} s")
        print("| " + " | ".join(cells) + " |")
    if notes:
        print()
        print("Warnings: " + " ".join(f"[{i}] {note}." for i, note in enumerate(notes, 1)))
    convergence = time_convergence(table)
    steps = sorted(convergence["numerics.time_step"].unique(), reverse=True)
    print()
    print(
        "RK4's time error alone, each step against the finest step on the same mesh: relative depth"
        + (" / axis turn (deg)" if turns else "")
        + "; the last column is the mesh's own depth error."
    )
    print()
    print("| mesh | " + " | ".join(f"{h:g} s" for h in steps) + " | mesh error |")
    print("|---|" + "---|" * (len(steps) + 1))
    for size, group in convergence.groupby("numerics.mesh_size", sort=False):
        group = group.set_index("numerics.time_step")
        cells = []
        for h in steps:
            if h not in group.index:
                cells.append("")
                continue
            cell = _error(group.loc[h, "depth_time_error"])
            if turns:
                cell += f" / {_error(group.loc[h, 'axis_angle_time_error'])}"
            cells.append(cell)
        mesh_error = group["mesh_error"].iloc[0]
        print(
            f"| {size * 1e3:g} mm | "
            + " | ".join(cells)
            + f" | {'reference' if not np.isfinite(mesh_error) else _error(mesh_error)} |"
        )
    print()
    print(stamp())


def shipped(studies: list[Path]) -> None:
    """Each study's scene at its own shipped numerics: what the shipped settings cost and miss."""
    print(
        "| scene | shipped numerics | steps | depth error | axis-turn error (deg) | convergence-speed error (m/s) "
        "| integration |"
    )
    print("|---|---|---|---|---|---|---|")
    for study in studies:
        table, _ = _read(study)
        row = table[table["axis"] == "scene"].iloc[0]
        numerics = (
            f"{float(row['numerics.mesh_size']) * 1e3:g} mm, P{int(float(row['numerics.geometry_order']))}, "
            f"{row['numerics.normals']} normals, {_points_per_facet(float(row['numerics.quadrature_order']))}"
            " points per facet, "
        )
        numerics += (
            f"Dormand-Prince rtol {float(row['numerics.rtol']):g}"
            if row["numerics.integrator"] == "dopri54"
            else f"RK4 {float(row['numerics.time_step']):g} s"
        )
        print(
            f"| {study.name} | {numerics} | {int(row['steps'])} | {_error(row['depth_error'])} | "
            f"{_error(row['axis_angle_error']) if _turns(table) else '-'} | {_error(row['convergence_speed_error'])} | "
            f"{row['integration_time']:.2f} s |"
        )
    print()
    print(stamp())


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("table", choices=["mesh", "time", "shipped"])
    parser.add_argument("studies", nargs="+", type=Path, help="the --out directories of `penetrate accuracy`")
    options = parser.parse_args(argv)
    if options.table == "shipped":
        shipped(options.studies)
    else:
        for study in options.studies:
            (mesh if options.table == "mesh" else time)(study)


if __name__ == "__main__":
    main()
