"""``penetrate map``: the critical speed over a grid, each point the search ``penetrate critical`` makes; the
files it writes; an interrupted map resumes from the run store; bad grids are refused in one line."""

import json

import pytest

from cases import scene_path
from cases.cli import main
from cases.run import RunStore
from cases.scene import InputError
from cases.studies import Pool, Sweep, Variation, find_critical_velocity
from cases.studies.speeds.stability_map import stability_map

COARSE = {"numerics.mesh_size": 0.04}
OVER = ["impact.attack_angle=1:2:1", "impact.oblique_angle=0,10"]
POOL = Pool(workers=2, progress=False)


@pytest.fixture(scope="module")
def mapped(tmp_path_factory):
    folder = tmp_path_factory.mktemp("map")
    record = stability_map(scene_path("paper_p3"), COARSE, OVER, RunStore(folder / "store"), folder / "out", pool=POOL)
    return folder, record


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_each_point_is_the_critical_search_of_its_scene(mapped):
    folder, record = mapped
    assert record["keys"] == ["impact.attack_angle", "impact.oblique_angle"]
    assert [(p["impact.attack_angle"], p["impact.oblique_angle"]) for p in record["points"]] == [
        (1, 0),
        (1, 10),
        (2, 0),
        (2, 10),
    ]
    for point in record["points"]:
        values = {key: point[key] for key in record["keys"]}
        base = Sweep.from_file(scene_path("paper_p3"), COARSE, [Variation(values)])
        unguided = find_critical_velocity(base, RunStore(folder / "store"), (200.0, 1600.0), 5.0, POOL, guide="none")
        assert point["guide"] == "reduced" and point["runs"] <= len(unguided.indicator)
        assert abs(point["critical_velocity"] - unguided.critical_velocity) <= 5.0
    # a larger attack angle turns the body sooner: the critical speed falls (docs/paper.md)
    by = {(p["impact.attack_angle"], p["impact.oblique_angle"]): p["critical_velocity"] for p in record["points"]}
    assert by[(2, 0)] < by[(1, 0)] and by[(2, 10)] < by[(1, 10)]


def test_the_map_writes_its_table_record_report_and_figure(mapped):
    folder, record = mapped
    out = folder / "out"
    assert (out / "map.png").stat().st_size > 10_000
    rows = (out / "map.csv").read_text().splitlines()
    assert len(rows) == 5 and rows[0].startswith("impact.attack_angle,impact.oblique_angle,critical_velocity")
    written = json.loads((out / "map.json").read_text())
    assert written["points"] == json.loads(json.dumps(record["points"]))
    assert "| 2 | 10 |" in (out / "map.md").read_text()


def test_an_interrupted_map_resumes_from_the_store(tmp_path):
    """A map whose last runs were lost (as if killed before they were stored) makes only those again."""
    store = RunStore(tmp_path / "store")
    over = ["impact.attack_angle=1,2"]
    first = stability_map(scene_path("paper_p3"), COARSE, over, store, tmp_path / "a", pool=POOL)
    records = sorted((tmp_path / "store").rglob("*.json"))
    lost = records[-2:]
    for path in lost:
        path.unlink()
    again = stability_map(scene_path("paper_p3"), COARSE, over, store, tmp_path / "b", pool=POOL)
    assert again["points"] == first["points"]
    assert sorted((tmp_path / "store").rglob("*.json")) == records  # the lost runs made again, and only those


@pytest.mark.parametrize(
    "overs, message",
    [
        ([], "--grid: give one or two"),
        (["impact.attack_angle=1,2"] * 2, "--grid: impact.attack_angle given twice"),
        (["impact.speed=800:900:50"], "--grid impact.speed: the map searches the impact speed"),
        (["impact.attack_angle=0:1:0.0001", "impact.oblique_angle=0:1:0.1"], "--grid: 110011 points"),
        (["impact.attack_angle=1:0:1"], "--grid 'impact.attack_angle=1:0:1': need STEP > 0 and STOP >= START"),
    ],
)
def test_bad_grids_are_refused_in_one_line(tmp_path, overs, message):
    with pytest.raises(InputError) as error:
        stability_map(scene_path("paper_p3"), COARSE, overs, RunStore(tmp_path), tmp_path / "out", pool=POOL)
    assert str(error.value).startswith(message) and "\n" not in str(error.value)
    assert not (tmp_path / "out").exists()


def test_the_command_prints_the_map(tmp_path, capsys):
    args = ["map", str(scene_path("paper_p3")), "--set", "numerics.mesh_size=0.04", "--grid", "impact.attack_angle=2"]
    common = ["--store", str(tmp_path / "store"), "--out", str(tmp_path / "out"), "--workers", "2", "--no-progress"]
    assert main([*args, *common]) == 0
    out = capsys.readouterr().out
    assert out.startswith("# Critical impact velocity of ") and "| 2 | " in out
    assert main([*args, *common, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["points"][0]["guide"] == "reduced"
    assert main(["map", str(scene_path("paper_p3")), "--grid", "impact.speed=1,2", *common]) == 2
