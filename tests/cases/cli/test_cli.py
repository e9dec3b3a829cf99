"""The penetrate command as a user runs it."""

import argparse
import contextlib
import gc
import io
import json
import os
import re
import subprocess
import sys

import pandas as pd
import pytest

from cases import scene_path
from cases.cli import main
from cases.run import HISTORY_UNITS

FAST = ["--set", "numerics.mesh_size=0.03"]
LAWS = scene_path("paper_p3").parent / "laws" / "soil_laws.py"
REQUIRED = {"depth", "path_length", "end_reason", "final_speed", "max_attack_angle", "axis_angle_change", "wall_time"}


def penetrate(*args):
    return subprocess.run([sys.executable, "-m", "cases.cli", *args], capture_output=True, text=True, timeout=300)


def test_run_json_and_outputs(tmp_path):
    out = tmp_path / "run"
    done = penetrate("run", str(scene_path("forrestal_luk_test5")), *FAST, "--json", "--out", str(out))
    assert done.returncode == 0, done.stderr
    record = json.loads(done.stdout)
    assert record.keys() >= REQUIRED and record["end_reason"] == "stopped"
    assert 4.5 < record["path_length"] < 5.5 and record["depth"] <= record["path_length"]
    written = json.loads((out / "summary.json").read_text())
    assert written["depth"] == record["depth"]
    assert written["scene_resolved"]["numerics"]["mesh_size"] == 0.03
    history = pd.read_csv(out / "history.csv")
    assert list(history.columns) == list(HISTORY_UNITS)
    assert history["time"].is_monotonic_increasing and history["tip_depth"].max() == pytest.approx(record["depth"])
    assert sorted(p.name for p in out.iterdir()) == ["history.csv", "summary.json"]


def test_run_human_summary():
    done = penetrate("run", str(scene_path("forrestal_luk_test2")), *FAST)
    assert done.returncode == 0, done.stderr
    assert "depth" in done.stdout and "stopped" in done.stdout


@pytest.mark.parametrize(
    "args, message",
    [
        (["--set", "impact.attack_angle=95"], "impact.attack_angle = 95: must be <= 90"),
        (["--set", "impact.speed"], "--set 'impact.speed': expected KEY=VALUE"),
        (["--set", "numerics.bogus=1"], "numerics.bogus: unknown key"),
        (["--set", "target.law={function='nowhere.py:law'}"], "target.law: function = 'nowhere.py:law': cannot read"),
        (
            [
                "--set",
                f"target.law={{function='{LAWS}:overburden', parameters={{c0=1}}}}",
            ],
            "needs c2, unit_weight, lateral_ratio",
        ),
        (["--set", "target.law={model='power', c0=1e6, c=1e4, n=0}"], "target.law.n = 0: must be > 0"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(args, message, tmp_path):
    done = penetrate("run", str(scene_path("forrestal_luk_test2")), *args, "--out", str(tmp_path / "o"))
    assert done.returncode == 2
    assert message in done.stderr and "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()  # nothing written
    assert not (tmp_path / "o").exists()


def test_missing_scene_file(tmp_path):
    done = penetrate("run", str(tmp_path / "nope.toml"))
    assert done.returncode == 2 and "cannot read the scene file" in done.stderr


def test_an_override_replaces_the_scene_files_alternative(tmp_path):
    """``--set target.layers=[...]`` on a scene that names ``target.law`` means the layers instead."""
    done = penetrate(
        "run",
        str(scene_path("forrestal_luk_test2")),
        *FAST,
        "--json",
        "--out",
        str(tmp_path / "o"),
        "--set",
        'target.layers=[{thickness = 2.0, law = "soil"}, {law = "softer_soil"}]',
    )
    assert done.returncode == 0, done.stderr
    resolved = json.loads((tmp_path / "o" / "summary.json").read_text())["scene_resolved"]["target"]
    assert [layer["law"] for layer in resolved["layers"]] == ["soil", "softer_soil"]
    plain = json.loads(penetrate("run", str(scene_path("forrestal_luk_test2")), *FAST, "--json").stdout)
    assert json.loads(done.stdout)["depth"] > plain["depth"]  # the softer soil below 2 m


@pytest.mark.slow  # 3 s of runs; the compare study's own tests stay in the default run
def test_compare_says_where_it_wrote(tmp_path):
    out = tmp_path / "cmp"
    done = penetrate(
        "compare",
        str(scene_path("forrestal_luk_test2")),
        *FAST,
        "--set",
        "numerics.time_limit=0.002",
        "--laws",
        "soil,softer_soil",
        "--out",
        str(out),
        "--store",
        str(tmp_path / "s"),
        "--no-progress",
        "--workers",
        "1",
    )
    assert done.returncode == 0, done.stderr
    written = [line for line in done.stdout.splitlines() if line.startswith("written")]
    assert written and all(str(out / name) in written[0] for name in ("compare.md", "compare.csv", "compare.png"))
    assert {p.name for p in out.iterdir()} == {"compare.md", "compare.csv", "compare.png"}
    bad = penetrate(
        "compare",
        str(scene_path("forrestal_luk_test2")),
        "--laws",
        "soil,clay",
        "--out",
        str(tmp_path / "bad"),
        "--store",
        str(tmp_path / "s2"),
        "--no-progress",
    )
    assert bad.returncode == 2 and "target.law: unknown law 'clay'" in bad.stderr and not (tmp_path / "bad").exists()
    assert len(bad.stderr.strip().splitlines()) == 1 and not (tmp_path / "s2").exists()


# what a run of a cached projectile never imports: pictures, tables, clusters, meshing and its libraries
# (scipy alone 0.45 s), the compiled kernel (numba, for studies), numpy.random, the e-mail parser (package
# metadata parsed whole), the explanations of bad scenes, and a study worker's gzip
NOT_IMPORTED_BY_A_RUN = (
    "pandas",
    "pyvista",
    "matplotlib",
    "distributed",
    "vtk",
    "gmsh",
    "meshio",
    "skfem",
    "scipy",
    "numba",
    "numpy.random",
    "email.parser",
    "cases.scene.explain",
    "gzip",
)


def test_a_run_imports_only_what_it_needs(tmp_path):
    """``penetrate run`` of a projectile seen before (with ``--out`` too) imports none of
    :data:`NOT_IMPORTED_BY_A_RUN`: start-up is most of a short run's time (pandas alone takes 0.16 s to
    import, numpy.random 4-8 ms)."""
    assert penetrate("run", str(scene_path("forrestal_luk_test2")), *FAST, "--json").returncode == 0  # mesh it
    code = (
        "import sys; from cases.cli import main; main(sys.argv[1:]); "
        f"print(sorted(m for m in {NOT_IMPORTED_BY_A_RUN!r} if m in sys.modules))"
    )
    for extra in ([], ["--out", str(tmp_path / "run")]):
        done = subprocess.run(
            [sys.executable, "-c", code, "run", str(scene_path("forrestal_luk_test2")), *FAST, "--json", *extra],
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert done.returncode == 0, done.stderr
        assert done.stdout.splitlines()[-1] == "[]"
    assert (tmp_path / "run" / "history.csv").exists()


def test_the_command_line_imports_nothing_before_a_command():
    """Importing the command line (and parsing it, below) loads neither numpy nor pydantic: each command
    imports what it uses, and ``run`` does so with the garbage collector at rest (cases.cli.options.quiet_start);
    a command's ``--help`` loads the registries it lists (cases.cli.options.Parser.late_help)."""
    code = (
        "import sys; import cases.cli; "
        "print(sorted(m for m in ('numpy', 'pydantic', 'cases.scene.load', 'cases.run') if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def test_a_run_in_process_leaves_the_process_as_it_was(monkeypatch):
    """``main`` rests the garbage collector while a run starts and sets PYDANTIC_DISABLE_PLUGINS and
    OPENBLAS_NUM_THREADS for the command where the user has not: afterwards all is as it was."""
    monkeypatch.delenv("PYDANTIC_DISABLE_PLUGINS", raising=False)
    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    assert gc.isenabled() and gc.get_freeze_count() == 0
    with contextlib.redirect_stdout(io.StringIO()) as out:
        assert main(["run", str(scene_path("forrestal_luk_test2")), *FAST, "--json"]) == 0
    assert json.loads(out.getvalue())["end_reason"] == "stopped"
    assert gc.isenabled() and gc.get_freeze_count() == 0
    assert "PYDANTIC_DISABLE_PLUGINS" not in os.environ and "OPENBLAS_NUM_THREADS" not in os.environ
    monkeypatch.setenv("PYDANTIC_DISABLE_PLUGINS", "some_plugin")  # the user's choice stands
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["run", str(scene_path("forrestal_luk_test2")), *FAST, "--json"]) == 0
    assert os.environ["PYDANTIC_DISABLE_PLUGINS"] == "some_plugin"


# every study command: one progress bar, shown on a terminal, forced on or off by --progress / --no-progress
STUDY_COMMANDS = {
    "sweep": [],
    "critical": [],
    "ballistic-limit": [],
    "convergent": [],
    "compare": ["--laws", "soil"],
    "accuracy": [],
    "contact": [],
    "entry": [],
    "fit": ["--param", "impact.speed=100:400", "--observe", "depth=5"],
    "ensemble": ["--sample", "impact.speed=uniform:250:300", "-n", "2"],
    "paper": [],
}


@pytest.mark.parametrize("command", sorted(STUDY_COMMANDS))
def test_progress_shows_on_a_terminal_unless_told(command, monkeypatch):
    """``penetrate fit --json`` drew its bar into a log file: now no study does unless ``--progress`` asks."""
    from cases.cli import build_parser
    from cases.cli.options import pool

    base = [command, *([] if command == "paper" else [str(scene_path("forrestal_luk_test2"))])]
    base += STUDY_COMMANDS[command]
    json_flag = ["--json"]
    for flags, terminal, shown in [
        ([], False, False),
        (json_flag, False, False),
        ([], True, True),
        (["--progress", *json_flag], False, True),
        (["--no-progress"], True, False),
    ]:
        monkeypatch.setattr(sys.stderr, "isatty", lambda terminal=terminal: terminal, raising=False)
        args = build_parser().parse_args([*base, *flags])
        assert pool(args).shows_progress is shown, (flags, terminal)
    with pytest.raises(SystemExit) as both, contextlib.redirect_stderr(io.StringIO()) as err:
        build_parser().parse_args([*base, "--progress", "--no-progress"])
    assert both.value.code == 2 and "not allowed with argument --progress" in err.getvalue()


def help_text(*command: str) -> str:
    """A command's ``--help``, its words joined by single spaces (the formatter wraps lines anywhere)."""
    with contextlib.redirect_stdout(io.StringIO()) as out, pytest.raises(SystemExit):
        main([*command, "--help"])
    return " ".join(out.getvalue().split())


def test_help_lists_every_value_the_code_takes(monkeypatch):
    """Distributions, designs, named laws, contact options, fit quantities: each help is built from the
    registry the code checks input against, so a name added there shows in the help (tried here)."""
    from cases.scene.target import Effects
    from cases.studies.ensemble.sampling import DESIGNS, FORMS
    from cases.studies.measured.fit import RUN_QUANTITIES, STUDY_QUANTITIES
    from fem_loads.resistance import NAMED_LAWS, ResistanceLaw

    monkeypatch.setitem(NAMED_LAWS, "test_clay", ResistanceLaw(1e6, 1500.0, "test_clay"))
    monkeypatch.setitem(FORMS, "test_triangular", "test_triangular:LO:MODE:HI")
    ensemble = help_text("ensemble")
    assert all(form in ensemble for form in FORMS.values()) and "halfnormal:SCALE" in ensemble
    assert "{" + ",".join(DESIGNS) + "}" in ensemble
    assert all(name in help_text("compare").split("--laws", 2)[2] for name in NAMED_LAWS)
    for command in ("run", "sweep", "critical", "convergent", "predict", "fit", "ensemble", "render", "contact"):
        shown = help_text(command).split("--set KEY=VALUE", 2)[2]
        assert all(name in shown for name in NAMED_LAWS), command
    contact = help_text("contact").split("--incidences", 2)[2]
    assert all(f"effects.{name}" in contact for name in Effects().contact_ramp)
    fit = help_text("fit").split("--observe", 2)[2]
    assert all(quantity in fit for quantity in RUN_QUANTITIES + STUDY_QUANTITIES)


def test_a_commands_help_does_not_slow_the_parsing_of_another():
    """The registries load when a help is shown, not when a command line is parsed."""
    code = (
        "import sys; from cases.cli import build_parser; build_parser().parse_args(sys.argv[1:]); "
        "print(sorted(m for m in ('numpy', 'pydantic', 'scipy', 'fem_loads') if m in sys.modules))"
    )
    args = ["ensemble", "x.toml", "--sample", "impact.speed=uniform:1:2", "-n", "2"]
    done = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def test_every_command_s_help_says_what_it_does_and_what_it_writes():
    """Each subcommand's ``--help`` opens with its description: what it does, and the files it writes or that it
    writes none (or prints)."""
    from cases.cli import build_parser
    from cases.cli.descriptions import DESCRIPTIONS

    commands = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    assert set(commands) == set(DESCRIPTIONS)
    for name, description in DESCRIPTIONS.items():
        assert " ".join(description.split()) in help_text(name), name
        assert re.search(r"\b([Ww]rites?|[Pp]rints?)\b", description), name


@pytest.mark.parametrize(
    "command",
    [
        ["sweep", "--grid", "impact.speed=300,350"],
        ["compare", "--laws", "scene,softer_soil", "--depths-at", "300"],
        ["contact", "--incidences", "0.01", "--step", "2e-5"],
        ["entry", "--smoothings", "1", "--steps", "4e-5,2e-5"],
    ],
    ids=lambda command: command[0],
)
def test_a_study_s_json_is_one_object(command, tmp_path, capsys):
    """``sweep``, ``compare``, ``contact`` and ``entry`` printed a bare list of records: now one object, the rows
    under ``rows``, each a run of the study (as every other command's ``--json``)."""
    name, *options = command
    out = ["--out", str(tmp_path / "out")]
    scene = str(scene_path("forrestal_luk_test2"))
    args = [name, scene, *FAST, *options, *out, "--store", str(tmp_path / "store"), "--workers", "1", "--no-progress"]
    assert main([*args, "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert isinstance(record, dict) and record["rows"] and all(isinstance(row, dict) for row in record["rows"])
    assert set(record) == ({"rows", "depths_at"} if name == "compare" else {"rows"})  # as the reference says
    expected = {"sweep": 2, "compare": 2, "contact": 2, "entry": 2}[name]  # the contact study adds the sharp law
    assert len(record["rows"]) == expected
    if name == "compare":
        assert [row["impact.speed"] for row in record["depths_at"]] == [300.0, 300.0]


@pytest.mark.parametrize(
    ("command", "new"),
    [
        (["map", "SCENE", "--over", "impact.attack_angle=1,2"], "--grid KEY=VALUES"),
        (["compare", "SCENE", "--speeds", "200,400"], "--depths-at V1,V2,..."),
        (["fit", "SCENE", "--step", "0.01"], "--difference-step FRACTION"),
        (["render", "SCENE", "--steps", "10"], "--paraview-frames N|all"),
    ],
)
def test_a_former_option_spelling_is_refused_naming_the_new_one(command, new):
    """An option renamed so that one word means one thing in every command: the old spelling is refused in one
    line that names the new one, never read as something else."""
    from cases.cli import build_parser

    with pytest.raises(SystemExit) as refused, contextlib.redirect_stderr(io.StringIO()) as err:
        build_parser().parse_args(command)
    message = err.getvalue()
    assert refused.value.code == 2 and message.count("\n") == 1
    assert f"{command[2]}: a former spelling; give {new}" in message


def test_every_study_command_takes_the_shared_options():
    """Every command that runs many scenes takes the same run-store, pool and ``--json`` options from one
    parser, and ``--out`` is checked as a folder wherever a study writes one (render too)."""
    from cases.cli import build_parser

    commands = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    shared = {"--store", "--workers", "--scheduler", "--progress", "--no-progress", "--json"}
    studies = [name for name, parser in commands.items() if "--store" in parser._option_string_actions]
    assert set(studies) >= {"sweep", "critical", "map", "compare", "validate", "ensemble", "fit", "paper"}
    for name in studies:
        assert shared <= set(commands[name]._option_string_actions), name
    for name, parser in commands.items():
        out = parser._option_string_actions.get("--out")
        if out is not None:
            assert out.type.__name__ == "out_folder", name


def test_every_json_shape_is_documented_and_the_records_keys_are_its_keys():
    """Each command with ``--json`` has its shape in the command reference (one table, JSON_SHAPES), and the
    records whose keys it lists print exactly those keys."""
    from cases.cli import build_parser
    from cases.cli.descriptions import JSON_SHAPES
    from cases.studies.reduced.pitch_plane import Prediction
    from cases.studies.speeds.ballistic import BallisticLimit
    from cases.studies.speeds.characteristic import ConvergentResult, CriticalSearch

    commands = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    assert {name for name, parser in commands.items() if "--json" in parser._option_string_actions} == set(JSON_SHAPES)
    records = {
        "critical": CriticalSearch(None, None).as_dict(),
        "ballistic-limit": BallisticLimit(None, None).as_dict(),
        "convergent": ConvergentResult(None, [], "").as_dict(),
        "predict": Prediction(None, None, None, "", []).as_dict(),
    }
    for name, record in records.items():
        assert set(re.findall(r"`(\w+)`", JSON_SHAPES[name])) == set(record), name
