"""``penetrate formulas``: the empirical equations for a scene, what it refuses, and its one JSON object."""

from __future__ import annotations

import contextlib
import io
import json

import pytest

from cases import load_scene, scene_path
from cases.cli import main
from cases.reference import empirical as eq
from cases.scene import InputError
from cases.studies.measured.formulas import formula_inputs, formulas

MEASURED = 0.37  # m: Forrestal et al. (1996), the 1.60 kg rod into 51 MPa concrete at 405 m/s (the scene's shot)


def test_the_inputs_are_the_scene_s():
    """1.60 kg, 30.5 mm, CRH 3 (N* = 23/216, nose 1.658 diameters), 405 m/s, 51 MPa, 2300 kg/m^3, a half-space."""
    inputs = formula_inputs(load_scene(scene_path("forrestal1996_concrete")))
    assert inputs.mass == pytest.approx(1.60, rel=1e-6) and inputs.diameter == pytest.approx(0.0305)
    assert inputs.nose_factor == pytest.approx(23 / 216) and inputs.nose_length == pytest.approx(0.0305 * 2.75**0.5)
    assert (inputs.speed, inputs.strength, inputs.density) == (405.0, 51e6, 2300.0)
    assert inputs.thickness == float("inf") and (inputs.ndrc_nose, inputs.young_nose) == ("very_sharp", "ogive")


def test_forrestal_1996_shot():
    """Every formula's depth is the function of the scene's inputs; Li and Chen's, whose S was fitted to concrete
    shots of this kind, lies within 5 % of the measured 0.37 m; the UKAEA's data end at 300 m/s and 44 MPa."""
    scene = load_scene(scene_path("forrestal1996_concrete"))
    result = formulas(scene)
    by_name = {e.name: e for e in result.estimates}
    i = result.inputs
    assert by_name["modified NDRC"].depth == eq.ndrc_depth(i.mass, i.diameter, i.speed, i.strength, 1.14)
    assert by_name["ACE"].depth == eq.ace_depth(i.mass, i.diameter, i.speed, i.strength)
    assert by_name["Li and Chen"].depth == pytest.approx(MEASURED, rel=0.05)
    assert not by_name["UKAEA"].valid and by_name["modified NDRC"].valid
    assert any("UKAEA: impact speed = 405 m/s lies outside its range 25-300 m/s" in m for m in result.messages)
    slower = formulas(scene.model_copy(update={"impact": scene.impact.model_copy(update={"speed": 250.0})}))
    assert all(a.depth < b.depth for a, b in zip(slower.estimates, result.estimates) if a.depth is not None)
    degen = by_name["Degen (perforation, on the NDRC's depth)"]  # a thickness only: no depth of its own
    x_ndrc = by_name["modified NDRC"].depth
    assert degen.depth is None and degen.perforation == eq.degen_perforation_thickness(x_ndrc, i.diameter) > x_ndrc


def test_an_oblique_shot_is_outside_every_formula():
    scene = load_scene(scene_path("forrestal1996_concrete"), {"impact.oblique_angle": 20.0})
    result = formulas(scene)
    assert not any(e.valid for e in result.estimates)
    assert sum("oblique angle = 20 deg" in m for m in result.messages) == len(result.estimates)


@pytest.mark.parametrize(
    ("scene", "overrides", "field"),
    [
        ("forrestal_luk_test2", [], "target.law = soil"),
        ("soil_over_sloping_concrete", [], "target.layers"),
    ],
)
def test_a_target_the_formulas_do_not_describe_is_refused(scene, overrides, field):
    with pytest.raises(InputError, match=field):
        formulas(load_scene(scene_path(scene), dict(overrides)))


def test_the_command_prints_one_object(tmp_path):
    out = tmp_path / "out"
    args = ["formulas", str(scene_path("forrestal1996_concrete")), "--out", str(out), "--json"]
    with contextlib.redirect_stdout(io.StringIO()) as printed:
        assert main(args) == 0
    record = json.loads(printed.getvalue())
    assert set(record) == {"inputs", "formulas", "messages"} and len(record["formulas"]) >= 4
    for entry in record["formulas"]:
        assert {"name", "depth", "valid", "checks", "source"} <= set(entry)
        assert entry["depth"] > 0 if entry["depth"] is not None else entry["perforation"] > 0
    assert sum(entry["depth"] is not None for entry in record["formulas"]) >= 4
    assert json.loads((out / "formulas.json").read_text()) == record
    assert (out / "formulas.md").read_text().startswith("# Empirical formulas: forrestal1996_concrete")
