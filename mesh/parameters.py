"""A CAD surface's parameter plane: the parameters of mesh nodes on it, and quadrature rules laid in it.

Used by :class:`mesh.cad.CadSurface` (quadrature on the exact surface) and by the mesher's fix of the
edge nodes at a pole (:mod:`mesh.cad`); each function works on the current gmsh model.
"""

from __future__ import annotations

import math

import numpy as np

from .geometry import TRI_EDGES

__all__ = ["node_parameters", "parameter_rule", "straighten_inner_edges"]


def parameter_rule(uv: np.ndarray, ref_points: np.ndarray, ref_weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each facet's rule points in its parameter triangle, and their weights in the parameter plane.

    ``uv``: (m, 3, 2) corner parameters, or (m, 6, 2) with the edge nodes', NaN in the degenerate
    parameter of a corner at a pole (:func:`node_parameters`).  A facet without a pole maps the
    triangle rule linearly through its corners, or quadratically through its six nodes, with the
    Jacobian of that map at each point.  A facet with a pole covers the region between the
    meridians of its other two corners: with ``t`` across it and ``s`` from the pole,
    ``a = a1 + (a2 - a1) t`` in the degenerate parameter and ``b = (1 - s) b0 + s (1 - t) b1 + s t b2``
    in the other, so the facets around a pole tile the surface there as they do elsewhere.  The
    integrand is smooth in ``(t, s)`` but rational in the triangle's own coordinates, so those
    facets take a Gauss-Legendre product rule on the square with as many points as the triangle
    rule has (the few left over carry zero weight).
    """
    q = len(ref_weights)
    shapes, gradients = _triangle_shapes(ref_points, uv.shape[1])  # (q, k), (q, k, 2)
    known = np.nan_to_num(uv)
    at = np.einsum("qk,mkd->mqd", shapes, known)
    jacobian = np.einsum("qke,mkd->mqde", gradients, known)  # d(u, v) / d(xi, eta)
    determinant = jacobian[..., 0, 0] * jacobian[..., 1, 1] - jacobian[..., 0, 1] * jacobian[..., 1, 0]
    weight = np.abs(determinant) * ref_weights[None, :]
    t, s, square_weights = _square_rule(q)
    for row, corner in zip(*np.nonzero(np.isnan(uv[:, :3]).any(axis=2))):
        d = int(np.flatnonzero(np.isnan(uv[row, corner]))[0])  # the degenerate parameter
        e = 1 - d
        first, second = (corner + 1) % 3, (corner + 2) % 3
        p0, p1, p2 = uv[row, [corner, first, second]]
        # the far edge, from p1 to p2: through its edge node where the facet has one, as its neighbour's is
        far = p1 + (p2 - p1) * t[:, None]
        slope = np.broadcast_to(p2 - p1, far.shape).copy()
        if uv.shape[1] == 6:
            middle = uv[row, 3 + TRI_EDGES.index((min(first, second), max(first, second)))]
            bulge = middle - 0.5 * (p1 + p2)
            far += 4.0 * (t * (1.0 - t))[:, None] * bulge
            slope += 4.0 * (1.0 - 2.0 * t)[:, None] * bulge
        at[row, :, d] = far[:, d]
        at[row, :, e] = p0[e] + s * (far[:, e] - p0[e])
        weight[row] = square_weights * np.abs(slope[:, d] * (far[:, e] - p0[e]))
    return at, weight


def straighten_inner_edges(uv: np.ndarray, edge_nodes: np.ndarray) -> None:
    """Put the parameters of the edge nodes of the edges inside a surface halfway between their corners' (in place).

    ``uv``: (m, 6, 2) the facets' node parameters; ``edge_nodes``: (m, 3, 3) their edge nodes.  An edge
    inside the surface (its node shared by two of these facets) is straight in the parameter plane, as
    with corners alone: the mesh's edge node, off the chord's midpoint in the parameters where they
    are strongly curved (near a pole), would only distort both facets' maps.  An edge on the surface's
    boundary keeps its node, which the mesh put on the boundary curve, so that the facet follows the
    curve where its neighbour (on another surface) does.
    """
    flat = edge_nodes.reshape(-1, 3)
    _, first, counts = np.unique(flat, axis=0, return_inverse=True, return_counts=True)
    inner = (counts[first.reshape(-1)] > 1).reshape(-1, 3)
    for k, (i, j) in enumerate(TRI_EDGES):
        rows = inner[:, k]
        uv[rows, 3 + k] = 0.5 * (uv[rows, i] + uv[rows, j])


def _triangle_shapes(ref_points: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """The linear (3 nodes) or quadratic (6: corners, then edges in the order of :data:`TRI_EDGES`) Lagrange
    shape functions of the reference triangle at ``ref_points``, shape (q, count), and their gradients in
    ``(xi, eta)``, shape (q, count, 2)."""
    xi, eta = ref_points
    barycentric = np.column_stack([1.0 - xi - eta, xi, eta])  # (q, 3)
    grad = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])  # d(barycentric) / d(xi, eta)
    if count == 3:
        return barycentric, np.broadcast_to(grad, (len(xi), 3, 2))
    shapes = [barycentric[:, i] * (2.0 * barycentric[:, i] - 1.0) for i in range(3)]
    gradients = [(4.0 * barycentric[:, i] - 1.0)[:, None] * grad[i] for i in range(3)]
    for i, j in TRI_EDGES:
        shapes.append(4.0 * barycentric[:, i] * barycentric[:, j])
        gradients.append(4.0 * (barycentric[:, j][:, None] * grad[i] + barycentric[:, i][:, None] * grad[j]))
    return np.column_stack(shapes), np.stack(gradients, axis=1)


def _square_rule(q: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A Gauss-Legendre product rule on the unit square with ``q`` points, padded with zero weights."""
    across = max(1, math.isqrt(q))
    along = q // across
    a, wa = np.polynomial.legendre.leggauss(across)
    b, wb = np.polynomial.legendre.leggauss(along)
    t = np.zeros(q)
    s = np.full(q, 0.5)
    w = np.zeros(q)
    t[: across * along] = np.repeat(0.5 * (a + 1.0), along)
    s[: across * along] = np.tile(0.5 * (b + 1.0), across)
    w[: across * along] = 0.25 * np.outer(wa, wb).ravel()
    return t, s, w


def node_parameters(entity: int, nodes: np.ndarray) -> np.ndarray:
    """The parameters ``(u, v)`` of each facet's nodes on a CAD surface, shape (m, k, 2) for nodes (m, k, 3).

    A periodic parameter (a surface of revolution's angle) is unwrapped facet by facet so that
    no facet spans the seam the long way round; a node at a pole (where ``x_u = 0``, the apex
    of a nose) has NaN for the parameter that is arbitrary there (:func:`parameter_rule`).
    """
    import gmsh

    m, k = nodes.shape[:2]
    flat = nodes.reshape(-1, 3)
    uv = np.asarray(gmsh.model.getParametrization(2, entity, flat.ravel().tolist())).reshape(m, k, 2)
    # poles: the derivative along one parameter vanishes there, and that parameter is arbitrary (NaN)
    derivative = np.asarray(gmsh.model.getDerivative(2, entity, uv.reshape(-1).tolist())).reshape(m, k, 2, 3)
    speed = np.linalg.norm(derivative, axis=3)  # (m, k, 2)
    poles = [speed[:, :, d] < 1e-9 * np.maximum(speed[:, :, 1 - d], np.finfo(float).tiny) for d in range(2)]
    for d in range(2):
        uv[:, :, d][poles[d]] = np.nan
    low, high = (np.asarray(b) for b in gmsh.model.getParametrizationBounds(2, entity))
    scale = float(np.ptp(flat, axis=0).max()) or 1.0
    # a patch of a periodic surface (a quarter of a surface of revolution across its seam): a corner on
    # the seam may come back a period (an angle: 2 pi) away from the patch
    for d in range(2):
        margin = 1e-9 * max(high[d] - low[d], 1.0)
        for shift in (2.0 * math.pi, -2.0 * math.pi):
            outside = (uv[:, :, d] < low[d] - margin) | (uv[:, :, d] > high[d] + margin)
            moved = uv[:, :, d] + shift
            back = outside & (moved >= low[d] - margin) & (moved <= high[d] + margin)
            if back.any():
                trial = uv[back].copy()
                trial[:, d] += shift
                same = np.asarray(gmsh.model.getValue(2, entity, trial.ravel().tolist())).reshape(-1, 3)
                ok = np.linalg.norm(same - flat.reshape(m, k, 3)[back], axis=1) < 1e-9 * scale
                rows, cols = np.nonzero(back)
                uv[rows[ok], cols[ok], d] += shift
    for d in range(2):
        period = high[d] - low[d]
        probe = np.array([0.5 * (low + high)] * 2)
        probe[0, d], probe[1, d] = low[d], high[d]
        ends = np.asarray(gmsh.model.getValue(2, entity, probe.ravel().tolist())).reshape(2, 3)
        if np.linalg.norm(ends[0] - ends[1]) < 1e-9 * scale:  # closed in this direction: unwrap
            values = uv[:, :, d]
            with np.errstate(invalid="ignore"):
                wide = np.nanmax(values, axis=1) - np.nanmin(values, axis=1) > 0.5 * period
                values[wide] = np.where(values[wide] < low[d] + 0.5 * period, values[wide] + period, values[wide])
    return uv
