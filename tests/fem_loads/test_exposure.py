"""Exposure (fem_loads.exposure): only surface the target can reach carries stress.

Against independent truth: the cube map's nodes and its continuity; the cone of exposure the compiled kernel
trusts; rays traced by hand against the finned body's shank; a convex body untouched bitwise; a base recess
that no longer changes the shot; the compiled kernel against the numpy load."""

from __future__ import annotations

import functools
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from cases import load_scene, run_scene, scene_path, summarise
from cases.run import prepare_projectile
from cases.run.compiled import compiled_modules
from cases.scene.projectile import MassPropertiesSpec
from dynamics.quaternion import normalize, rotation_matrix
from fem_loads.exposure import Exposure, cube_nodes

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from docs.geometry.cad_bodies import write_changed_body  # noqa: E402

RESOLUTION = 16


def _random_exposure(seed: int, count: int = 5) -> Exposure:
    rng = np.random.default_rng(seed)
    table = (rng.random((count, 6, RESOLUTION + 1, RESOLUTION + 1)) < 0.7).astype(np.uint8)
    nodes = cube_nodes(RESOLUTION)
    # the same direction on two faces' shared edges has one value: take the first face's
    flat = nodes.reshape(-1, 3)
    _, first = np.unique(np.round(flat, 12), axis=0, return_inverse=True)
    for row in range(count):
        values = table[row].reshape(-1)
        chosen = np.zeros(first.max() + 1, dtype=np.uint8)
        chosen[first[::-1]] = values[::-1]
        table[row] = chosen[first].reshape(table[row].shape)
    return Exposure(np.arange(count), table)


def test_the_factor_is_the_table_at_its_nodes_and_continuous_between():
    exposure = _random_exposure(0)
    nodes = cube_nodes(RESOLUTION)
    factor = exposure.factor(np.broadcast_to(nodes.reshape(-1, 1, 3), (nodes[..., 0].size, 5, 3)))
    np.testing.assert_allclose(factor.T.reshape(exposure.table.shape), exposure.table, rtol=0, atol=1e-12)
    # across every direction, a small turn moves the factor by at most about its angle over a cell's
    rng = np.random.default_rng(1)
    d = rng.normal(size=(20000, 1, 3))
    turned = d + 1e-7 * rng.normal(size=d.shape) * np.linalg.norm(d, axis=-1, keepdims=True)
    change = np.abs(
        exposure.factor(np.broadcast_to(d, (20000, 5, 3))) - exposure.factor(np.broadcast_to(turned, (20000, 5, 3)))
    )
    assert change.max() < 1e-4


def test_each_cell_lists_the_rows_hidden_at_its_corners():
    exposure = _random_exposure(2)
    n = exposure.resolution
    for cell in range(6 * n * n):
        face, i, j = cell // (n * n), (cell // n) % n, cell % n
        span = slice(exposure.cell_start[cell], exposure.cell_start[cell + 1])
        corners = [exposure.table[:, face, i + di, j + dj] == 0 for di, dj in ((0, 0), (1, 0), (0, 1), (1, 1))]
        masks = sum(corner.astype(int) << bit for bit, corner in enumerate(corners))
        assert exposure.cell_rows[span].tolist() == np.flatnonzero(masks).tolist()
        assert exposure.cell_corners[span].tolist() == masks[masks != 0].tolist()


@functools.cache
def _finned():
    scene = load_scene(scene_path("finned_test2"))
    return scene, prepare_projectile(scene)


def _state(attack: float, sideways: float, speed: float = 300.0):
    """Embedded, no spin, the body's axis down; its body-frame velocity at ``attack`` degrees off the axis, towards
    ``(0, -cos, -sin)`` of ``sideways`` degrees about it."""
    nose_down = rotation_matrix(np.array([math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0]))
    a, b = math.radians(attack), math.radians(sideways)
    body_velocity = speed * np.array([math.cos(a), -math.sin(a) * math.cos(b), -math.sin(a) * math.sin(b)])
    return np.array([0.0, 0.0, -3.0]), nose_down @ body_velocity, nose_down, np.zeros(3)


def _hits_shank(point: np.ndarray, direction: np.ndarray, radius: float, start: float, end: float) -> bool:
    """Whether the ray meets the cylinder of ``radius`` about the axis between ``start`` and ``end`` (body frame x,
    tip at 0, m): the closest approach of its (y, z) path, within the shank's length."""
    py, pz, dy, dz = point[1], point[2], direction[1], direction[2]
    lateral = dy * dy + dz * dz
    t = -(py * dy + pz * dz) / lateral
    if t <= 0.0 or math.hypot(py + t * dy, pz + t * dz) > radius:
        return False
    # the first crossing of the cylinder
    b, c = py * dy + pz * dz, py * py + pz * pz - radius * radius
    first = (-b - math.sqrt(b * b - lateral * c)) / lateral
    return start < point[0] + first * direction[0] < end


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_the_finned_body_s_hidden_faces_carry_no_stress():
    """30 degrees of attack between two fins: on the fins' faces that move into the soil, the points whose ray
    along the body's motion (and along every direction within 10 degrees of it) meets the body's shank carry
    exactly no stress, on the load field; the same faces' points whose rays clear everything carry it."""
    scene, prepared = _finned()
    loads = scene.loads(prepared.quadrature)
    q = prepared.quadrature
    state = _state(30.0, 45.0)
    field = loads.surface_stress(*state)
    body_velocity = state[1] @ state[2]
    direction = body_velocity / np.linalg.norm(body_velocity)
    centre = prepared.mass.centre
    tips = q.points + centre  # body frame, tip at the origin
    radius, length = 0.0952 / 2, 1.4
    shank = (-length + 0.01, -0.35)  # the shank, clear of the tail and the nose (m)
    rng = np.random.default_rng(4)
    turns = [direction]
    for _ in range(24):  # directions 10 degrees off it, all round
        side = np.cross(direction, rng.normal(size=3))
        turned = direction + math.tan(math.radians(10.0)) * side / np.linalg.norm(side)
        turns.append(turned / np.linalg.norm(turned))
    on_fins = (np.abs(q.normals[:, 1]) > 0.99) | (np.abs(q.normals[:, 2]) > 0.99)
    on_fins &= np.hypot(tips[:, 1], tips[:, 2]) > radius + 0.002
    loaded = on_fins & (field.normal_velocity > 0.05 * 300.0)
    hidden = [j for j in np.flatnonzero(loaded) if all(_hits_shank(tips[j], d, radius, *shank) for d in turns)]
    clear = [j for j in np.flatnonzero(loaded) if not any(_hits_shank(tips[j], d, radius, -length, 0.0) for d in turns)]
    assert len(hidden) >= 10 and len(clear) >= 10
    assert (field.sigma_n[hidden] == 0.0).all()
    assert (field.sigma_n[clear] > 0.0).all()
    without = load_scene(scene_path("finned_test2"), {"effects.exposure": False}).loads(q).surface_stress(*state)
    assert (without.sigma_n[hidden] > 0.0).all()  # the same points, every Vn > 0 loaded


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_a_convex_body_has_no_table_and_loads_as_before():
    for name in ("forrestal_luk_test2", "eroded_test2"):
        scene = load_scene(scene_path(name))
        q = prepare_projectile(scene).quadrature
        assert q.exposure is None
        off = load_scene(scene_path(name), {"effects.exposure": False}).loads(q)
        state = _state(10.0, 30.0)
        np.testing.assert_array_equal(np.concatenate(scene.loads(q)(*state)), np.concatenate(off(*state)))


#: the compiled kernel's loops: the plain law, a plain law with a strength table, layers of plain laws (a row and
#: an interface 2 m down, which the states straddle) and a power term, each read in passes of their own; and the
#: loop of any other load, point by point (no separation)
TARGETS = {
    "plain": {},
    "table": {
        "target.law": {
            "model": "polynomial",
            "c0": 17.18e6,
            "c2": 2282.2,
            "strength_table": [[0.0, 0.0], [2.0, 4e6], [3.0, 5e6]],
        }
    },
    "layers": {
        "target.layers": [{"thickness": 2.0, "law": "soil"}, {"law": {"model": "polynomial", "c0": 8e6, "c2": 1500.0}}]
    },
    "power": {"target.law": {"model": "power", "c0": 17.18e6, "c": 5000.0, "n": 1.9}},
    "point by point": {"effects.separation": False},
}


@pytest.mark.parametrize("target", list(TARGETS))
@pytest.mark.parametrize(
    "friction", [None, {"model": "coulomb", "coefficient": 0.2}, {"model": "capped", "coefficient": 0.3, "cap": 2e6}]
)
def test_the_compiled_kernel_hides_what_the_numpy_load_hides(friction, target):
    scene, prepared = _finned()
    overrides = {**TARGETS[target], **({"effects.friction": friction} if friction else {})}
    loads = load_scene(scene_path("finned_test2"), overrides).loads(prepared.quadrature)
    assert loads.exposure is not None
    _, layout = compiled_modules()
    data = layout.kernel_data(loads)
    rng = np.random.default_rng(7)
    hidden = 0
    for _ in range(30):
        state = (
            np.array([0.0, 0.0, -2.0]) + rng.normal(size=3) * 0.5,
            rng.normal(size=3) * 300.0,
            rotation_matrix(normalize(rng.normal(size=4))),
            rng.normal(size=3) * 20.0,
        )
        reference = np.concatenate(loads(*state))
        out = np.empty(6)
        layout.dafl_kernel(data, *state, out)
        np.testing.assert_allclose(out, reference, rtol=0, atol=1e-12 * np.abs(reference).max())
        everything = np.concatenate(
            load_scene(scene_path("finned_test2"), {**overrides, "effects.exposure": False}).loads(prepared.quadrature)(
                *state
            )
        )
        hidden += not np.allclose(everything, reference, rtol=1e-9)
    assert hidden > 10  # the states do hide surface


@functools.cache
def _recess_runs(folder: str) -> tuple:
    """Test 2's scene with a 105 mm, 600 mm, CRH 2.5 body of steel with a base recess (20 mm deep, 35 mm radius),
    at 400 m/s and 5 degrees of attack; with and without exposure; and the same body without the recess given the
    recessed body's mass properties."""
    plain = write_changed_body(Path(folder) / "plain.step")
    recess = write_changed_body(Path(folder) / "recess.step", recess=(0.02, 0.035))
    shot = {"impact.speed": 400.0, "impact.attack_angle": 5.0}
    geometry = {"geometry": {"file": str(recess), "unit": "mm"}, "body_density": 7850.0}
    recessed = load_scene(scene_path("forrestal_luk_test2"), {"projectile": geometry, **shot})
    given = MassPropertiesSpec.of(prepare_projectile(recessed).mass).model_dump()
    reference = load_scene(
        scene_path("forrestal_luk_test2"),
        {"projectile": {"geometry": {"file": str(plain), "unit": "mm"}, "mass_properties": given}, **shot},
    )
    everything = load_scene(
        scene_path("forrestal_luk_test2"), {"projectile": geometry, **shot, "effects.exposure": False}
    )
    return tuple(summarise(run_scene(s)) for s in (recessed, everything, reference))


@pytest.mark.slow  # the default suite keeps within 4 minutes on 2 cores; CI runs it
def test_a_base_recess_the_soil_cannot_reach_does_not_change_the_shot(tmp_path_factory):
    """The recess's inner wall is hidden behind the body: the recessed body runs as the plain one with its mass
    properties, within 0.2 % in depth and 0.1 degrees in turn (measured: 4e-9 and 5e-7 degrees).  Loading it (every
    Vn > 0) moves the depth by 1.3 % and the turn by 2.3 degrees."""
    recessed, everything, reference = _recess_runs(str(tmp_path_factory.mktemp("recess")))
    assert abs(recessed.depth / reference.depth - 1.0) < 2e-3
    assert abs(recessed.axis_angle_change - reference.axis_angle_change) < 0.1
    assert abs(everything.depth / reference.depth - 1.0) > 5e-3
    assert abs(everything.axis_angle_change - reference.axis_angle_change) > 1.0


@pytest.mark.slow
def test_a_convex_body_of_flat_facets_hides_little_of_itself(tmp_path):
    """A triangulated convex body has slight dents where its facets meet.  Its rays start a twentieth of an
    element off (not its points' sag, which is zero on flat facets), so that the facets do not hide their
    neighbours: test 2's body as 4-node tetrahedra at 20 mm runs with exposure within 1 % of the run without it
    (measured 0.6 %: some grazing rays still meet a dent; with the flat facets' rays started at the least lift,
    a hundredth of that, 2028 points hid and the depth moved by 5 %)."""
    from docs.geometry.cad_bodies import write_volume_mesh

    path = write_volume_mesh(tmp_path / "faceted.msh", 0.02, order=1)
    shot = {
        "projectile.geometry": {"file": str(path)},
        "numerics.normals": "mesh",
        "numerics.geometry_order": 1,
        "numerics.mesh_size": 0.02,
    }
    on, off = (
        summarise(run_scene(load_scene(scene_path("forrestal_luk_test2"), {**shot, "effects.exposure": flag})))
        for flag in (True, False)
    )
    assert abs(on.depth / off.depth - 1.0) < 1e-2


def _on_face(face: int, s: float, t: float, length: float = 1.0) -> np.ndarray:
    """The direction ``length (+-1, s, t)`` in the axes ``(a, a + 1, a + 2)`` (mod 3) of face ``f`` (axis
    ``a = f // 2``, positive for even ``f``): the cube map's placing, written out here."""
    axis, direction = face // 2, np.empty(3)
    direction[axis] = -1.0 if face % 2 else 1.0
    direction[(axis + 1) % 3], direction[(axis + 2) % 3] = s, t
    return length * direction


def _bilinear(a, b, c, d, fx: float, fy: float):
    """Corner values ``(0, 0)``, ``(1, 0)``, ``(0, 1)``, ``(1, 1)`` interpolated at ``(fx, fy)``."""
    return (1.0 - fx) * (1.0 - fy) * a + fx * (1.0 - fy) * b + (1.0 - fx) * fy * c + fx * fy * d


def test_the_factor_is_the_table_at_the_nodes_and_bilinear_between():
    """At each node, given unnormalised so that its place in its cell is exact, every row's factor is the table's
    value exactly; at random places in random cells it is the bilinear interpolation of the cell's four corners
    (exactly their value where they agree)."""
    exposure = _random_exposure(5, count=40)
    n, table = exposure.resolution, exposure.table.astype(float)
    for face, i, j in np.ndindex(6, n + 1, n + 1):
        direction = _on_face(face, 2.0 * i / n - 1.0, 2.0 * j / n - 1.0)
        assert np.array_equal(exposure.factor(np.broadcast_to(direction, (40, 3))), table[:, face, i, j])
    rng = np.random.default_rng(6)
    for _ in range(300):
        face, i, j = rng.integers(6), rng.integers(n), rng.integers(n)
        fx, fy = rng.uniform(1e-3, 1.0 - 1e-3, 2)
        direction = _on_face(face, 2.0 * (i + fx) / n - 1.0, 2.0 * (j + fy) / n - 1.0, rng.uniform(0.1, 10.0))
        corners = [table[:, face, i + di, j + dj] for di, dj in ((0, 0), (1, 0), (0, 1), (1, 1))]
        value = exposure.factor(np.broadcast_to(direction, (40, 3)))
        np.testing.assert_allclose(value, _bilinear(*corners, fx, fy), rtol=0, atol=1e-12)
        agree = (corners[0] == corners[1]) & (corners[1] == corners[2]) & (corners[2] == corners[3])
        assert np.array_equal(value[agree], corners[0][agree])


def test_a_refined_cell_is_its_sub_nodes_at_theirs_and_bilinear_between():
    """A refined cell's value at each of its 49 sub-nodes is that sub-node's bit, and between them the bilinear
    interpolation of the four sub-nodes around the direction (exactly their value where they agree)."""
    from fem_loads.exposure import SUB_CELLS, _sub_nodes

    base = _random_exposure(3)
    rng = np.random.default_rng(4)
    n, count = RESOLUTION, len(base.columns)
    rows, cells = rng.integers(0, count, 40), rng.choice(6 * n * n, 40, replace=False)
    bits = rng.integers(0, 2, (40, (SUB_CELLS + 1) ** 2))
    faces, i, j = np.unravel_index(cells, (6, n, n))
    for corner_i, corner_j in ((0, 0), (1, 0), (0, 1), (1, 1)):  # the corners are the table's
        bit = (SUB_CELLS * corner_j) * (SUB_CELLS + 1) + SUB_CELLS * corner_i
        bits[:, bit] = 1 - base.table[rows, faces, i + corner_i, j + corner_j]
    packed = (bits << np.arange(bits.shape[1])).sum(axis=1)
    exposure = Exposure(base.columns, base.table, np.column_stack([rows, cells, packed]))
    sub = _sub_nodes(n, faces, i, j)  # (40, 49, 3)
    inside = sub * (1.0 - 1e-12) + sub.mean(axis=1, keepdims=True) * 1e-12  # on the node, just inside the cell
    for k in range(40):
        directions = np.broadcast_to(inside[k][:, None, :], (sub.shape[1], count, 3))
        value = exposure.factor(directions)[:, rows[k]]
        np.testing.assert_allclose(value, 1 - bits[k], atol=1e-9)
        for fx, fy in rng.uniform(1e-3, 1.0 - 1e-3, (20, 2)):
            direction = _on_face(faces[k], 2.0 * (i[k] + fx) / n - 1.0, 2.0 * (j[k] + fy) / n - 1.0)
            a, b = int(fx * SUB_CELLS), int(fy * SUB_CELLS)  # the sub-cell
            first = b * (SUB_CELLS + 1) + a
            corners = 1.0 - bits[k, [first, first + 1, first + SUB_CELLS + 1, first + SUB_CELLS + 2]]
            value = exposure.factor(np.broadcast_to(direction, (count, 3)))[rows[k]]
            expected = _bilinear(*corners, fx * SUB_CELLS - a, fy * SUB_CELLS - b)
            assert value == pytest.approx(expected, rel=0, abs=1e-12)
            if np.all(corners == corners[0]):
                assert value == corners[0]


@pytest.fixture(scope="module")
def groove_wall(tmp_path_factory):
    """The rear wall of a 10 mm wide, 10 mm deep ring groove around the 105 mm body's shank (20 mm mesh): 1400
    points across it, their exposure as the tool computes it, the ray tracer of the body's surface, and each
    point's area."""
    import trimesh
    from trimesh.ray.ray_pyembree import RayMeshIntersector

    from cases.run.prepare import body_mesh
    from fem_loads.exposure import exposure_table
    from mesh.geometry import outer_triangles

    path = write_changed_body(tmp_path_factory.mktemp("groove") / "groove.step", groove=(0.3, 0.01, 0.01))
    scene = load_scene(
        scene_path("forrestal_luk_test2"),
        {"projectile": {"geometry": {"file": str(path), "unit": "mm"}, "body_density": 7850.0}},
    )
    prepared = prepare_projectile(scene)
    mesh, _ = body_mesh(prepared.geometry, scene.numerics.mesh_size, scene.numerics.geometry_order)
    triangles = outer_triangles(mesh) - prepared.mass.centre
    q = prepared.quadrature
    radius = np.hypot(q.points[:, 1], q.points[:, 2])
    wall_x = float(np.median(q.points[(q.normals[:, 0] > 0.99) & (radius < 0.052) & (radius > 0.043), 0]))
    r, theta = np.meshgrid(np.linspace(0.0425 + 1e-4, 0.0525 - 1e-5, 200), np.radians([0, 30, 60, 90, 120, 150, 180]))
    probes = np.column_stack([np.full(r.size, wall_x), (r * np.cos(theta)).ravel(), (r * np.sin(theta)).ravel()])
    normals = np.tile([1.0, 0.0, 0.0], (len(probes), 1))
    exposure = Exposure(*exposure_table(probes, normals, triangles, 0.05 * scene.numerics.mesh_size))
    surface = trimesh.Trimesh(triangles.reshape(-1, 3), np.arange(triangles.size // 3).reshape(-1, 3))
    return probes, normals, exposure, RayMeshIntersector(surface), r.ravel()


@pytest.mark.parametrize("attack", [3.0, 5.0, 8.0])
@pytest.mark.slow  # seconds of runs: CI's slow step
def test_a_groove_s_rear_wall_is_exposed_as_exact_rays_expose_it(groove_wall, attack):
    """At 3, 5 and 8 degrees of attack in every roll, the area of the groove's rear wall (facing forward) that the
    exposure leaves loaded is that of exact rays from the same points within 2 % (measured: +0.8, +0.3, +0.1 %;
    bilinear between the coarse nodes alone gave +5 to +8 %, and rays lifted a twentieth of an element, which
    start inside the groove, -1 to -4 %)."""
    probes, normals, exposure, tracer, area = groove_wall
    tabled = exact = 0.0
    for roll in np.radians(np.arange(0.0, 360.0, 10.0)):
        a = math.radians(attack)
        d = np.array([math.cos(a), math.sin(a) * math.cos(roll), math.sin(a) * math.sin(roll)])
        e = np.ones(len(probes))
        e[exposure.columns] = exposure.factor(np.broadcast_to(d, (len(exposure.columns), 3)))
        tabled += float(area @ e)
        exact += float(area @ ~tracer.intersects_any(probes + 1e-6 * normals, np.broadcast_to(d, probes.shape)))
    assert tabled == pytest.approx(exact, rel=0.02)
