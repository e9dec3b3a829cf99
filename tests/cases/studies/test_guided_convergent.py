"""The guided convergent-velocity measurement: it starts at the first raised speed the reduced model finds
unstable, with the speed below it, and gives the unguided measurement's result with fewer runs; a guide
that is wrong costs runs, not the result."""

import pytest

from cases import scene_path
from cases.run import RunStore
from cases.studies import Pool, Sweep, measure_convergent_velocity
from cases.studies.speeds import characteristic as speeds_module
from cases.studies.speeds.guide import Guide

COARSE = {"numerics.mesh_size": 0.04, "impact.speed": 700.0}  # #3 at 700 m/s: stable, as at 805; 925.75 turns
POOL = Pool(workers=2, progress=False)


@pytest.fixture(scope="module")
def unguided(tmp_path_factory):
    store = RunStore(tmp_path_factory.mktemp("store"))
    base = Sweep.from_file(scene_path("paper_p3"), COARSE)
    return base, store, measure_convergent_velocity(base, store, pool=POOL, guide="none")


def test_the_guided_measurement_skips_the_stable_speeds_the_reduced_model_predicts(unguided):
    base, store, reference = unguided
    assert [run.speed for run in reference.runs] == [700.0, 805.0, 925.75]
    guided = measure_convergent_velocity(base, store, pool=POOL)
    assert guided.guide.guided and guided.guide.predicted == 925.75
    assert [run.speed for run in guided.runs] == [805.0, 925.75]
    assert guided.characteristic_convergent_velocity == reference.characteristic_convergent_velocity
    assert guided.message == (
        "the run at 700 m/s is stable; raised the impact speed to 925.75 m/s to get an unstable run;"
        " not run: 700 m/s, stable in the reduced model"
    )
    assert guided.as_dict()["guide"] == "reduced"


@pytest.mark.parametrize("raised, ran", [(4, [805.0, 925.75, 1064.61, 1224.30]), (1, [700.0, 805.0, 925.75, 1064.61])])
def test_a_wrong_guide_goes_down_or_on_up_to_the_same_result(monkeypatch, unguided, raised, ran):
    """Too high: the two speeds below it, then the next; too low: on up two speeds a round (two workers)."""
    base, store, reference = unguided
    monkeypatch.setattr(speeds_module, "convergent_guide", lambda *args: (Guide("reduced", "fake"), raised))
    guided = measure_convergent_velocity(base, store, pool=POOL)
    assert [run.speed for run in guided.runs] == pytest.approx(ran, abs=0.01)
    assert guided.characteristic_convergent_velocity == reference.characteristic_convergent_velocity
