"""The fuzzing table of docs/robustness.md describes every fuzzing property of tests/robustness/test_fuzz.py."""

from __future__ import annotations

import re
from pathlib import Path

from docs.robustness import fuzz


def test_the_fuzz_table_has_a_row_for_every_fuzz_test(capsys):
    fuzz.main()  # exits naming any property the script does not describe
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| ") and "---" not in line]
    tests = re.findall(r"^def (test_\w+)", Path(fuzz.MODULE).read_text(), flags=re.MULTILINE)
    fuzzed = [name for name in tests if name in fuzz.PROPERTIES]
    assert len(rows) - 1 == len(fuzzed) == len(fuzz.PROPERTIES)  # the header, then one row each
