"""The one Markdown table formatter and number cell every study's report draws with."""

import math

import numpy as np
import pytest

from cases.studies.engine.report import markdown_table, number_cell


def test_a_table_has_its_header_its_rule_and_a_line_per_row():
    lines = markdown_table(["law", "depth (m)"], [["soil", "5.50"], ["", 3]])
    assert lines == ["| law | depth (m) |", "|---|---|", "| soil | 5.50 |", "| | 3 |"]


def test_a_table_without_rows_is_its_header():
    assert markdown_table(["a"], []) == ["| a |", "|---|"]


@pytest.mark.parametrize(
    ("value", "spec", "shown"),
    [
        (1234.5678, ".3g", "1.23e+03"),
        (np.float64(0.125), ".2f", "0.12"),  # numpy's floats are floats (round half to even)
        (-0.05, "+.1f", "-0.1"),
        (None, ".3g", "-"),
        (math.nan, ".3g", "-"),
        (math.inf, ".0f", "-"),
        (12, ".3g", "12"),  # a count stays whole
        ("stopped", ".3g", "stopped"),
    ],
)
def test_a_number_cell_formats_floats_and_marks_what_is_missing(value, spec, shown):
    assert number_cell(value, spec) == shown


def test_a_report_is_written_by_the_one_writer(tmp_path):
    """Its table as CSV, its record as strict JSON (a NaN as null), its Markdown and each figure, into a folder
    made if missing; what it wrote is what it lists."""
    import json

    import pandas as pd

    from cases.studies.engine.report import Report, write_report

    drawn = []
    report = Report(
        "study",
        "# a study\n",
        pd.DataFrame({"speed": [300.0, 350.0], "depth": [1.5, math.nan]}),
        {"critical_velocity": math.nan, "runs": 2},
        {"study.png": lambda path: (drawn.append(path), path.write_bytes(b"png"))},
    )
    paths = write_report(tmp_path / "out", report)
    assert [p.name for p in paths] == ["study.csv", "study.json", "study.md", "study.png"]
    assert all(p.is_file() for p in paths) and drawn == [tmp_path / "out" / "study.png"]
    assert json.loads((tmp_path / "out" / "study.json").read_text()) == {"critical_velocity": None, "runs": 2}
    assert "NaN" not in (tmp_path / "out" / "study.json").read_text()
    assert pd.read_csv(paths[0])["speed"].tolist() == [300.0, 350.0]
    assert (tmp_path / "out" / "study.md").read_text() == "# a study\n"


def _figure(text: str, path) -> None:
    import os

    path.write_text(f"{text} {os.getpid()}")


def test_figures_drawn_on_workers_are_each_where_the_report_lists_them(tmp_path):
    """``width`` 2: the figures (functions with their data bound) drawn by the local workers, each into its own
    file with its own data, none by this process."""
    import functools
    import os

    from cases.studies.engine.report import Report, write_report

    figures = {f"f{i}.png": functools.partial(_figure, f"figure {i}") for i in range(5)}
    paths = write_report(tmp_path, Report("study", "# a study\n", figures=figures), width=2)
    assert [p.name for p in paths] == ["study.md", *figures]
    for i, path in enumerate(paths[1:]):
        text, pid = path.read_text().rsplit(" ", 1)
        assert text == f"figure {i}" and int(pid) != os.getpid()


def test_no_study_writes_a_file_itself():
    """Every study's files go through the one writer: no module of the studies but the writer calls the atomic
    writers or the JSON writer."""
    from pathlib import Path

    import cases.studies

    root = Path(cases.studies.__file__).parent
    for path in root.rglob("*.py"):
        text = path.read_text()
        if path.name == "report.py" and path.parent.name == "engine":
            assert "atomic_write_text(" in text and "write_json(" in text  # the control: the writer is found
            continue
        assert not any(call in text for call in ("atomic_write_text(", "write_json(", "atomic_write(")), path
