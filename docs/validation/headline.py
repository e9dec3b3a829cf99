"""The README's accuracy against experiment: each shipped test series predicted shot by shot, nothing fitted to
it, as three lines.  Run from the repository root::

    python -m docs.validation.headline
"""

from __future__ import annotations

import tempfile

from cases.run import RunStore
from cases.studies import Pool
from cases.studies.measured.series import read_series
from cases.studies.measured.validate import validate

#: each series, what it is, and the quantity measured
SERIES = (
    (
        "forrestal_luk_soil",
        "Forrestal and Luk's soil shots (95 mm, 280 m/s, normal, oblique and with an attack angle)",
        "path length",
    ),
    ("forrestal1996_concrete", "Forrestal et al.'s concrete shots (30 mm rods into grout, 405-1201 m/s)", "depth"),
)


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        for name, what, quantity in SERIES:
            validation = validate(read_series(name), None, RunStore(folder), Pool(progress=False), curve_points=0)
            [summary] = validation.summary.values()  # the series' one quantity
            print(
                f"* {what}: {summary['shots']} shots, {quantity} predicted with a mean error of "
                f"{summary['mean_abs_error_percent']:.1f} % (bias {summary['bias_percent']:+.1f} %)."
            )


if __name__ == "__main__":
    main()
