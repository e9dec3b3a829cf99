"""Projectiles from CAD and mesh files (mesh.imported, mesh.cad, mesh.volume_mesh), against bodies written by
gmsh's own primitives (docs/geometry/cad_bodies.py): analytic mass properties, OpenCASCADE's mass properties, the exact
surface's integrals, units both ways, and one clear error for each kind of bad file."""

from __future__ import annotations

import math
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from fem_loads import mass_properties, surface_quadrature
from mesh import ConeNose, OgiveNose, Profile, ProjectileGeometry, analytic_mass_properties
from mesh.cad import CadSurface
from mesh.files import build_file_mesh, tangled
from mesh.imported import MATERIAL_BASE, FileGeometry, GeometryError, body_frame, file_digest, outline

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from support import slow_except  # noqa: E402

from docs.geometry.cad_bodies import VALIDATION, occ_mass_properties, write_body, write_volume_mesh  # noqa: E402

STEEL = 7850.0
OGIVE = ProjectileGeometry(Profile(VALIDATION["diameter"], VALIDATION["length"], OgiveNose(VALIDATION["crh"])))
CONE = ProjectileGeometry(Profile(VALIDATION["diameter"], VALIDATION["length"], ConeNose(12.0)))


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("bodies")


def geometry(path: Path, unit: str = "m", **kw) -> FileGeometry:
    return FileGeometry(str(path), file_digest(path), unit, **kw)


def body(path: Path, unit: str = "m", size: float = 0.02, **kw):
    """Body-frame mesh, tip x in the model frame, and the mass properties of steel."""
    mesh, tip = body_frame(build_file_mesh(geometry(path, unit, **kw), size, 2))
    return mesh, tip, mass_properties(mesh, {1: STEEL, MATERIAL_BASE: 18000.0, MATERIAL_BASE + 1: 18000.0})


def assert_matches_analytic(props, exact, tol: float) -> None:
    assert props.mass == pytest.approx(exact.mass, rel=tol)
    assert props.centre_from_tip == pytest.approx(exact.centre_from_tip, rel=tol)
    assert props.axial_inertia == pytest.approx(exact.axial_inertia, rel=tol)
    assert props.transverse_inertia == pytest.approx(exact.transverse_inertia, rel=tol)
    assert np.abs(props.centre[1:]).max() < tol * exact.centre_from_tip


@pytest.mark.parametrize(
    "name, unit, scale",
    slow_except(
        [
            ("ogive.step", "m", 1.0),
            ("ogive_mm.step", "mm", 1e-3),
            ("ogive_cm.brep", "cm", 1e-2),
            ("ogive_in.step", "in", 0.0254),
            ("ogive_mm.iges", "mm", 1e-3),
        ],
        ("ogive.step", "m", 1.0),
        ("ogive_mm.step", "mm", 1e-3),
    ),
)  # units both ways by default
def test_cad_formats_and_units_give_the_analytic_body(folder, name, unit, scale):
    """Each format, written in its unit's numbers and read with that unit, is the same body in metres;
    10 mm elements: the mesh's own error in the mass properties is ~1e-5."""
    path = write_body(folder / name, scale=scale)
    mesh, tip, props = body(path, unit, size=0.01)
    assert tip == pytest.approx(VALIDATION["length"], rel=1e-9)
    sizes = outline(mesh)
    assert sizes.length == pytest.approx(VALIDATION["length"], rel=1e-9)
    assert sizes.diameter == pytest.approx(VALIDATION["diameter"], rel=1e-6)
    assert sizes.nose_length == pytest.approx(OGIVE.profile.nose_length, rel=0.02)
    assert_matches_analytic(props, analytic_mass_properties(OGIVE, STEEL), 1e-4)


def test_the_wrong_unit_is_refused_naming_the_right_one(folder):
    millimetres = write_body(folder / "in_mm.step", scale=1e-3)  # 1400 units long
    with pytest.raises(GeometryError, match=r'projectile.geometry.unit = "m".*1400 m.*unit = "mm"'):
        build_file_mesh(geometry(millimetres, "m"), 0.02)
    metres = write_body(folder / "in_m.step")
    with pytest.raises(GeometryError, match=r'projectile.geometry.unit = "mm".*0.0014 m.*unit = "m"'):
        build_file_mesh(geometry(metres, "mm"), 0.02)


def test_axis_turns_the_file_onto_x(folder):
    along_z = write_body(folder / "along_z.step", axis="z")
    _, tip, props = body(along_z, axis=(0.0, 0.0, 1.0))
    _, _, reference = body(write_body(folder / "along_x.step"))
    assert tip == pytest.approx(VALIDATION["length"], rel=1e-9)
    np.testing.assert_allclose(np.diag(props.inertia), np.diag(reference.inertia), rtol=2e-4)
    assert props.centre_from_tip == pytest.approx(reference.centre_from_tip, rel=1e-4)


def test_cone_against_the_analytic_cone(folder):
    _, _, props = body(write_body(folder / "cone.step", half_angle=12.0), size=0.01)
    assert_matches_analytic(props, analytic_mass_properties(CONE, STEEL), 2e-4)


@pytest.mark.slow  # the default suite keeps within 4 minutes on 2 cores; CI runs it
def test_named_and_numbered_solids_take_their_densities(folder):
    """A counterweight solid inside the body: named in a STEP file's products, or numbered (``solid1``,
    ``solid2``) in a BREP file (no names), against OpenCASCADE's own volumes.  Which solid the file lists
    first is the writer's business: naming each in turn gives the counterweight's density to the
    counterweight once and to the rest of the body once."""
    span = (0.3, 0.6, 0.03)
    original = write_body(folder / "weighted.step", counterweight=span).read_text()
    brep = write_body(folder / "weighted.brep", counterweight=span)
    volume = occ_mass_properties(write_body(folder / "plain.step"))[0]
    weight = math.pi * span[2] ** 2 * (span[1] - span[0])
    expected = sorted([STEEL * (volume - weight) + 18000.0 * weight, 18000.0 * (volume - weight) + STEEL * weight])
    by_name = []
    for k in (1, 2):
        step = folder / f"named{k}.step"
        text, renamed = re.subn(rf"Open CASCADE STEP translator [\d.]+ \d+\.{k}\b", "counterweight", original)
        assert renamed == 2  # the product's name and its description
        step.write_text(text)
        by_name.append(body(step, materials=("counterweight",))[2].mass)
    by_number = [body(brep, materials=(f"solid{k}",))[2].mass for k in (1, 2)]
    for masses in (by_name, by_number):
        np.testing.assert_allclose(sorted(masses), expected, rtol=2e-4)
    with pytest.raises(
        GeometryError,
        match=r"projectile.materials.tungsten: no solid or group of that name.*"
        r"counterweight",
    ):
        body(folder / "named1.step", materials=("tungsten",))


def test_exact_surface_rule_integrates_the_ogive_exactly(folder):
    """The parametric rule on the CAD surfaces: area, frontal area and the nose's integral of n_x^3
    against 1-D integrals of the profile (the facets only partition the exact surface)."""
    path = write_body(folder / "exact.step")
    mesh, tip, props = body(path)
    q = surface_quadrature(
        mesh, props.centre, None, "exact", 4, surface=CadSurface(geometry(path), tip), facet_rule="shape"
    )
    profile = OGIVE.profile
    assert q.area == pytest.approx(profile.surface_area(), rel=2e-5)
    front = q.normals[:, 0] > 0
    assert (q.normals[front, 0] * q.weights[front]).sum() == pytest.approx(math.pi * profile.radius**2, rel=2e-5)
    s = np.linspace(0.0, profile.nose_length, 200001)
    n_forward, _ = profile.outward_normal(s)
    ds = np.gradient(s)
    lateral = 2 * math.pi * profile.radius_at(s) * np.sqrt(1 + profile.slope_at(s) ** 2) * ds
    assert (q.normals[front, 0] ** 3 * q.weights[front]).sum() == pytest.approx(
        (n_forward**3 * lateral).sum(), rel=1e-4
    )
    # every point on the exact surface, with the exact normal
    p = q.points + props.centre
    on_side = -p[:, 0] < profile.length - 1e-9
    radius = np.hypot(p[on_side, 1], p[on_side, 2])
    np.testing.assert_allclose(radius, profile.radius_at(-p[on_side, 0]), atol=1e-12)


@pytest.mark.parametrize("suffix", [".msh", ".vtu"])
def test_volume_meshes_with_their_materials(folder, suffix):
    span = (0.3, 0.6, 0.03)
    path = write_volume_mesh(folder / f"weighted{suffix}", 0.02, counterweight=span)
    name, field = ("counterweight", None) if suffix == ".msh" else ("2", "material")
    _, _, props = body(path, materials=(name,), cell_field=field)
    exact = analytic_mass_properties(OGIVE, STEEL)
    weight = math.pi * span[2] ** 2 * (span[1] - span[0])
    assert props.mass == pytest.approx(exact.mass + (18000.0 - STEEL) * weight, rel=2e-4)


def test_first_order_mesh_keeps_its_order(folder):
    mesh = build_file_mesh(geometry(write_volume_mesh(folder / "flat.msh", 0.02, order=1)), 0.02, 2)
    assert mesh.order == 1 and mesh.tetra.shape[1] == 4 and mesh.outer.shape[1] == 3


def test_outer_triangles_face_outward(folder):
    """Every outer facet's normal points away from its tetrahedron (the enclosed volume comes out positive
    and equal to the mesh's: x . n dA on a quadratic facet is a polynomial of degree 4, which the
    order-4 rule integrates exactly)."""
    for path in (write_body(folder / "o.step"), write_volume_mesh(folder / "o.msh", 0.03)):
        mesh, _, props = body(path)
        q = surface_quadrature(mesh, props.centre, None, "mesh", 4, facet_rule="shape")
        assert q.enclosed_volume() == pytest.approx(props.volume, rel=1e-9)


def _write_text(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def test_bad_files_get_one_line_each(folder):
    import gmsh

    cases = []
    cases.append((folder / "missing.step", "no such file"))
    cases.append((_write_text(folder / "garbage.step", "not a step file\n"), "gmsh cannot read it as STEP"))
    cases.append((_write_text(folder / "garbage.msh", "$MeshFormat\nnonsense\n"), "meshio cannot read it"))
    # an open surface: one face of revolution, no tail
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("open")
    occ = gmsh.model.occ
    line = occ.addLine(occ.addPoint(0, 0.05, 0), occ.addPoint(1, 0.05, 0))
    occ.revolve([(1, line)], 0, 0, 0, 1, 0, 0, 2 * math.pi)
    occ.synchronize()
    gmsh.write(str(folder / "open.brep"))
    gmsh.write(str(folder / "open.iges"))
    # two disjoint solids
    gmsh.clear()
    gmsh.model.add("two")
    gmsh.model.occ.addBox(0, 0, 0, 0.1, 0.1, 0.5)
    gmsh.model.occ.addBox(0.5, 0, 0, 0.1, 0.1, 0.5)
    gmsh.model.occ.synchronize()
    gmsh.write(str(folder / "two.step"))
    gmsh.model.mesh.generate(2)  # a surface mesh only
    gmsh.write(str(folder / "surface.msh"))
    gmsh.finalize()
    cases += [
        (folder / "open.brep", "no closed solid"),
        (folder / "two.step", "2 disjoint bodies"),
        (folder / "surface.msh", "no tetrahedra"),
        (folder / "open.iges", "no closed solid.*export it as STEP or BREP"),
    ]
    for path, message in cases:
        with pytest.raises(GeometryError, match=message) as info:
            build_file_mesh(FileGeometry(str(path), "", "m"), 0.02)
        assert "\n" not in str(info.value) and "projectile.geometry" in str(info.value)


def test_folded_curved_tetrahedra_are_refused(folder):
    """A quadratic tetrahedron whose edge node is pulled across its opposite face has a Jacobian of both
    signs: its mass would be counted twice over the folded part, so the file is refused with the fix."""
    import meshio

    good = write_volume_mesh(folder / "good.msh", 0.03)
    assert not tangled(build_file_mesh(FileGeometry(str(good), "", "m"), 0.02)).any()
    m = meshio.read(good)
    block = next(b for b in m.cells if b.type == "tetra10")
    tet = block.data[0]
    points = m.points.copy()
    # the midpoint of edge 0-1 moved past the opposite edge's midpoint, through the element
    points[tet[4]] = 2.0 * (0.5 * (points[tet[2]] + points[tet[3]])) - 0.5 * (points[tet[0]] + points[tet[1]])
    bad = folder / "folded.vtu"
    meshio.write(bad, meshio.Mesh(points, [("tetra10", block.data)]))
    with pytest.raises(GeometryError, match=r"\d+ curved tetrahedra fold over.*HighOrderOptimize"):
        build_file_mesh(FileGeometry(str(bad), "", "m"), 0.02)


def _rod(points: int = 4000, seed: int = 0) -> np.ndarray:
    """Points filling a rod along +x from 0 to 1 with a cone tip beyond, radius 0.1: its centroid lies
    behind the middle of its length, so the tip is the end further from it."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.0, 1.3, points * 3)
    r = 0.1 * np.sqrt(rng.uniform(0.0, 1.0, points * 3))
    keep = r <= 0.1 * np.clip((1.3 - x) / 0.3, 0.0, 1.0)
    angle = rng.uniform(0.0, 2.0 * math.pi, points * 3)
    return np.column_stack([x, r * np.cos(angle), r * np.sin(angle)])[keep][:points]


def _placed(points: np.ndarray, axis) -> FileGeometry:
    from mesh.imported import place

    centroid = points.mean(axis=0)
    r = points - centroid
    second = r.T @ r
    inertia = np.trace(second) * np.eye(3) - second

    def span(direction: np.ndarray) -> tuple[float, float]:
        along = points @ direction
        return float(along.min()), float(along.max())

    return place(FileGeometry("body.step", "", "m", axis), centroid, inertia, span)


@pytest.mark.parametrize("seed", range(4))
def test_placing_a_turned_and_moved_body_turns_and_moves_its_axis(seed):
    """Rotating a scene rotates its result: a rod turned by a random rotation and moved is read along the
    turned axis by "auto", its origin on the moved axis; without an axis it is refused, naming the turned axis."""
    from scipy.spatial.transform import Rotation

    rod = _rod()
    rod -= rod.mean(axis=0)  # its centroid at the file's origin: on every line through it
    turn = Rotation.random(random_state=seed).as_matrix()
    offset = np.random.default_rng(seed).uniform(-1.0, 1.0, 3)
    moved = rod @ turn.T + offset
    at_origin, placed = _placed(rod, "auto"), _placed(moved, "auto")
    assert np.allclose(placed.axis, turn @ np.asarray(at_origin.axis), atol=1e-12)
    # in the model frame the two are the same body, up to a shift along the axis and a roll about it
    from mesh.imported import model_frame

    a, b = model_frame(rod, at_origin), model_frame(moved, placed)
    assert np.allclose(b[:, 0] - a[:, 0], (b[:, 0] - a[:, 0]).mean(), atol=1e-12)
    assert np.allclose(np.hypot(b[:, 1], b[:, 2]), np.hypot(a[:, 1], a[:, 2]), atol=1e-12)
    angle = math.degrees(math.acos(abs(float(np.asarray(placed.axis)[0]))))
    if angle > 1.0:
        with pytest.raises(GeometryError, match=r"axis: not given.*say axis = \[.*\] \(tail to tip\)"):
            _placed(moved, None)


def test_a_body_drawn_about_its_axis_keeps_the_files_line():
    """A centroid within 1e-3 of the length of the file's x line is on it (a body drawn about that line, such as
    an eroded nose whose centroid lies a little off its shank's axis): the origin stays the file's, and the body
    is meshed exactly as drawn; one 1e-2 off moves the axis onto it."""
    rod = _rod()
    rod[:, 1:] -= rod[:, 1:].mean(axis=0)  # the centroid on the x line exactly
    assert _placed(rod + [0.3, 1e-4, -1e-4], None).origin == (0.0, 0.0, 0.0)
    off = _placed(rod + [0.3, 0.0, 1e-2], None)
    assert off.origin == pytest.approx((0.0, 0.0, 1e-2), abs=1e-12)


def test_a_finned_body_measures_its_nose_to_the_shoulder_not_the_fins():
    """The shipped finned body (test 2's CRH 3 ogive of 95.2 mm with four tail fins from 1.25 m): its nose is the
    tangent ogive's, ``d sqrt(CRH - 1/4)``, and its diameter the fins' span; the widest point is 1.25 m back."""
    step = Path(__file__).resolve().parents[2] / "cases" / "bodies" / "finned_test2.step"
    mesh, _, _ = body(step, "mm", size=0.032)
    sizes = outline(mesh)
    assert sizes.nose_length == pytest.approx(0.0952 * math.sqrt(3.0 - 0.25), rel=0.02)
    assert sizes.length == pytest.approx(1.4, rel=1e-9) and sizes.diameter > 1.5 * 0.0952
