"""The accuracy study on a tiny grid: references, errors and the Pareto front."""

import numpy as np

from cases import scene_path
from cases.run import RunStore
from cases.studies import Pool
from cases.studies.accuracy import _pareto, accuracy_study


def test_pareto_front():
    error = np.array([1e-2, 1e-3, 1e-3, 1e-4, np.nan])
    cost = np.array([1.0, 2.0, 3.0, 10.0, 0.1])
    assert _pareto(error, cost).tolist() == [True, True, False, True, False]


def test_normal_impact_uses_the_exact_reference(tmp_path):
    table, reference = accuracy_study(scene_path("forrestal_luk_test2"), None, RunStore(tmp_path / "s"),
                                      tmp_path / "out", sizes=(0.04, 0.02), steps=(8e-5, 4e-5), rtols=(1e-4,),
                                      pool=Pool(workers=2, progress=False), quadrature_orders=(4,))
    assert reference["kind"].startswith("1-D integration")
    # mesh axis 2 sizes x 2 orders x 2 normal models, quadrature axis 2 sizes x 1 order, time axis
    # one more step and one tolerance, combined axis the one size x step pair not yet run, and the
    # scene as it is
    assert list(table["axis"].value_counts().sort_index().items()) == [
        ("combined", 1), ("mesh", 8), ("quadrature", 2), ("scene", 1), ("time", 2)]
    quadrature = table[table["axis"] == "quadrature"].set_index("numerics.mesh_size")["depth_error"]
    mesh_q2 = table[(table["axis"] == "mesh") & (table["numerics.geometry_order"] == 2)
                    & (table["numerics.normals"] == "exact")].set_index("numerics.mesh_size")["depth_error"]
    assert quadrature[0.02] < mesh_q2[0.02]  # more points per facet: smaller error at the same mesh
    # exact normals beat flat mesh normals on flat facets; refinement helps the exact model
    by = table.set_index(["numerics.mesh_size", "numerics.geometry_order", "numerics.normals",
                          "numerics.integrator", "numerics.time_step"])["depth_error"]
    by = by[~by.index.duplicated()]  # the finest mesh at the finest step is on both axes
    assert by[(0.02, 1, "exact", "rk4", 4e-5)] < 0.1 * by[(0.02, 1, "mesh", "rk4", 4e-5)]
    assert by[(0.02, 2, "exact", "rk4", 4e-5)] < by[(0.04, 2, "exact", "rk4", 4e-5)]
    assert table["pareto"].any()
    assert {p.name for p in (tmp_path / "out").iterdir()} == {"accuracy.md", "accuracy.csv", "accuracy.png"}


def test_contact_width_study_tends_to_the_sharp_law(tmp_path):
    """Test 2 on a 40 mm mesh: the depth's change from the sharp law falls as the contact width does, and
    equals the change the independent 1-D integration gives with the same width (within 10 %)."""
    from cases.studies.contact import contact_study

    table = contact_study(scene_path("forrestal_luk_test2"), {"numerics.mesh_size": 0.04}, RunStore(tmp_path / "s"),
                          tmp_path / "out", widths=(1.5, 0.75), step=4e-5, pool=Pool(workers=2, progress=False))
    assert list(table["contact_width"]) == [1.5, 0.75, 0.0]
    change = table["depth_change"].to_numpy()
    assert change[0] > change[1] > 0 == change[2]
    change_1d = (table["depth_1d"] - table["depth_1d"].iloc[-1]).to_numpy()
    np.testing.assert_allclose(change[:2], change_1d[:2], rtol=0.1)
    assert {p.name for p in (tmp_path / "out").iterdir()} == {"contact.md", "contact.csv"}
