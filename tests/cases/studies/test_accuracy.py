"""The accuracy study on a tiny grid: references, errors and the Pareto front."""

import numpy as np
import pandas as pd
import pytest

from cases import scene_path
from cases.run import RunStore
from cases.studies import Pool
from cases.studies.numerics.accuracy import _pareto, accuracy_study


def test_pareto_front():
    error = np.array([1e-2, 1e-3, 1e-3, 1e-4, np.nan])
    cost = np.array([1.0, 2.0, 3.0, 10.0, 0.1])
    assert _pareto(error, cost).tolist() == [True, True, False, True, False]


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_normal_impact_uses_the_exact_reference(tmp_path):
    table, reference = accuracy_study(
        scene_path("forrestal_luk_test2"),
        None,
        RunStore(tmp_path / "s"),
        tmp_path / "out",
        sizes=(0.04, 0.02),
        steps=(8e-5, 4e-5),
        rtols=(1e-4,),
        pool=Pool(workers=2, progress=False),
        quadrature_orders=(4,),
    )
    assert reference["kind"].startswith("1-D integration")
    # mesh axis 2 sizes x 2 orders x 2 normal models, quadrature axis 2 sizes x 1 order, time axis
    # one more step and one tolerance, combined axis the one size x step pair not yet run, and the
    # scene as it is
    assert list(table["axis"].value_counts().sort_index().items()) == [
        ("combined", 1),
        ("mesh", 8),
        ("quadrature", 2),
        ("scene", 1),
        ("time", 2),
    ]
    quadrature = table[table["axis"] == "quadrature"].set_index("numerics.mesh_size")["depth_error"]
    mesh_q2 = table[
        (table["axis"] == "mesh") & (table["numerics.geometry_order"] == 2) & (table["numerics.normals"] == "exact")
    ].set_index("numerics.mesh_size")["depth_error"]
    assert quadrature[0.02] < mesh_q2[0.02]  # more points per facet: smaller error at the same mesh
    # exact normals beat flat mesh normals on flat facets; refinement helps the exact model
    by = table.set_index(
        [
            "numerics.mesh_size",
            "numerics.geometry_order",
            "numerics.normals",
            "numerics.integrator",
            "numerics.time_step",
        ]
    )["depth_error"]
    by = by[~by.index.duplicated()]  # the finest mesh at the finest step is on both axes
    assert by[(0.02, 1, "exact", "rk4", 4e-5)] < 0.1 * by[(0.02, 1, "mesh", "rk4", 4e-5)]
    assert by[(0.02, 2, "exact", "rk4", 4e-5)] < by[(0.04, 2, "exact", "rk4", 4e-5)]
    assert table["pareto"].any()
    assert {p.name for p in (tmp_path / "out").iterdir()} == {"accuracy.md", "accuracy.csv", "accuracy.png"}


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_contact_incidence_study_tends_to_the_sharp_law(tmp_path):
    """Test 2 at its own 20 mm mesh: the depth's change from the sharp law falls as the contact incidence
    does, and equals the change the independent 1-D integration gives with the same incidence within 15 %
    (measured: 2 % at 0.04, 13 % at 0.02).  The change comes from the band of the ogive's shoulder whose
    slope is below the incidence, 11 mm long at 0.04 and 6 mm at 0.02, less than one element: the mesh
    samples it with a few points, so the agreement degrades as the band narrows (2x at 0.01)."""
    from cases.studies.numerics.contact import contact_study

    table = contact_study(
        scene_path("forrestal_luk_test2"),
        None,
        RunStore(tmp_path / "s"),
        tmp_path / "out",
        incidences=(0.04, 0.02),
        step=4e-5,
        pool=Pool(workers=2, progress=False),
    )
    assert list(table["contact_incidence"]) == [0.04, 0.02, 0.0]
    change = table["depth_change"].to_numpy()
    assert change[0] > change[1] > 0 == change[2]
    change_1d = (table["depth_1d"] - table["depth_1d"].iloc[-1]).to_numpy()
    np.testing.assert_allclose(change[:2], change_1d[:2], rtol=0.15)
    assert {p.name for p in (tmp_path / "out").iterdir()} == {"contact.md", "contact.csv"}


def test_time_convergence_orders_of_a_known_error():
    """A depth with a step error of exactly ``c h^4`` on each mesh: orders 4, errors against each mesh's finest step,
    and that mesh's error against the reference."""
    import pandas as pd

    from cases.studies.numerics.accuracy import time_convergence

    rows = []
    for size, exact in ((0.04, 5.0), (0.02, 5.1)):
        for h in (4e-5, 2e-5, 1e-5, 5e-6):
            rows.append(
                {
                    "axis": "combined",
                    "key": f"{size}-{h}",
                    "numerics.integrator": "rk4",
                    "numerics.geometry_order": 2,
                    "numerics.normals": "exact",
                    "numerics.quadrature_order": 2,
                    "numerics.mesh_size": size,
                    "numerics.time_step": h,
                    "steps": round(1e-2 / h),
                    "depth": exact + 1e15 * h**4,
                    "axis_angle_change": 2.0 - 1e16 * h**4,
                    "convergence_speed": np.nan,
                    "depth_error": abs(exact + 1e15 * h**4 - 5.2) / 5.2,
                    "integration_time": 1e-4 / h,
                }
            )
    rows.append({**rows[-1], "axis": "scene"})  # the scene's own row is not a point of the ladder
    table = time_convergence(pd.DataFrame(rows))
    assert list(table["numerics.mesh_size"]) == [0.04] * 3 + [0.02] * 3
    coarse = table[table["numerics.mesh_size"] == 0.02]
    np.testing.assert_allclose(
        coarse["depth_time_error"], 1e15 * (np.array([4e-5, 2e-5, 1e-5]) ** 4 - 5e-6**4) / (5.1 + 1e15 * 5e-6**4)
    )
    orders = table["depth_order"].dropna().to_numpy()
    assert len(orders) == 4 and np.all((orders > 4.0) & (orders < 4.2))  # 4 plus the finest step's own error
    np.testing.assert_allclose(table["axis_angle_order"].dropna(), table["depth_order"].dropna(), rtol=1e-3)
    assert table["convergence_speed_time_error"].isna().all()
    np.testing.assert_allclose(coarse["mesh_error"], abs(5.1 + 1e15 * 5e-6**4 - 5.2) / 5.2)


def test_entry_study_tables_each_smoothing_against_its_own_finest_step(tmp_path):
    """Test 2 on a 40 mm mesh, two smoothings x three steps: time errors against the finest step of the same
    smoothing (zero there), changes against the smaller smoothing; a longer entry smoothing moves the depth by less
    than a fortieth of the 40 mm mesh error (4e-3 relative, 2 cm; measured 0.18 mm)."""
    from cases.studies.numerics.contact import entry_study

    table = entry_study(
        scene_path("forrestal_luk_test2"),
        {"numerics.mesh_size": 0.04},
        RunStore(tmp_path / "s"),
        tmp_path / "out",
        smoothings=(4.0, 1.0),
        steps=(1e-4, 2e-4, 5e-5),
        pool=Pool(workers=2, progress=False),
    )
    assert list(zip(table["entry_smoothing"], table["time_step"])) == [
        (1.0, 2e-4),
        (1.0, 1e-4),
        (1.0, 5e-5),
        (4.0, 2e-4),
        (4.0, 1e-4),
        (4.0, 5e-5),
    ]
    finest = table[table["time_step"] == 5e-5]
    assert (finest["depth_time_error"] == 0).all()
    assert finest["depth_change"].iloc[0] == 0.0
    assert 0 < abs(finest["depth_change"].iloc[1]) < 1e-4 * finest["depth"].iloc[1]
    assert (table["depth_time_error"].iloc[[0, 1, 3, 4]] > 0).all()
    assert "| 4 |" in (tmp_path / "out" / "entry.md").read_text()


def test_a_change_at_round_off_is_reported_as_zero():
    """Two runs of one setting summed in another order differ by ~1e-16 of the value: shown as 0,
    while a real change, however small against the value's unit, keeps its digits."""
    from cases.studies.numerics.contact import _change

    row = pd.Series(
        {
            "depth": 5.039502,
            "depth_change": 2.66e-15,
            "path_length": 5.0,
            "path_length_change": 8.3e-8,
            "convergence_speed": float("nan"),
            "convergence_speed_change": float("nan"),
        }
    )
    assert _change(row, "depth") == "+0.00e+00"
    assert _change(row, "path_length") == "+8.30e-08"
    assert _change(row, "convergence_speed") == "-"
