"""The fuzzing's properties and how many examples each draws (docs/robustness.md), read off the test module.

Run from the repository root: ``python -m docs.robustness.fuzz``.  Prints a markdown table: what each
property of ``tests/robustness/test_fuzz.py`` generates (said here) and its examples in the default run
(its ``@fuzz(N)`` decorator) and at ``PENETRATE_FUZZ_SCALE=10``; a test of the module this script does not
describe fails the script, so the table cannot miss one.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

MODULE = Path(__file__).resolve().parents[2] / "tests" / "robustness" / "test_fuzz.py"
PROPERTIES = {  # test -> (property, what is generated)
    "test_mutated_scenes_validate_or_explain": (
        "mutated scenes (dicts)",
        "shipped scenes with 1-4 leaves replaced (wrong types, 0, -0.0, negatives, NaN, inf,"
        " 1e308, 10^400, dates, empty strings, lists and tables, code), numbers at, inside and just outside their"
        " ranges, keys deleted, unknown keys added",
    ),
    "test_profile_noses_validate_or_explain": (
        "measured noses",
        "test 2 with a table of 3 to 40 points sampled from its ogive, with up to three defects (a"
        " point dropped, swapped, duplicated, a coordinate replaced, the shank radius missed, a point not a pair)",
    ),
    "test_measured_bodies_validate_or_explain": (
        "measured bodies",
        "test 2 with a boat tail or flare of 2 to 12 points, with up to three defects, or a scalar, or no points",
    ),
    "test_geometry_projectiles_validate_or_explain": (
        "projectiles from files",
        "the geometry table's keys (file, unit, axis, cell_field, symmetry) valid or not, with or"
        " without the mass, the materials and the analytic keys it excludes",
    ),
    "test_mutated_scene_files_validate_or_explain": ("mutated scene files", "the mutated scenes, written as TOML"),
    "test_random_bytes_and_text": ("random bytes and text", "binary, invalid UTF-8, random Unicode"),
    "test_random_toml_documents": ("random TOML documents", "random keys (schema names and text) and nested values"),
    "test_edited_scene_files": (
        "edited scene files",
        "shipped files with random characters deleted, inserted, replaced",
    ),
    "test_edited_series_files": (
        "edited series files",
        "shipped series CSVs with random characters deleted, inserted, replaced (commas, quotes, newlines, `%`,"
        " `nan`, `1e999`, comment marks, column prefixes); read with every shot valid, or refused in one line"
        " naming the file and the row, line, header or column",
    ),
    "test_random_series_files": (
        "random series files",
        "1-6 columns (scene, label, group, scene keys, measured and sigma columns, unknown and empty names) and"
        " up to 4 rows of numbers, NaN, inf, percentages, names and random text; read or refused as above",
    ),
    "test_malformed_overrides": (
        "`--set` strings",
        "no `=`, empty keys, `a..b`, unknown paths, 5000-character keys"
        " and values, deep nesting, random text, in-range and out-of-range values",
    ),
    "test_command_line_bad_input": (
        "command lines",
        "each command with a bad scene file or a bad option, plus random noise; must exit 2",
    ),
    "test_fit_is_refused_before_any_run_exactly_when_counting_says_so": (
        "fits by their counts",
        "1-7 observations (run quantities and characteristic speeds, with or without sigmas) of 1-6 parameters;"
        " refused before any run exactly when there are fewer observations than parameters",
    ),
    "test_a_critical_search_that_finds_nothing_names_the_option_that_would": (
        "critical searches that find nothing",
        "every run stable or unstable over any range, with or without a disturbance; the last line names a"
        " --speeds range reaching further the right way, and the attack angle when the scene has none",
    ),
    "test_a_user_law_is_used_or_refused_in_one_line": (
        "user laws",
        "a law file with any body (usable, negative, infinite, NaN, Python-only, not compilable, not a number),"
        " arguments, function name and parameters; used, with finite stresses >= 0 equal on both paths, or"
        " refused in one line naming target.law",
    ),
    "test_a_target_is_used_or_refused_in_one_line": (
        "targets",
        "0-5 layers with any thickness (any float, NaN, inf, 0, negatives, text) or none, laws named, unknown,"
        " tables or numbers (air for a gap), and any inclination; used with its faces in order and consistent,"
        " or refused in one line naming the target",
    ),
    "test_valid_runs_write_finite_numbers": (
        "valid runs",
        "speeds, angles, spins, integrators, friction, history"
        " thinning, time limits; must exit 0 and write finite numbers",
    ),
}


def main() -> None:
    source = MODULE.read_text()
    # the decorators between @fuzz(N) and the test may span lines (a long @given(...))
    found = re.findall(r"^@fuzz\((\d+)\)\n(?:(?!def ).*\n)*?def (test_\w+)", source, flags=re.MULTILINE)
    unknown = [name for _, name in found if name not in PROPERTIES]
    if unknown:
        sys.exit(f"docs.robustness.fuzz: describe {', '.join(unknown)}")
    print("| property | what is generated | examples, default run | at `PENETRATE_FUZZ_SCALE=10` |")
    print("|---|---|---|---|")
    for examples, name in found:
        label, what = PROPERTIES[name]
        print(f"| {label} | {what} | {examples} | {10 * int(examples)} |")


if __name__ == "__main__":
    main()
