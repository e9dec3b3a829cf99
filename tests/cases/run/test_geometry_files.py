"""Scenes whose projectile is a CAD or mesh file (issue: any projectile): the same shots as the analytic
scenes, from files written by gmsh's own primitives (docs/geometry/cad_bodies.py), through the scene, the run and the
command line."""

from __future__ import annotations

import functools
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cases import load_scene, run_scene, scene_path, summarise
from cases.run import prepare_projectile
from cases.scene import InputError
from docs.geometry.cad_bodies import VALIDATION, write_body, write_volume_mesh

TEST2 = scene_path("forrestal_luk_test2")


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("scene_bodies")


def from_file(geometry: dict, **extra):
    """Test 2 with its projectile from a file (the scene's mass, 23.1 kg, kept)."""
    return load_scene(TEST2, {"projectile.geometry": geometry, **extra})


@functools.lru_cache
def analytic(nose: tuple = ()):
    scene = load_scene(TEST2, {"projectile.nose": dict(nose)} if nose else {})
    result = run_scene(scene)
    return result.prepared.mass, summarise(result).depth, result.prepared.profile


def assert_same_shot(scene, nose: tuple = (), mass_tol: float = 1e-4, depth_tol: float = 1e-3) -> float:
    props, depth, _ = analytic(nose)
    result = run_scene(scene)
    got = result.prepared.mass
    assert got.mass == pytest.approx(props.mass, rel=mass_tol)
    assert got.centre_from_tip == pytest.approx(props.centre_from_tip, rel=mass_tol)
    assert got.axial_inertia == pytest.approx(props.axial_inertia, rel=mass_tol)
    assert got.transverse_inertia == pytest.approx(props.transverse_inertia, rel=mass_tol)
    got_depth = summarise(result).depth
    assert got_depth == pytest.approx(depth, rel=depth_tol)
    return got_depth / depth - 1.0


def test_step_file_in_millimetres_is_test_2(folder):
    """The acceptance: a STEP file (millimetres) of the validation body gives the analytic scene's mass
    properties within 1e-4 and its depth within 0.1 % (measured: +3.8e-4 at the shipped 20 mm mesh, with
    the CAD surfaces' exact normals; the analytic scene itself is 4e-4 short of the 1-D reference)."""
    path = write_body(folder / "body.step", scale=1e-3)
    assert_same_shot(from_file({"file": str(path), "unit": "mm"}))


@pytest.mark.slow
def test_cone_step_file_is_the_cone_scene(folder):
    path = write_body(folder / "cone.step", half_angle=12.0)
    assert_same_shot(from_file({"file": str(path)}), nose=(("shape", "cone"), ("half_angle", 12.0)))


@pytest.mark.slow
@pytest.mark.parametrize("suffix", [".msh", ".vtu"])
def test_volume_mesh_is_test_2(folder, suffix):
    """A second-order mesh of 10 mm tetrahedra with its own normals (measured: -0.056 % in depth)."""
    path = write_volume_mesh(folder / f"body{suffix}", 0.01)
    assert_same_shot(from_file({"file": str(path)}, **{"numerics.normals": "mesh"}))


def test_relative_file_is_found_beside_the_scene(folder, monkeypatch, tmp_path):
    write_body(folder / "beside.step")
    scene_file = folder / "beside.toml"
    scene_file.write_text(
        TEST2.read_text()
        .replace("diameter = 0.0952", 'geometry = { file = "beside.step" }\n#')
        .replace("length = 1.4 ", "# length")
        .replace("nose = {", "# nose = {")
    )
    monkeypatch.chdir(tmp_path)
    scene = load_scene(scene_file)
    assert Path(scene.projectile.geometry.file) == folder / "beside.step"
    prepared = prepare_projectile(scene)
    assert prepared.length == pytest.approx(VALIDATION["length"], rel=1e-9)
    assert prepared.diameter == pytest.approx(VALIDATION["diameter"], rel=1e-6)


def test_a_changed_file_is_not_silently_reused(folder):
    """The scene records the file's digest: a run, a stored run or a sweep never mixes two versions."""
    path = write_body(folder / "changing.step")
    scene = from_file({"file": str(path)})
    digest = scene.projectile.geometry.sha256
    write_body(path, scale=1.0, length=1.2)
    assert from_file({"file": str(path)}).projectile.geometry.sha256 != digest


def penetrate(*args):
    return subprocess.run([sys.executable, "-m", "cases.cli", *args], capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda f: f / "nowhere.step", "nowhere.step': cannot read it"),
        (lambda f: write_body(f / "huge.step", scale=1e-3), r'unit = "m": the body is 1400 m across.*say unit = "mm"'),
        (
            lambda f: f / "body.dxf",
            r"projectile.geometry: file = .*body.dxf': not a CAD or mesh file \(allowed suffixes",
        ),
    ],
)
def test_bad_geometry_is_one_line_and_exit_2(folder, tmp_path, make, message):
    path = make(folder)
    done = penetrate(
        "run", str(TEST2), "--set", f'projectile.geometry={{file = "{path}"}}', "--out", str(tmp_path / "o")
    )
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert "projectile.geometry" in done.stderr
    assert re.search(message, done.stderr), done.stderr
    assert not (tmp_path / "o").exists()


def test_exact_normals_need_a_cad_file(folder):
    path = write_volume_mesh(folder / "n.msh", 0.03)
    with pytest.raises(
        InputError, match=r"numerics.normals = 'exact'.*a mesh file has none: set numerics.normals = 'mesh'"
    ):
        prepare_projectile(from_file({"file": str(path)}))


@pytest.mark.slow  # 7 s: three meshes and runs
def test_flat_facets_come_with_their_error(folder):
    """A first-order mesh with its own (flat-facet) normals runs, and its summary says what that costs; the
    statement's figure for 20 mm facets (7 % short on test 2) is held to what a run measures."""
    path = write_volume_mesh(folder / "flat.msh", 0.02, order=1)
    summary = summarise(
        run_scene(from_file({"file": str(path)}, **{"numerics.normals": "mesh", "numerics.geometry_order": 1}))
    )
    assert any("flat facets" in w and "7 % short at 20 mm" in w for w in summary.warnings)
    assert summary.depth / analytic()[1] - 1.0 == pytest.approx(-0.072, abs=0.01)
    assert not any("flat facets" in w for w in summarise(run_scene(load_scene(TEST2))).warnings)


@pytest.mark.slow
def test_a_file_body_renders_its_field(folder, tmp_path):
    """Rendering needs no profile: the snapshots, the polar plot (the body's own surface points at the
    station, all round) and the ParaView files of a STEP body; on the nose in axial motion the ring's
    stress is the closed form A sigma_0 + B rho_0 (V n_x)^2 for the normals across the ring's band."""
    from cases.viz.field import FieldEvaluator
    from cases.viz.panels import ring_stress

    path = write_body(folder / "render.step", scale=1e-3)
    result = run_scene(from_file({"file": str(path), "unit": "mm"}))
    evaluator = FieldEvaluator(result)
    row = len(evaluator) // 2
    station = 0.5 * result.prepared.nose_length
    theta, sigma = ring_stress(evaluator, row, station)
    assert len(theta) > 20 and np.all(np.diff(theta) >= 0) and np.ptp(theta) > 1.9 * np.pi
    law = result.scene.target.build()
    axial_speed = evaluator.result.trajectory.velocity[row] @ evaluator.rotations[row][:, 0]
    half = 0.5 * result.scene.numerics.mesh_size
    profile = analytic()[2]
    n_x = profile.outward_normal(np.linspace(station - half, station + half, 101))[0]
    bounds = law.c0 + law.c2 * (axial_speed * n_x) ** 2
    assert bounds.min() * (1 - 1e-9) <= sigma.min() and sigma.max() <= bounds.max() * (1 + 1e-9)
    out = tmp_path / "render"
    done = penetrate(
        "render",
        str(TEST2),
        "--set",
        f'projectile.geometry={{file = "{path}", unit = "mm"}}',
        "--times",
        "embedded,end",
        "--out",
        str(out),
        "--paraview",
        "--paraview-frames",
        "3",
    )
    assert done.returncode == 0, done.stderr
    assert {"field_nose_embedded.png", "field_end.png", "polar.png", "paraview"} <= {p.name for p in out.iterdir()}


@pytest.mark.slow  # 4 s: a whole penetrate process
def test_a_mesh_file_run_prints_nothing_but_its_json(folder):
    """meshio prints an empty line reading a gmsh 4 file; `penetrate run --json` keeps it off the standard output,
    which holds exactly the JSON object."""
    import json

    path = write_volume_mesh(folder / "quiet.msh", 0.05, order=1)
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "cases.cli",
            "run",
            str(TEST2),
            "--json",
            "--set",
            f"projectile.geometry={{file = '{path}'}}",
            "--set",
            "numerics.normals=mesh",
            "--set",
            "numerics.geometry_order=1",
            "--set",
            "numerics.mesh_size=0.05",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("{") and json.loads(done.stdout)["depth"] > 0


def _straight_and_flat(result) -> tuple[float, float]:
    """The largest sideways displacement (m, world Y) and out-of-plane attitude (quaternion x and z) of a run."""
    trajectory = result.trajectory
    return float(np.abs(trajectory.position[:, 1]).max()), float(np.abs(trajectory.attitude[:, [1, 3]]).max())


@pytest.mark.parametrize("kernel", ["numpy", "compiled"])
def test_a_body_of_revolution_from_a_file_flies_straight(folder, kernel):
    """A 105 mm, 600 mm body with a CRH 2.5 ogive, revolved by gmsh's own primitives (not by mesh/), as STEP in
    millimetres; normal impact at 400 m/s on the shipped 20 mm mesh: meshed on a quarter and mirrored, it stays
    exactly on its axis (0.06-0.4 degrees off before, from the whole mesh's asymmetry)."""
    path = folder / "revolved.step"
    if not path.exists():
        write_body(path, diameter=0.105, length=0.6, crh=2.5, scale=1e-3)
    geometry = {"file": str(path), "unit": "mm"}
    scene = load_scene(
        TEST2,
        {
            "projectile": {"geometry": geometry, "body_density": 7850.0},
            "impact.speed": 400.0,
            "numerics.kernel": kernel,
        },
    )
    assert prepare_projectile(scene).quadrature.mirror_planes == (1, 2)
    result = run_scene(scene)
    summary = summarise(result)
    assert summary.end_reason == "stopped" and summary.axis_angle_change == 0.0 and summary.max_attack_angle == 0.0
    assert _straight_and_flat(result) == (0.0, 0.0)


@pytest.mark.parametrize("kernel", ["numpy", "compiled"])
@pytest.mark.slow  # seconds of runs: CI's slow step
def test_a_body_with_one_mirror_plane_moves_in_it(kernel):
    """The shipped eroded test 2 (its nose cut by a plane whose normal lies in the x-z plane: one mirror plane,
    y = 0), with 3 degrees of attack and 20 degrees of obliquity in that plane: it turns (by a degree or more), and
    exactly in the plane."""
    scene = load_scene(
        scene_path("eroded_test2"),
        {"impact.attack_angle": 3.0, "impact.oblique_angle": 20.0, "numerics.kernel": kernel},
    )
    assert prepare_projectile(scene).quadrature.mirror_planes == (1,)
    result = run_scene(scene)
    assert abs(summarise(result).axis_angle_change) > 1.0
    assert _straight_and_flat(result) == (0.0, 0.0)


def test_p3_from_a_step_file_stays_straight_at_2000_m_s(folder):
    """#3 with a solid nose (the eroded-nose study's whole body, cases/bodies/make_bodies.py) as STEP (metres,
    body and counterweight), at 2000 m/s with no attack angle, at the study's 20 mm: exactly straight (up to 2
    degrees off before, from the whole mesh's asymmetry)."""
    import gmsh

    from cases.bodies.make_bodies import write_eroded_p3

    path = write_eroded_p3(folder / "p3_whole.step", 0.0, 0.0)
    gmsh.initialize(interruptible=False)
    try:  # STEP names its solids after the translator: the counterweight is the second
        gmsh.model.occ.importShapes(str(path))
        gmsh.model.occ.synchronize()
        counterweight = gmsh.model.getEntityName(3, gmsh.model.getEntities(3)[1][1]).rsplit("/", 1)[-1]
    finally:
        gmsh.finalize()
    scene = load_scene(
        scene_path("eroded_p3"),
        {
            "projectile.geometry.file": str(path),
            "projectile.materials": {counterweight: 18000.0},
            "impact.speed": 2000.0,
            "numerics.mesh_size": 0.02,
        },
    )
    assert prepare_projectile(scene).quadrature.mirror_planes == (1, 2)
    result = run_scene(scene)
    assert summarise(result).axis_angle_change == 0.0
    assert _straight_and_flat(result) == (0.0, 0.0)


@pytest.mark.parametrize(
    "geometry, message",
    [
        (
            'file = "{mesh}", symmetry = "mirrors"',
            r"projectile.geometry: symmetry = \'mirrors\': a mesh file is used as its elements are; mirror planes apply"
            r' to CAD files .*say symmetry = "none" or give the CAD file',
        ),
        (
            'file = "{step}", symmetry = "sideways"',
            r"projectile.geometry.symmetry = 'sideways': input should be 'auto', 'none', 'mirror_y'",
        ),
    ],
)
def test_a_symmetry_that_cannot_apply_is_one_line_and_exit_2(folder, tmp_path, geometry, message):
    mesh = folder / "symmetric.msh"
    if not mesh.exists():
        write_volume_mesh(mesh, 0.03)
    step = write_body(folder / "symmetric.step")
    text = geometry.format(mesh=mesh, step=step)
    done = penetrate("run", str(TEST2), "--set", f"projectile.geometry={{{text}}}", "--out", str(tmp_path / "o"))
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert re.search(message, done.stderr), done.stderr
    assert not (tmp_path / "o").exists()


def test_a_fused_cone_runs_at_the_shipped_numerics_as_the_cone_scene(folder):
    """A cylinder fused with a 12.92-degree cone, as a CAD user draws it (STEP, millimetres), at test 2's 20 mm
    and second order (its curved elements folded there before gmsh's high-order optimisation): the depth of the
    analytic cone scene within 0.1 % (measured +2.8e-4)."""
    from docs.geometry.cad_bodies import write_fused_cone

    path = write_fused_cone(folder / "fused_cone.step")
    got = summarise(run_scene(from_file({"file": str(path), "unit": "mm"})))
    _, depth, _ = analytic((("shape", "cone"), ("half_angle", 12.92)))
    assert got.depth == pytest.approx(depth, rel=1e-3)


def test_a_body_along_another_axis_is_refused_without_axis_and_warned_of_with_a_wrong_one(folder):
    """A long body along +z in its file, run without ``axis``, would fly broadside: it is refused in one line that
    names the axis to give; declared along x it runs and warns, naming the axis; with ``axis = [0, 0, 1]``
    nothing is said."""
    path = write_body(folder / "along_z.step", axis="z")
    coarse = {"numerics.mesh_size": 0.04}
    with pytest.raises(InputError, match=r"projectile.geometry.axis: not given.*90.0 deg.*say axis = \[0, 0, 1\]"):
        prepare_projectile(from_file({"file": str(path)}, **coarse))
    wrong = summarise(run_scene(from_file({"file": str(path), "axis": [1, 0, 0]}, **coarse)))
    assert any("projectile.geometry.axis = [1, 0, 0]" in w and "90.0 deg" in w for w in wrong.warnings)
    assert any("say axis = [0, 0, 1]" in w for w in wrong.warnings), wrong.warnings
    right = summarise(run_scene(from_file({"file": str(path), "axis": [0, 0, 1]}, **coarse)))
    assert not any("geometry.axis" in w for w in right.warnings)


MOVED = {"diameter": 0.105, "length": 0.525, "crh": 2.5, "scale": 1e-3}  # a 105 mm CRH 2.5 body, in millimetres
MOVED_SHOT = {"projectile.mass": 20.0, "impact.speed": 400.0, "numerics.mesh_size": 0.02}


@pytest.fixture(scope="module")
def depth_at_the_origin(folder) -> float:
    """The depth of the 105 mm body drawn along +x at the file's origin."""
    path = write_body(folder / "origin.step", **MOVED)
    return summarise(run_scene(from_file({"file": str(path), "unit": "mm"}, **MOVED_SHOT))).depth


@pytest.mark.parametrize(
    ("turned", "axis"),
    [("z", [0, 0, 1]), ("z", "auto"), ("x", None)],
    ids=["turned-axis-given", "turned-axis-auto", "moved-only"],
)
def test_a_body_anywhere_in_its_file_is_the_body_at_the_origin(folder, depth_at_the_origin, turned, axis):
    """The acceptance: a 105 mm CRH 2.5 body of revolution turned onto +z and moved by (100, 50, -30) mm in its
    STEP file, at 400 m/s and 20 mm: the depth of the body drawn along +x at the origin within 0.1 % (measured:
    1e-5) and an axis turn of at most 0.01 deg (measured: 0, its mirror planes found through its own axis), with
    ``axis`` given or found by ``"auto"``; moved without turning, with no ``axis``, the same."""
    path = write_body(folder / f"moved_{turned}.step", axis=turned, offset=(0.1, 0.05, -0.03), **MOVED)
    geometry = {"file": str(path), "unit": "mm", **({"axis": axis} if axis is not None else {})}
    result = run_scene(from_file(geometry, **MOVED_SHOT))
    got = summarise(result)
    assert got.depth == pytest.approx(depth_at_the_origin, rel=1e-3)
    assert abs(got.axis_angle_change) <= 0.01 and got.warnings == []
    assert result.prepared.quadrature.mirror_images is not None  # both mirror planes found


def test_a_declared_symmetry_is_checked_through_the_bodys_own_axis(folder):
    """``symmetry = "revolution"`` on the moved and turned body holds (it was refused when the planes passed
    through the file's origin)."""
    path = write_body(folder / "moved_revolution.step", axis="z", offset=(0.1, 0.05, -0.03), **MOVED)
    geometry = {"file": str(path), "unit": "mm", "axis": [0, 0, 1], "symmetry": "revolution"}
    prepared = prepare_projectile(from_file(geometry, **{**MOVED_SHOT, "numerics.mesh_size": 0.04}))
    assert prepared.quadrature.mirror_images is not None


@pytest.mark.slow
def test_a_volume_mesh_turned_and_moved_in_its_file_is_the_mesh_at_the_origin(folder):
    """Rotating a scene rotates its result: the same mesh with its nodes turned onto an oblique axis and moved,
    read along that axis, has the mass properties within 1e-9 and the depth and turn of the mesh moved without
    turning within 1e-9 (round-off: the nodes are turned back; measured 1e-13).

    With ``axis = "auto"`` the axis found turns with the mesh (within 1e-9), but the body frame is the shortest
    turn from that axis onto +x, and the axis found lies 3e-5 rad off the drawn one (the mesh is not quite
    symmetric): the two files' frames differ by a small roll about the axis, which turns the mesh's own
    asymmetry against the attack plane (measured over six meshes: 1e-9 to 1.1e-8 in depth; gmsh's high-order
    optimisation makes a different mesh each run).  So the turned file is checked against the unturned mesh
    rolled by that roll about its own axis: the same within 1e-9.

    Against the mesh at the origin the depth agrees within 1e-5 only, and that is not round-off: a body whose
    centroid lies on the file's own x line (within a thousandth of its length) keeps that line as its axis,
    while a moved body's axis runs through its centroid, here 1.9e-5 m off the drawn axis; measured 1.5e-6."""
    import meshio

    from mesh.imported import rotation_to_x

    plain = write_volume_mesh(folder / "origin.vtu", 0.03)
    m = meshio.read(plain)
    turn = rotation_to_x((0.3, -0.5, 0.81)).T
    offset = np.array([0.1, 0.05, -0.03])
    shifted, moved = folder / "shifted.vtu", folder / "turned.vtu"
    meshio.write(shifted, meshio.Mesh(m.points + offset, m.cells, cell_data=m.cell_data))
    meshio.write(moved, meshio.Mesh(m.points @ turn.T + offset, m.cells, cell_data=m.cell_data))
    shot = {"numerics.normals": "mesh", "numerics.mesh_size": 0.03, "impact.attack_angle": 2.0}

    def same(b, a) -> None:
        assert b.prepared.mass.axial_inertia == pytest.approx(a.prepared.mass.axial_inertia, rel=1e-9)
        assert b.prepared.mass.transverse_inertia == pytest.approx(a.prepared.mass.transverse_inertia, rel=1e-9)
        assert summarise(b).depth == pytest.approx(summarise(a).depth, rel=1e-9)
        assert summarise(b).axis_angle_change == pytest.approx(summarise(a).axis_angle_change, abs=1e-9)

    at_origin = run_scene(from_file({"file": str(plain), "axis": [1, 0, 0]}, **shot))
    a = run_scene(from_file({"file": str(shifted), "axis": [1, 0, 0]}, **shot))
    b = run_scene(from_file({"file": str(moved), "axis": turn[:, 0].tolist()}, **shot))
    same(b, a)
    assert summarise(b).depth == pytest.approx(summarise(at_origin).depth, rel=1e-5)

    a = run_scene(from_file({"file": str(shifted), "axis": "auto"}, **shot))
    b = run_scene(from_file({"file": str(moved), "axis": "auto"}, **shot))
    found_a, found_b = (np.array(r.prepared.geometry.axis) for r in (a, b))
    assert np.abs(found_b - turn @ found_a).max() < 1e-9
    # b's frame is a's turned and then rolled about +x: roll the shifted mesh by as much about its own axis
    centre = a.prepared.geometry.centre
    roll = rotation_to_x(found_a).T @ rotation_to_x(found_b) @ turn
    rolled = folder / "rolled.vtu"
    meshio.write(rolled, meshio.Mesh((m.points + offset - centre) @ roll.T + centre, m.cells, cell_data=m.cell_data))
    same(b, run_scene(from_file({"file": str(rolled), "axis": found_a.tolist()}, **shot)))
    assert summarise(b).depth == pytest.approx(summarise(at_origin).depth, rel=1e-5)


@pytest.mark.parametrize(
    ("shape", "axis", "message", "fix"),
    [
        ("sphere", "auto", r'axis = "auto": the body has no clear long axis.*give the axis', [1, 0, 0]),
        (
            "cylinder",
            "auto",
            r'axis = "auto": the body\'s ends along its long axis \[0.8018, 0.5345, 0.2673\] lie equally far from its'
            r" centroid.*give axis = \[0.8018, 0.5345, 0.2673\]",
            [0.8018, 0.5345, 0.2673],
        ),
        ("backwards", None, r"its tip .* is at its -x end: say axis = \[-1, 0, 0\]", [-1, 0, 0]),
    ],
)
def test_an_axis_that_cannot_be_found_is_refused_in_one_line_that_names_a_fix_that_works(
    folder, shape, axis, message, fix
):
    import gmsh

    path = folder / f"{shape}.step"
    gmsh.initialize(interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        occ = gmsh.model.occ
        if shape == "sphere":
            occ.addSphere(0.1, 0.2, 0.3, 0.1)
        elif shape == "cylinder":
            occ.addCylinder(0.0, 0.0, 0.0, 0.3, 0.2, 0.1, 0.05)
        occ.synchronize()
        if shape != "backwards":
            gmsh.write(str(path))
    finally:
        gmsh.finalize()
    if shape == "backwards":
        path = write_body(folder / "backwards_source.step")
        import gmsh as g

        g.initialize(interruptible=False)
        g.option.setNumber("General.Terminal", 0)
        try:
            g.model.occ.importShapes(str(path))
            g.model.occ.rotate(g.model.occ.getEntities(3), 0, 0, 0, 0, 0, 1, np.pi)  # tip onto -x
            g.model.occ.synchronize()
            path = folder / "backwards.step"
            g.write(str(path))
        finally:
            g.finalize()
    geometry = {"file": str(path), **({"axis": axis} if axis is not None else {})}
    with pytest.raises(InputError, match=message) as refused:
        prepare_projectile(from_file(geometry, **{"numerics.mesh_size": 0.04}))
    assert "\n" not in str(refused.value)
    fixed = prepare_projectile(from_file({**geometry, "axis": fix}, **{"numerics.mesh_size": 0.04}))
    assert fixed.mass.mass > 0.0
