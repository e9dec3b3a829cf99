"""Off-screen renderings, the animation and the ParaView files of the resistance field (cases.viz).

The scenes are projectile #3 on a coarse mesh (40 mm, RK4 at 40 us): a 1120 m/s run with
1 degree of attack (unstable: the attack angle peaks near 16 degrees, then converges) and a
short purely axial run.  Images are read back pixel by pixel: with lighting off every pixel of
a facet has exactly its colour-map colour, so colours decode to stresses.
"""

from __future__ import annotations

import gc
import json
import subprocess
import sys
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest
from PIL import Image
from scipy.spatial import cKDTree
from support import rss_bytes

import cases.viz.render as render_module
from cases import load_scene, run_scene, scene_path
from cases.cli import main
from cases.scene import InputError
from cases.viz.field import FieldEvaluator, frame_rows, key_instants, resolve_instants
from cases.viz.frames import FrameRenderer, field_ranges, render_animation, render_snapshots
from cases.viz.panels import default_station, plot_polar, ring_stress
from cases.viz.paraview import write_paraview
from cases.viz.render import render_all
from cases.viz.trajectory import render_trajectory, trajectory_rows

COARSE = {"numerics.mesh_size": 0.04, "numerics.integrator": "rk4", "numerics.time_step": 4e-5}
COARSE_SET = ["numerics.mesh_size=0.04", "numerics.integrator=rk4", "numerics.time_step=4e-5"]


@pytest.fixture(scope="module")
def unstable():
    """Projectile #3 at 1120 m/s, 1 degree attack: the whole run."""
    scene = load_scene(scene_path("paper_p3"), {"impact.speed": 1120, **COARSE})
    return FieldEvaluator(run_scene(scene))


@pytest.fixture(scope="module")
def axial():
    """Projectile #3 at 1120 m/s straight along its axis, until the nose and 0.4 m more are in."""
    scene = load_scene(
        scene_path("paper_p3"),
        {"impact.speed": 1120, "impact.attack_angle": 0, "numerics.time_limit": 0.0007, **COARSE},
    )
    return FieldEvaluator(run_scene(scene))


def _decode(image: np.ndarray, renderer: FrameRenderer, name: str = "sigma_n", tolerance: float = 3.0):
    """Stress (MPa) of every pixel of the body whose colour is a colour-map entry, else NaN.

    The colour bar (the right 16 % of the view) is left out.
    """
    lut = renderer.scalar_bars[name]
    colours = np.array([lut.GetTableValue(i)[:3] for i in range(lut.GetNumberOfTableValues())]) * 255.0
    lo, hi = renderer.scalar_bar_range(name)
    distance, index = cKDTree(colours).query(image.reshape(-1, 3).astype(float), distance_upper_bound=tolerance)
    values = lo + (index + 0.5) / len(colours) * (hi - lo)
    values[~np.isfinite(distance)] = np.nan
    values = values.reshape(image.shape[:2])
    values[:, int(0.84 * image.shape[1]) :] = np.nan
    return values


def _facet_normals_world(evaluator: FieldEvaluator, rotation: np.ndarray) -> np.ndarray:
    q = evaluator.prepared.quadrature
    per = evaluator.surface.points_per_facet
    n = (q.normals * q.weights[:, None]).reshape(-1, per, 3).sum(axis=1)
    n /= np.linalg.norm(n, axis=1)[:, None]
    return n @ rotation.T


def _facet_station(evaluator: FieldEvaluator) -> np.ndarray:
    """Distance of each facet's quadrature centroid behind the tip (m)."""
    q = evaluator.prepared.quadrature
    per = evaluator.surface.points_per_facet
    centroid = q.points.reshape(-1, per, 3).mean(axis=1)
    return evaluator.prepared.tip[0] - centroid[:, 0]


def test_the_drawn_field_is_the_integrated_field(unstable):
    """Facet means carry exactly the stress the loads integrate, and the drawn surface is the projectile's."""
    ev = unstable
    rows = key_instants(ev)
    q = ev.prepared.quadrature
    for row in rows.values():
        fld = ev.at(row)
        areas = q.weights.reshape(-1, ev.surface.points_per_facet).sum(axis=1)
        assert np.sum(fld.sigma_n * areas) == pytest.approx(np.sum(fld.point_sigma_n * q.weights), rel=1e-12)
        sigma, _ = ev.loads.stress(fld.position, fld.velocity, fld.rotation, ev.result.trajectory.angular_velocity[row])
        np.testing.assert_array_equal(fld.point_sigma_n, sigma)
    # every facet drawn; flat triangles through the curved surface's nodes: area within 1 % of the exact
    assert set(np.unique(ev.surface.facet)) == set(range(ev.surface.n_facets))
    tri = ev.surface.points[ev.surface.triangles]
    drawn = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
    assert drawn == pytest.approx(q.area, rel=0.01)
    # outward orientation (ParaView's normals): the divergence theorem gives the enclosed volume
    volume = np.einsum("ij,ij->", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])) / 6.0
    assert volume == pytest.approx(q.enclosed_volume(), rel=0.01)
    # the tip of the drawn body is the projectile's tip, at its world position
    tips = ev.world_points(rows["peak"])
    assert np.min(np.linalg.norm(tips - ev.tip(rows["peak"]), axis=1)) < 1e-9


def test_default_instants(unstable):
    ev = unstable
    rows = key_instants(ev)
    h = ev.history
    assert list(rows) == ["embedded", "peak", "converged", "end"]
    assert list(rows.values()) == sorted(rows.values())
    nose = ev.prepared.profile.nose_length
    # the whole nose is in at "embedded" and was not one step earlier
    assert h["tip_depth"].iloc[rows["embedded"]] >= nose * np.cos(np.radians(2.0))
    assert h["tip_depth"].iloc[rows["embedded"] - 1] < nose + 1e-3
    assert h["total_attack_angle"].iloc[rows["peak"]] == pytest.approx(h["total_attack_angle"].max(), rel=1e-12)
    assert h["total_attack_angle"].iloc[rows["peak"]] > 10.0  # unstable at 1120 m/s
    assert h["total_attack_angle"].iloc[rows["converged"]] < 0.1 <= h["total_attack_angle"].iloc[rows["converged"] - 1]
    assert rows["end"] == len(h) - 1
    labelled = resolve_instants(ev, ["peak", "0.01"])
    assert labelled[0] == ("peak attack angle", rows["peak"])
    assert ev.result.trajectory.time[labelled[1][1]] == pytest.approx(0.01, abs=2.1e-5)
    for bad in (["soon"], ["1.0"]):
        with pytest.raises(InputError, match="--times"):
            resolve_instants(ev, bad)


def test_axial_motion_has_no_peak_or_convergence_by_default(axial):
    assert list(key_instants(axial)) == ["embedded", "end"]
    with pytest.raises(InputError, match="no such instant"):
        resolve_instants(axial, ["converged"])


def test_nose_tip_hottest_in_axial_motion(axial):
    """Axial motion: sigma_n = A sigma_0 + B rho_0 (V n_x)^2 falls from the tip along the nose; the shank
    carries none."""
    ev = axial
    fld = ev.at(-1)
    nose = ev.prepared.profile.nose_length
    assert fld.tip_depth > nose + 0.2
    station = _facet_station(ev)
    assert station[np.argmax(fld.sigma_n)] < 0.04  # the tip facets, one mesh size
    bins = np.linspace(0.0, nose, 7)
    means = [fld.sigma_n[(station >= a) & (station < b)].mean() for a, b in zip(bins[:-1], bins[1:])]
    assert all(np.diff(means) < 0), means
    assert np.all(fld.sigma_n[station > nose + 0.04] == 0.0)
    # in the image: the hottest pixels sit at the tip
    with FrameRenderer(ev, (640, 360), side_panel=False, lighting=False) as renderer:
        image = renderer.render(len(ev) - 1)
        values = _decode(image, renderer)
        lo, hi = renderer.scalar_bar_range()
        tip = renderer.to_pixels(ev.tip(len(ev) - 1)[None])[0]
        tail = renderer.to_pixels((ev.tip(len(ev) - 1) - ev.length * fld.rotation[:, 0])[None])[0]
    assert (lo, hi) == pytest.approx((fld.sigma_n.min() * 1e-6, fld.sigma_n.max() * 1e-6), rel=1e-12)
    assert np.nanmax(values) > hi - 2 * (hi - lo) / 256
    rows, cols = np.nonzero(values > lo + 0.9 * (hi - lo))
    assert len(rows) > 3
    body_pixels = np.linalg.norm(tail - tip)
    assert np.max(np.hypot(cols - tip[0], rows - tip[1])) < 0.12 * body_pixels
    assert np.nanmin(values) < lo + 2 * (hi - lo) / 256  # the unloaded shank is in view


def test_windward_side_hotter_than_leeward(unstable):
    """At the peak attack angle the side facing the transverse velocity carries the load, in the field and in
    the image."""
    ev = unstable
    row = key_instants(ev)["peak"]
    fld = ev.at(row)
    axis = fld.rotation[:, 0]
    v = fld.velocity / np.linalg.norm(fld.velocity)
    windward = v - (v @ axis) * axis
    windward /= np.linalg.norm(windward)
    normals = _facet_normals_world(ev, fld.rotation)
    side = normals @ windward
    wind, lee = fld.sigma_n[side > 0.3].mean(), fld.sigma_n[side < -0.3].mean()
    assert wind > 5 * lee
    with FrameRenderer(ev, (640, 360), side_panel=False, lighting=False) as renderer:
        image = renderer.render(row)
        values = _decode(image, renderer)
        tip = ev.tip(row)
        tip_px, tail_px, wind_px = renderer.to_pixels(np.array([tip, tip - ev.length * axis, tip + 0.1 * windward]))
    # split the body's pixels by the projected axis: the windward half is hotter
    along = (tail_px - tip_px) / np.linalg.norm(tail_px - tip_px)
    across = np.array([-along[1], along[0]])
    if (wind_px - tip_px) @ across < 0:
        across = -across
    rows, cols = np.nonzero(np.isfinite(values))
    offset = np.column_stack([cols, rows]) - tip_px
    on_body = (offset @ along > 0) & (offset @ along < np.linalg.norm(tail_px - tip_px))
    signed = offset @ across
    hot_side = values[rows, cols][on_body & (signed > 2)]
    cold_side = values[rows, cols][on_body & (signed < -2)]
    assert len(hot_side) > 200 and len(cold_side) > 200
    assert hot_side.mean() > 3 * cold_side.mean()


def test_snapshots_are_images_of_the_field(unstable, tmp_path):
    """The written PNGs reopen, are not blank, and the colour bar spans the field of each instant."""
    ev = unstable
    instants = resolve_instants(ev, None)
    paths = render_snapshots(ev, tmp_path, instants, size=(800, 400))
    assert [p.name for p in paths] == [
        "field_nose_embedded.png",
        "field_peak_attack_angle.png",
        "field_converged.png",
        "field_end.png",
    ]
    for path in paths:
        image = np.asarray(Image.open(path).convert("RGB"))
        assert image.shape == (400, 800, 3)
        assert image.std() > 20
        assert len(np.unique(image.reshape(-1, 3), axis=0)) > 200
    with FrameRenderer(ev, (480, 240)) as renderer:
        for _, row in instants:
            renderer.render(row)
            sigma = ev.at(row).sigma_n * 1e-6
            # a field without stress (after the exit) gets a range of 1 MPa above its value
            expected = (sigma.min(), sigma.max()) if sigma.max() > sigma.min() else (sigma.min(), sigma.min() + 1)
            assert renderer.scalar_bar_range() == pytest.approx(expected, rel=1e-12)
    trajectory = render_trajectory(ev, tmp_path / "trajectory.png", count=5, size=(700, 350))
    image = np.asarray(Image.open(trajectory).convert("RGB"))
    assert image.shape == (350, 700, 3) and image.std() > 20


@pytest.fixture
def shown(monkeypatch):
    """Every frame a FrameRenderer draws while the test runs: (row, sigma_n colour bar range (MPa), caption)."""
    frames = []
    real = FrameRenderer.render

    def render(self, index, label=""):
        image = real(self, index, label)
        frames.append((index, self.scalar_bar_range("sigma_n"), self.texts["sigma_n"].GetText(2)))
        return image

    monkeypatch.setattr(FrameRenderer, "render", render)
    return frames


def test_the_field_images_of_one_render_share_one_colour_range(unstable, tmp_path, shown):
    """One colour bar for all the images: the min..max over the instants (145.9, 122.9, 93.4 MPa each before)."""
    ev = unstable
    instants = resolve_instants(ev, None)
    render_snapshots(ev, tmp_path, instants, size=(480, 240))
    assert [row for row, _, _ in shown] == [row for _, row in instants]
    ranges = {bar for _, bar, _ in shown}
    assert len(ranges) == 1
    fields = [ev.at(row).sigma_n * 1e-6 for _, row in instants]
    lo, hi = ranges.pop()
    assert (lo, hi) == pytest.approx((min(f.min() for f in fields), max(f.max() for f in fields)), rel=1e-12)
    assert (lo, hi) == pytest.approx(field_ranges(ev, [row for _, row in instants])["sigma_n"], rel=1e-12)
    # the converged instant carries far less than the embedded one, and its image now shows it
    assert fields[2].max() < 0.3 * hi and fields[0].max() == pytest.approx(hi, rel=1e-12)
    assert all("beyond the colour bar" not in caption for _, _, caption in shown)


@pytest.mark.slow  # the default suite keeps within 4 minutes on 2 cores; CI runs it
def test_render_all_draws_every_picture_on_one_range_or_the_given_one(unstable, tmp_path, shown, monkeypatch):
    """Field images, trajectory bodies and animation frames: one range over all they draw; ``colour_range``
    fixes it, and a frame whose field goes beyond it says so."""
    ev = unstable
    bodies = []
    real = render_module.render_trajectory

    def trajectory(evaluator, path, *args, **kwargs):
        bodies.append(kwargs["clim"])
        return real(evaluator, path, *args, size=(350, 175), **kwargs)

    monkeypatch.setattr(render_module, "render_trajectory", trajectory)
    record = render_all(ev.result, tmp_path / "a", ["embedded", "converged"], animation=True, frames=3, size=(320, 160))
    rows = [key_instants(ev)["embedded"], key_instants(ev)["converged"]]
    drawn = rows + list(trajectory_rows(ev)) + list(frame_rows(ev, 3))
    expected = field_ranges(ev, drawn)["sigma_n"]
    assert record["colour_range"] == {"sigma_n": pytest.approx(list(expected), rel=1e-12)}
    assert len(shown) == 2 + 3 and all(bar == pytest.approx(expected, rel=1e-12) for _, bar, _ in shown)
    assert bodies == [pytest.approx(expected, rel=1e-12)]
    assert (tmp_path / "a" / "animation.gif").exists() and (tmp_path / "a" / "trajectory.png").exists()
    shown.clear()
    bodies.clear()
    record = render_all(ev.result, tmp_path / "b", ["embedded", "converged"], size=(320, 160), colour_range=(0, 100))
    assert record["colour_range"] == {"sigma_n": [0.0, 100.0]} and bodies == [(0.0, 100.0)]
    assert [bar for _, bar, _ in shown] == [(0.0, 100.0)] * 2
    embedded = ev.at(rows[0]).sigma_n.max() * 1e-6
    assert f"{embedded:.4g} MPa, beyond the colour bar" in shown[0][2] and "beyond" not in shown[1][2]


@pytest.mark.parametrize("bad", ["600", "0:600:1", "a:b", "600:100", "100:100", "=-5:100", "nan:100", "0:inf", ""])
def test_a_bad_colour_range_is_refused_before_the_run(bad, tmp_path, capsys):
    out = tmp_path / "render"
    option = ["--colour-range" + bad] if bad.startswith("=") else ["--colour-range", bad]
    assert main(["render", str(scene_path("paper_p3")), *option, "--out", str(out)]) == 2
    error = capsys.readouterr().err.strip()
    assert "\n" not in error and "--colour-range" in error and "LO:HI in MPa" in error and "0 <= LO < HI" in error
    assert not out.exists()


def test_a_negative_colour_range_reads_as_an_option_and_is_refused(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["render", str(scene_path("paper_p3")), "--colour-range", "-5:100", "--out", str(tmp_path / "r")])
    assert stop.value.code == 2 and "--colour-range" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


def test_friction_adds_the_tangential_stress_panel(tmp_path):
    scene = load_scene(
        scene_path("paper_p3"),
        {
            "impact.speed": 1120,
            "numerics.time_limit": 0.001,
            "effects.friction.model": "coulomb",
            "effects.friction.coefficient": 0.1,
            **COARSE,
        },
    )
    ev = FieldEvaluator(run_scene(scene))
    fld = ev.at(-1)
    assert fld.tau is not None and fld.tau.max() > 0
    # Coulomb: tau = mu sigma_n |s| / sqrt(|s|^2 + W^2) with the slip |s| = sqrt(|u|^2 - Vn^2) of each point
    # (u = R^T V + omega x r) and the contact width W = 0.005 (|V| + |omega| r_max), about 5.6 m/s against
    # slips of about 1000 m/s: tau is mu sigma_n within 1.6e-5.  The field is the facet average of its
    # points, weighted by sigma_n dS, so tau / (mu sigma_n) lies between its points' |s| / sqrt(|s|^2 + W^2),
    # recomputed here from the state
    tr, quadrature = ev.result.trajectory, ev.prepared.quadrature
    velocity, spin = tr.velocity[-1], tr.angular_velocity[-1]
    u = ev.rotations[-1].T @ velocity + np.cross(spin, quadrature.points)
    slip2 = np.einsum("ij,ij->i", u, u) - np.einsum("ij,ij->i", u, quadrature.normals) ** 2
    width = 0.005 * (np.linalg.norm(velocity) + np.linalg.norm(spin) * np.linalg.norm(quadrature.points, axis=1).max())
    share = np.sqrt(slip2 / (slip2 + width**2)).reshape(len(fld.tau), -1)
    loaded = fld.sigma_n > 0
    ratio = fld.tau[loaded] / (0.1 * fld.sigma_n[loaded])
    assert np.all(ratio >= share.min(axis=1)[loaded] - 1e-12) and np.all(ratio <= share.max(axis=1)[loaded] + 1e-12)
    assert 1 - 2e-5 < ratio.min() < 1 - 1e-6
    assert np.all(fld.tau <= 0.1 * fld.sigma_n)
    with FrameRenderer(ev, (480, 480), side_panel=False) as renderer:
        image = renderer.render(len(ev) - 1)
        assert renderer.scalar_bar_range("tau") == pytest.approx((fld.tau.min() * 1e-6, fld.tau.max() * 1e-6))
    # shared ranges: tau over the instants as sigma_n
    ranges = field_ranges(ev, [len(ev) // 2, len(ev) - 1])
    taus = [ev.at(r).tau * 1e-6 for r in (len(ev) // 2, len(ev) - 1)]
    assert ranges["tau"] == pytest.approx((min(t.min() for t in taus), max(t.max() for t in taus)), rel=1e-12)
    upper, lower = image[:240], image[240:]
    assert upper.std() > 20 and lower.std() > 20


def test_paraview_files_reopen_with_the_same_values(unstable, tmp_path):
    ev = unstable
    written = write_paraview(ev, tmp_path, steps=6)
    assert len(written["surfaces"]) == 6
    for path, row in zip(written["surfaces"], written["rows"]):
        mesh = meshio.read(path)
        fld = ev.at(row)
        np.testing.assert_array_equal(mesh.points, ev.world_points(row))
        np.testing.assert_array_equal(mesh.cells_dict["triangle"], ev.surface.triangles)
        np.testing.assert_array_equal(mesh.cell_data_dict["sigma_n"]["triangle"], ev.cell_values(fld.sigma_n))
        np.testing.assert_array_equal(
            mesh.cell_data_dict["normal_velocity"]["triangle"], ev.cell_values(fld.normal_velocity)
        )
    # the index: one surface (part 0) and the path (part 1) per time, in time order, files present
    root = ET.parse(written["index"]).getroot()
    sets = root.findall("./Collection/DataSet")
    assert len(sets) == 12
    surfaces = [d for d in sets if d.get("part") == "0"]
    times = [float(d.get("timestep")) for d in surfaces]
    assert times == [ev.result.trajectory.time[r] for r in written["rows"]]
    assert times[0] == 0.0 and times[-1] == ev.result.trajectory.time[-1]
    assert all((tmp_path / d.get("file")).exists() for d in sets)
    # what ParaView does with the index: one multiblock (surface, path) per time
    import pyvista as pv

    reader = pv.get_reader(str(written["index"]))
    assert reader.time_values == pytest.approx(times, rel=0, abs=0)
    reader.set_active_time_value(times[3])
    surface, line = reader.read()
    np.testing.assert_array_equal(surface.cell_data["sigma_n"], ev.cell_values(ev.at(written["rows"][3]).sigma_n))
    np.testing.assert_array_equal(line.point_data["speed"], ev.history["speed"].to_numpy())
    path = meshio.read(tmp_path / "trajectory.vtu")
    np.testing.assert_array_equal(path.points, ev.result.trajectory.position)
    assert len(path.cells_dict["line"]) == len(ev) - 1
    for name in ("speed", "attack_angle", "total_attack_angle", "time", "tip_depth"):
        np.testing.assert_array_equal(path.point_data[name], ev.history[name].to_numpy())


def test_animation_gif(unstable, tmp_path):
    record = render_animation(unstable, tmp_path / "run.gif", frames=6, size=(400, 200))
    gif = Image.open(tmp_path / "run.gif")
    assert gif.n_frames == 6 and record["frames"] == 6
    frames = []
    for k in range(6):
        gif.seek(k)
        frames.append(np.asarray(gif.convert("RGB")))
    assert frames[0].shape == (200, 400, 3)
    assert all(np.abs(a.astype(int) - b).mean() > 1 for a, b in zip(frames, frames[1:]))


@pytest.mark.slow  # 9 s of frames: the second CI step
def test_fifty_frames_keep_memory_flat(unstable):
    """Fifty frames in one renderer, and renderers opened and closed, leave the resident memory flat.

    A 480 x 240 frame is 0.35 MB; keeping every frame would add 17 MB, a leaked plotter (OpenGL
    context and buffers) several MB per cycle.  Measured: under 1 MB over the fifty frames, and
    under 0.1 MB per renderer cycle alone; inside the whole suite the allocator once grew 5.4 MB
    over six cycles in one step, so the cycles are judged by their median growth per cycle
    over twelve (a leak grows every cycle; a one-time arena growth moves one of them), against
    1 MB per cycle.
    """
    ev = unstable
    rows = np.linspace(0, len(ev) - 1, 55).astype(int)
    with FrameRenderer(ev, (480, 240)) as renderer:
        for row in rows[:5]:
            renderer.render(int(row))
        gc.collect()
        before = rss_bytes()
        for row in rows[5:]:
            renderer.render(int(row))
        gc.collect()
        grown = rss_bytes() - before
    assert grown < 5e6, f"{grown / 1e6:.1f} MB over 50 frames"
    resident = []
    for k in range(14):
        with FrameRenderer(ev, (240, 120)) as renderer:
            renderer.render(int(rows[k]))
        gc.collect()
        if k >= 1:  # the first cycle sets up what every later one reuses
            resident.append(rss_bytes())
    per_cycle = float(np.median(np.diff(resident)))
    assert per_cycle < 1e6, f"{per_cycle / 1e6:.2f} MB per renderer (median over 12 cycles)"


def test_ring_stress_on_the_nose_is_the_closed_form_and_the_shank_windward(axial, unstable):
    """On the nose in axial motion sigma_n = A sigma_0 + B rho_0 (V n_x)^2 all round; at an attack angle the
    shank is loaded on the windward side (theta = 0) only."""
    ev = axial
    law = ev.result.scene.target.build()
    profile = ev.prepared.profile
    station = 0.5 * profile.nose_length
    row = len(ev) - 1
    theta, sigma = ring_stress(ev, row, station)
    rotation = ev.rotations[row]
    speed_along_axis = ev.result.trajectory.velocity[row] @ rotation[:, 0]
    n_forward, _ = profile.outward_normal(station)
    expected = law.c0 + law.c2 * (speed_along_axis * float(n_forward)) ** 2
    np.testing.assert_allclose(sigma, expected, rtol=1e-6)
    _, shank = ring_stress(ev, row, default_station(ev.prepared))
    assert np.all(shank == 0.0)
    ev = unstable
    theta, sigma = ring_stress(ev, key_instants(ev)["peak"], default_station(ev.prepared))
    assert sigma[0] == sigma.max() > 0
    assert np.all(sigma[np.abs(theta - np.pi) < np.pi / 2 - 0.05] == 0.0)
    with pytest.raises(InputError, match="station"):
        ring_stress(ev, 0, 2.0)


def test_the_polar_plot_says_its_unit_and_its_legend_lies_below(unstable, tmp_path, monkeypatch):
    kept = []
    monkeypatch.setattr("cases.viz.panels.save_figure", lambda figure, path, dpi: kept.append(figure) or path)
    plot_polar(unstable, resolve_instants(unstable, ["peak", "converged"]), tmp_path / "polar.png")
    (figure,) = kept
    figure.canvas.draw()
    (ax,) = figure.axes
    radial = [label.get_text() for label in ax.yaxis.get_ticklabels() if label.get_text()]
    assert len(radial) >= 3 and all(text.endswith(" MPa") for text in radial)
    renderer = figure.canvas.get_renderer()
    legend, disc = ax.get_legend().get_window_extent(renderer), ax.get_window_extent(renderer)
    assert legend.y1 < disc.y0 and legend.y0 >= 0  # under the plot, inside the figure


@pytest.mark.slow  # 5 s: the whole command; the snapshots are tested in the default run
def test_render_command(tmp_path):
    out = tmp_path / "render"
    args = [
        sys.executable,
        "-m",
        "cases.cli",
        "render",
        str(scene_path("paper_p3")),
        "--set",
        "impact.speed=1120",
        "--set",
        "numerics.time_limit=0.004",
        *[a for s in COARSE_SET for a in ("--set", s)],
        "--times",
        "embedded,0.002,end",
        "--out",
        str(out),
        "--paraview",
        "--paraview-frames",
        "3",
        "--animation",
        "--frames",
        "3",
        "--size",
        "640x320",
        "--colour-range",
        "0:400",
        "--json",
    ]
    done = subprocess.run(args, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    record = json.loads(done.stdout)
    assert {p.name for p in out.iterdir()} == {
        "animation.gif",
        "field_nose_embedded.png",
        "field_t2.000ms.png",
        "field_end.png",
        "paraview",
        "polar.png",
        "resistance_centre.png",
        "trajectory.png",
    }
    assert record["paraview_steps"] == 3 and (out / "paraview" / "run.pvd").exists()
    assert record["colour_range"] == {"sigma_n": [0.0, 400.0]}
    bad = subprocess.run(
        args[:5] + ["--times", "soon", "--out", str(tmp_path / "bad")], capture_output=True, text=True, timeout=300
    )
    assert bad.returncode == 2 and "--times" in bad.stderr and "Traceback" not in bad.stderr


@pytest.mark.slow  # the default suite keeps within 4 minutes on 2 cores; CI runs it
def test_surface_the_target_cannot_reach_is_drawn_apart(tmp_path):
    """The finned body thrown in pitching (300 rad/s), so that it meets the soil at an angle: the facets its fins and
    shank hide (fem_loads.exposure) are grey in the picture, not a stress colour, and the caption says so."""
    scene = load_scene(
        scene_path("finned_test2"),
        {"impact.speed": 600.0, "impact.angular_velocity": [0.0, 300.0, 0.0], "numerics.time_limit": 0.004},
    )
    ev = FieldEvaluator(run_scene(scene))
    row = max(range(len(ev)), key=lambda index: int(ev.at(index).hidden.sum()))
    fld = ev.at(row)
    assert fld.hidden.sum() >= 10
    from cases.viz.frames import HIDDEN_COLOUR

    with FrameRenderer(ev, (960, 480)) as renderer:
        renderer.render(row)
        drawn = renderer.meshes["sigma_n"].cell_data["sigma_n"]
        caption = renderer.texts["sigma_n"].GetText(2)
        nan_colour = renderer.actors["sigma_n"].mapper.lookup_table.nan_color
    assert np.isnan(drawn).sum() == ev.cell_values(fld.hidden).sum() > 0
    assert "grey: hidden by the body ahead" in caption
    assert tuple(nan_colour.float_rgb) == pytest.approx(HIDDEN_COLOUR, abs=1 / 255)  # stored as bytes
