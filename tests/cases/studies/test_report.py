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
