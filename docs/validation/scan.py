"""The concrete calibration checked by brute force: ``penetrate fit --series``'s S against the minimum of the sum of
squared residuals scanned over S (docs/validation.md).  Run from the repository root::

    python -m docs.validation.scan

The fit takes the four slowest shots of the 1996 series.  The scan runs the same four shots at every S from 9 to
13 in steps of 0.1 (41 values, 164 runs, kept in the run store), and places the minimum by a parabola through the
lowest grid point and its two neighbours.
"""

from __future__ import annotations

import numpy as np

from cases.run import RunStore
from cases.studies import Pool
from cases.studies.measured.fit_series import Holdout, fit_series
from cases.studies.measured.series import read_series
from cases.studies.measured.validate import validate

TRAINING = ("v405", "v446", "v545", "v651")


def main() -> None:
    series = read_series("forrestal1996_concrete")
    store, pool = RunStore("runs/series-scan-store"), Pool(progress=False)
    held = tuple(label for label in series.labels if label not in TRAINING)
    result = fit_series(series, None, ["target.law.S=5:20"], store, pool, holdout=Holdout("label", held))
    fitted, error = result.parameters["target.law.S"], result.standard_errors["target.law.S"]
    grid = np.round(np.arange(9.0, 13.0001, 0.1), 6)
    training = series.subset(TRAINING)
    sums = [
        sum(
            (row["predicted"] - row["measured"]) ** 2
            for row in validate(training, [("target.law.S", float(s))], store, pool, 0).rows
        )
        for s in grid
    ]
    best = int(np.argmin(sums))
    a, b, _ = np.polyfit(grid[best - 1 : best + 2], sums[best - 1 : best + 2], 2)
    scanned = -b / (2 * a)
    assert error is not None
    print(
        f"Fitted to {', '.join(TRAINING)}: S = {fitted:.3f} +- {error:.3f}. The scan of the sum of squared residuals"
        f" over S = 9 ... 13 (step 0.1, {len(grid) * len(TRAINING)} runs) has its lowest point at S = {grid[best]:.1f}"
        f" ({sums[best]:.3g} m^2) and, by a parabola through it and its neighbours, its minimum at S = {scanned:.3f}:"
        f" {abs(fitted - scanned) / error:.2f} standard errors from the fit (the target: within one)."
    )


if __name__ == "__main__":
    main()
