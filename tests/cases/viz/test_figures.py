"""Every matplotlib figure the project draws: each axis says its unit, and no legend covers data.

The figures are drawn from synthetic inputs (no runs): each figure function is called as its study
calls it, the figure is kept as it is saved (``save_figure`` wrapped), and then measured in display
coordinates.  A legend covers data when its box, where it overlaps an axes' data area, meets a
plotted line, marker or band (the filled polygon of a probability band, not only its vertices).
"""

from __future__ import annotations

import re
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from matplotlib.path import Path as MplPath
from matplotlib.transforms import Bbox

import cases.viz.figures as figures_module
from cases.studies.ensemble import study as ensemble_study
from cases.studies.ensemble.sampling import Distribution, wilson_interval
from cases.studies.measured import compare, validate
from cases.studies.measured.fit_report import FitResult, write_fit
from cases.studies.numerics import accuracy
from cases.studies.paper import figures as paper
from cases.studies.reduced.turn_boundary import TurnBoundary
from cases.viz import panels
from cases.viz.figures import axis_label, legend_outside, quantity_unit, subplots

UNIT = re.compile(r"\(\S.*\)$")  # "speed (m/s)", "probability (-)"


def _history(n: int = 200, turn: float = 1.0) -> pd.DataFrame:
    """A run's history that curves and slows down: every column the figures read (SI, angles in deg)."""
    t = np.linspace(0.0, 0.04, n)
    speed = 1100.0 * (1 - t / 0.05)
    heading = turn * np.radians(120.0) * (t / t[-1]) ** 2
    step = speed * np.gradient(t)
    x, z = np.cumsum(step * np.sin(heading)), -np.cumsum(step * np.cos(heading))
    attack = 15.0 * turn * np.sin(np.pi * t / t[-1]) * np.exp(-3 * t / t[-1])
    return pd.DataFrame(
        {
            "time": t,
            "speed": speed,
            "position_x": x,
            "position_z": z,
            "tip_depth": -z + 0.3,
            "axis_angle": np.degrees(heading) + attack,
            "attack_angle": attack,
            "total_attack_angle": np.abs(attack),
            "moment_y": 4e4 * attack,
            "moment_z": 1e3 * np.cos(40 * t),
            "resistance_centre_from_tip": 0.3 + 0.2 * np.tanh(attack),
        }
    )


class _Study:
    """What the paper's figures ask of a study: a run's history by key."""

    def __init__(self, histories: dict[str, pd.DataFrame]) -> None:
        self.histories = histories

    def history(self, key: str) -> pd.DataFrame:
        return self.histories[key]


def _curve_record() -> dict:
    """An ensemble's record by impact speed, as docs/ensembles/scale_1 has it: 36 runs a bin, the unstable and
    exited fractions rising and crossing the stopped one, with their 95 % Wilson bands over the whole plot."""
    unstable = [4, 3, 8, 10, 12, 14, 17, 17, 20, 21, 21, 25, 25, 25]
    exited = [0, 0, 0, 0, 1, 6, 14, 17, 20, 21, 21, 25, 25, 25]
    bins = []
    for k, (u, e) in enumerate(zip(unstable, exited)):
        counts = {"unstable": u, "exited": e, "stopped": 36 - e, "failed": 0}
        entry = {"bin": [700.0 + 50 * k, 750.0 + 50 * k], "runs": 36, "finished": 36}
        entry.update({o: c / 36 for o, c in counts.items()})
        entry["interval"] = {o: [float(v) for v in wilson_interval(c, 36)] for o, c in counts.items()}
        bins.append(entry)
    return {"by": "impact.speed", "curve": bins}


@pytest.fixture(scope="module")
def every_figure(tmp_path_factory):
    """Every figure the figure functions below save, drawn once (each module's ``save_figure`` wrapped to keep
    the figure; the files are still written)."""
    kept = []
    real = figures_module.save_figure

    def keep(figure, path, *args, **kwargs):
        kept.append(figure)
        return real(figure, path, *args, **kwargs)

    out = tmp_path_factory.mktemp("figures")
    with pytest.MonkeyPatch.context() as patch:
        for module in (figures_module, ensemble_study, compare, accuracy, paper, panels):
            patch.setattr(module, "save_figure", keep)
        _draw_every_figure(out)
    return out, kept


def _over_data(ax) -> dict:
    """A legend box centred on a point of ``ax``'s first curve: it covers data by construction."""
    xy = ax.lines[0].get_xydata()
    point = xy[np.all(np.isfinite(xy), axis=1)][len(xy) // 2]
    return {"loc": "center", "bbox_to_anchor": tuple(ax.transAxes.inverted().transform(ax.transData.transform(point)))}


def _draw_every_figure(tmp_path) -> None:
    """Every figure function of cases.studies and cases.viz that needs no run."""
    h = _history()
    study = _Study({"a": h, "b": _history(turn=0.5), "c": _history(turn=0.0)})
    runs = [("Lc/L = 56 %", "a"), ("Lc/L = 50 %", "b"), ("stable", "c")]
    ensemble_study._curve_figure(_curve_record(), tmp_path / "curve.png")
    table = pd.DataFrame(
        {
            "impact.speed": np.linspace(700, 1400, 40),
            "target.law.B": np.linspace(1.1, 1.3, 40),
            "depth": np.linspace(2, 5, 40),
            "axis_angle_change": np.linspace(0, 90, 40),
        }
    )
    samples = [
        Distribution("impact.speed", "uniform", (700.0, 1400.0)),
        Distribution("target.law.B", "uniform", (1.1, 1.3)),
    ]
    ensemble_study._histograms(table, samples, tmp_path / "histograms.png")
    result = SimpleNamespace(runs=[SimpleNamespace(failed=False)] * 3, history=lambda i: study.history("abc"[i]))
    laws = ["soil", "sand", "clay"]
    x = np.linspace(0.0, 1.0, 50)
    by_speed = pd.DataFrame(
        {"law": np.repeat(laws, 3), "impact.speed": np.tile([300.0, 500.0, 700.0], 3), "depth": np.arange(9.0)}
    )
    comparison = compare.LawComparison(
        pd.DataFrame({"law": laws}), result, by_speed, dict.fromkeys(laws, (x, 10000000.0 * (1.0 - x)))
    )
    compare._figure(comparison, tmp_path / "compare.png")
    paper.angle_figure(study, runs, "three runs", tmp_path / "angles.png")
    paper.history_figure(study, runs, 0.45, "three runs", tmp_path / "histories.png")
    ratios = [0.45, 0.5, 0.56, 0.6]
    fit = {"slope": 800.0, "intercept": 700.0, "r2": 0.98}
    paper.speeds_figure(
        ratios,
        [1060, 1100, 1150, 1180],
        [300, 320, 330, None],
        {"critical": fit, "convergent": fit},
        tmp_path / "s.png",
    )
    boundary = TurnBoundary([1, 5, 10, 20], [1500, 1200, 900, None], [1400, 1000, 800, 700], 700.0, 20.0)
    unstable = [SimpleNamespace(unstable=True, key=key, speed=1100.0 + 50 * k) for k, key in enumerate("ab")]
    paper.boundary_figure(study, boundary, unstable, tmp_path / "boundary.png")
    paper.variants_figure(ratios, {"paper": [300, 320, 330, 340], "blunt": [280, None, 310, 330]}, tmp_path / "v.png")
    prepared = SimpleNamespace(length=0.93, mass=SimpleNamespace(centre_from_tip=0.45))
    panels.plot_histories(h, prepared, tmp_path / "resistance_centre.png", [("peak", 60), ("", 150)])
    errors = pd.DataFrame(
        {
            "axis": ["time", "time", "mesh", "mesh"],
            "numerics.integrator": ["rk4"] * 4,
            "integration_time": [0.5, 2.0, 1.0, 4.0],
            "depth_error": [1e-2, 1e-3, 5e-3, 1e-4],
            "pareto": [True, False, True, True],
        }
    )
    with pytest.MonkeyPatch.context() as patch:  # the table's markdown needs a reference run: not drawn
        patch.setattr(accuracy, "_markdown", lambda *args: "")
        accuracy._write(errors, {}, SimpleNamespace(name="p3"), tmp_path / "accuracy")
    observations = [
        {
            "scene": "p3.toml",
            "quantity": q,
            "impact_speed": 1200.0,
            "observed": v,
            "sigma": 0.1,
            "fitted": 1.02 * v,
            "residual": 0.2,
        }
        for q, v in (("depth", 5.5), ("final_speed", 180.0))
    ]
    shots = [
        {"label": f"v{v}", "group": g, "quantity": "depth", "impact_speed": v, "predicted": d * 1.1, "measured": d}
        for g, v, d in (("51 MPa", 405.0, 0.37), ("51 MPa", 1009.0, 1.75), ("23 MPa", 600.0, 1.2))
    ]
    curve = {"impact_speed": [405.0, 700.0, 1009.0], "depth": [0.4, 1.0, 1.9]}
    validate.figure(shots, {"": {"51 MPa": curve}}, tmp_path / "validate.png")
    write_fit(
        FitResult({"target.law.B": 1.2}, {"target.law.B": 0.01}, None, observations, 2, 0, 5, 0.1), tmp_path, "p3"
    )


def _visible_tick_labels(axis) -> bool:
    return any(label.get_visible() and label.get_text() for label in axis.get_ticklabels())


def _paths_of(ax):
    """(display-space path, filled) of every line, marker set and band of ``ax``."""
    for line in ax.lines:
        xy = line.get_xydata()
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if len(xy):
            yield MplPath(line.get_transform().transform(xy)), False
    for collection in ax.collections:
        transform = collection.get_transform()
        for path in collection.get_paths():
            yield transform.transform_path(path), True


def _covered(figure) -> list[str]:
    """What any legend of ``figure`` covers: ``legend label -> axes title`` of each plotted item it meets."""
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    legends = [ax.get_legend() for ax in figure.axes if ax.get_legend() is not None] + list(figure.legends)
    found = []
    for legend in legends:
        box = legend.get_window_extent(renderer)
        for ax in figure.axes:
            inside = Bbox.intersection(box, ax.get_window_extent(renderer))
            if inside is None or inside.width <= 0 or inside.height <= 0:
                continue  # the legend lies outside this axes: the data, clipped to it, cannot be under it
            for path, filled in _paths_of(ax):
                if path.intersects_bbox(inside, filled=filled):
                    found.append(f"legend over data in {ax.get_title()!r}")
    return found


def test_the_helpers_label_units_from_the_project_records():
    assert quantity_unit("impact.speed") == "m/s"  # the scene schema
    assert quantity_unit("depth") == "m" and quantity_unit("critical_velocity") == "m/s"
    assert quantity_unit("attack_angle") == "deg"  # the history's units
    assert axis_label("target.law.B", quantity_unit("target.law.B")) == "target.law.B (-)"
    assert axis_label("probability", "") == "probability (-)"
    assert quantity_unit("no.such.key") is None and axis_label("x", None) == "x"


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_every_axis_of_every_figure_says_its_unit(every_figure):
    out, drawn = every_figure
    assert len(drawn) == 12
    missing = []
    for figure in drawn:
        figure.canvas.draw()
        for ax in figure.axes:
            if not ax.get_visible() or ax.name == "polar":
                continue
            for axis, label in ((ax.xaxis, ax.get_xlabel()), (ax.yaxis, ax.get_ylabel())):
                # an axis without tick labels (the upper panels of a shared x) needs no label
                if _visible_tick_labels(axis) and not UNIT.search(label):
                    missing.append(f"{ax.get_title()}: {label!r}")
    assert not missing, missing
    assert {p.name for p in out.glob("*.png")} >= {"curve.png", "compare.png", "fit.png", "resistance_centre.png"}
    histograms = drawn[1]
    assert [ax.get_xlabel() for ax in histograms.axes[:4]] == [
        "impact.speed (m/s)",
        "target.law.B (-)",
        "depth (m)",
        "axis_angle_change (deg)",
    ]
    fit = drawn[-1]  # depth (m) and final_speed (m/s): no unit shared, each point says its own
    assert fit.axes[0].get_xlabel() == "observed (each point's unit)"
    assert {t.get_text() for t in fit.axes[0].texts} == {"p3: depth (m)", "p3: final_speed (m/s)"}


def test_no_legend_covers_data(every_figure):
    _, drawn = every_figure
    with_legends = [f for f in drawn if any(ax.get_legend() for ax in f.axes) or f.legends]
    assert len(with_legends) == 10  # all but the histograms and the fit's scatter
    for figure in with_legends:
        assert not _covered(figure), figure.axes[0].get_title()
        # and the legend is not cut off instead: it lies inside the saved figure
        renderer = figure.canvas.get_renderer()
        for ax in figure.axes:
            if ax.get_legend() is not None:
                box = ax.get_legend().get_window_extent(renderer)
                assert box.x1 <= figure.bbox.x1 + 1 and box.y0 >= -1, ax.get_title()


def test_the_ensemble_curve_legend_clears_the_bands(every_figure):
    """The known gap: with ``loc="best"`` the legend sat on the bands (matplotlib's "best" weighs the
    lines, not the filled bands); now it lies right of the axes."""
    figure = every_figure[1][0]
    ax = figure.axes[0]
    assert ax.get_xlabel() == "impact.speed (m/s)" and ax.get_ylabel() == "probability (-)"
    assert len(ax.collections) == 3 and not _covered(figure)  # three bands (no run failed), none under the legend
    legend = ax.get_legend()
    try:
        ax.legend(fontsize=8, **_over_data(ax))  # the check is not vacuous
        assert _covered(figure)
    finally:
        ax.legend_ = legend


def test_the_history_legends_clear_their_curves(every_figure):
    """The resistance centre and moment panels of resistance_centre.png: legends right of the panels."""
    figure = next(f for f in every_figure[1] if f.axes[0].get_title().startswith("resistance centre (R"))
    centre_ax, moment_ax, _ = figure.axes
    assert centre_ax.get_legend() is not None and moment_ax.get_legend() is not None
    assert not _covered(figure)
    legend = moment_ax.get_legend()
    try:
        moment_ax.legend(fontsize=8, **_over_data(moment_ax))  # the check is not vacuous
        assert _covered(figure)
    finally:
        moment_ax.legend_ = legend


def test_legend_outside_places_right_of_the_axes():
    figure, ax = subplots(figsize=(5, 3))
    ax.plot([0, 1], [0, 1], label="a line (m)")
    legend = legend_outside(ax)
    figure.tight_layout()
    figure.canvas.draw()
    box = legend.get_window_extent(figure.canvas.get_renderer())
    assert box.x0 > ax.get_window_extent().x1


def test_the_check_sees_a_band_under_a_legend():
    """A legend over the inside of a band, far from its edges and from any line, covers data."""
    figure, ax = subplots(figsize=(5, 3))
    ax.fill_between([0.0, 1.0], [0.0, 0.0], [1.0, 1.0], alpha=0.2, label="band")
    ax.set(xlim=(-0.5, 1.5), ylim=(-0.5, 1.5))
    ax.legend(loc="center")
    assert _covered(figure)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0))
    assert not _covered(figure)
