"""Meshes: regions, symmetry, orientation and meshio round trips."""

import numpy as np
import pytest

from mesh import (
    BODY,
    COUNTERWEIGHT,
    ConeNose,
    OgiveNose,
    Profile,
    ProjectileGeometry,
    build_mesh,
    read_mesh,
    write_mesh,
)


def _tet_volumes(mesh):
    p = mesh.points[mesh.tetra[:, :4]]
    return np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0]) / 6


@pytest.mark.parametrize("order", [1, 2])
def test_regions_orientation_and_symmetry(projectile3, order):
    mesh = build_mesh(projectile3, 0.02, order)
    assert mesh.tetra.shape[1] == (4 if order == 1 else 10)
    assert set(np.unique(mesh.tetra_region)) == {BODY, COUNTERWEIGHT}
    assert np.all(_tet_volumes(mesh) > 0)
    # the counterweight lies between its two cross-sections
    x1, x2 = projectile3.counterweight
    s = -mesh.points[mesh.tetra[mesh.tetra_region == COUNTERWEIGHT][:, :4], 0]
    assert s.min() >= x1 - 1e-9 and s.max() <= x2 + 1e-9
    # every node's mirror images in y = 0 and z = 0 are nodes (bitwise)
    nodes = {tuple(p) for p in mesh.points}
    for flip in ([1, -1, 1], [1, 1, -1], [1, -1, -1]):
        assert all(tuple(p) in nodes for p in mesh.points * flip)
    # the outer surface: outward corner normals
    tri = mesh.points[mesh.outer[:, :3]]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    centroid = tri.mean(axis=1)
    lateral = ~np.isclose(centroid[:, 0], -0.93)
    radial = np.einsum("ij,ij->i", normal[lateral, 1:], centroid[lateral, 1:])
    assert np.all(radial > 0)


@pytest.mark.parametrize("nose", [OgiveNose(0.5), OgiveNose(20.0), ConeNose(5.0), ConeNose(60.0)])
def test_extreme_noses_mesh(nose):
    mesh = build_mesh(ProjectileGeometry(Profile(0.1, 0.6, nose)), 0.02, 2)
    assert len(mesh.tetra) > 100 and np.all(_tet_volumes(mesh) > 0)


@pytest.mark.parametrize("order", [1, 2])
def test_meshio_round_trip(tmp_path, projectile3, order):
    mesh = build_mesh(projectile3, 0.03, order)
    write_mesh(mesh, tmp_path / "p.vtu")
    back = read_mesh(tmp_path / "p.vtu")
    assert back.order == order
    np.testing.assert_array_equal(back.points, mesh.points)
    np.testing.assert_array_equal(back.tetra, mesh.tetra)
    np.testing.assert_array_equal(back.tetra_region, mesh.tetra_region)
    np.testing.assert_array_equal(back.outer, mesh.outer)
    assert [p.name for p in tmp_path.iterdir()] == ["p.vtu"]
    # the format is VTU whatever the name says (the cache writes to temporary names)
    write_mesh(mesh, tmp_path / "q.tmp")
    np.testing.assert_array_equal(read_mesh(tmp_path / "q.tmp").points, mesh.points)


def test_bad_mesh_requests():
    g = ProjectileGeometry(Profile(0.1, 0.6, OgiveNose(3.0)))
    with pytest.raises(ValueError, match="order"):
        build_mesh(g, 0.02, 3)
    with pytest.raises(ValueError, match="mesh size"):
        build_mesh(g, -1.0, 2)
