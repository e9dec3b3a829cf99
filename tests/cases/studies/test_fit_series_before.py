"""fit --series: the held-out shots' "before the fit" predictions are each shot's own scene, as validate runs it.

The series below has two concrete groups of different compressive strengths, so the fitted key,
``target.law.S``, is filled in by Frew et al.'s formula with a different value on each shot: a prediction
"before the fit" made with the first shot's ``S`` set on every shot would be the wrong group's.
"""

from __future__ import annotations

import pytest

from cases.run import RunStore
from cases.studies.engine.pool import Pool
from cases.studies.measured.fit_series import fit_series, parse_holdout
from cases.studies.measured.series import parse_series
from cases.studies.measured.validate import validate
from fem_loads.resistance import concrete_strength_factor

SERIAL = Pool(workers=1, progress=False)
COARSE = [("numerics.mesh_size", 0.012)]  # the checks are of the plumbing, not of the mesh

# the shipped 1996 grout (51 MPa, two of its shots) and a weaker grout, held out
TWO_STRENGTHS = """\
label,group,scene,impact.speed,target.law.compressive_strength,measured.depth
v405,51 MPa,forrestal1996_concrete,405,51e6,0.370
v545,51 MPa,forrestal1996_concrete,545,51e6,0.560
w492,21.6 MPa,forrestal1996_concrete,492,21.6e6,0.650
w700,21.6 MPa,forrestal1996_concrete,700,21.6e6,1.150
"""


def test_before_the_fit_is_each_held_out_shots_own_scene(tmp_path):
    series = parse_series(TWO_STRENGTHS, tmp_path, "two_strengths.csv")
    held = ["w492", "w700"]
    result = fit_series(
        series,
        COARSE,
        ["target.law.S=5:20"],
        RunStore(tmp_path / "fit-store"),
        SERIAL,
        holdout=parse_holdout("group=21.6 MPa"),
        max_evaluations=3,
    )
    # the held-out shots' own S is not the first shot's, which the fit starts from
    assert result.starts["target.law.S"] == pytest.approx(concrete_strength_factor(51e6), rel=1e-12)
    assert concrete_strength_factor(21.6e6) > 1.4 * concrete_strength_factor(51e6)
    assert result.predictions is not None and result.predictions["held_out"] == held
    # validate's predictions, in a store of their own: runs made apart from the fit's
    validation = validate(series, COARSE, RunStore(tmp_path / "validate-store"), SERIAL, curve_points=0)
    validated = {row["label"]: row for row in validation.rows}
    before = result.predictions["start_rows"]
    assert [row["label"] for row in before] == held
    for row in before:
        own = validated[row["label"]]
        assert row["predicted"] is not None and own["predicted"] is not None
        assert row["predicted"] == pytest.approx(own["predicted"], rel=1e-6), row["label"]
        assert row["error_percent"] == pytest.approx(own["error_percent"], rel=1e-6), row["label"]
    summary = result.predictions["start_summary"]["depth"]
    expected = [validated[label]["error_percent"] for label in held]
    assert summary["bias_percent"] == pytest.approx(sum(expected) / len(expected), rel=1e-9)
