"""A stability map of #3 and six of its points searched again without the guide (docs/evidence-studies.md).

Run from the repository root: ``python -m docs.studies.map`` (about a minute on 2 cores from an empty store;
runs are kept in ``runs/map-store``).  ``penetrate map`` of the shipped #3 over 10 attack angles (0.5-5
degrees) and 7 oblique angles (0-30 degrees); then six points drawn at random (seed 0) searched again by
today's unguided search (``penetrate critical --guide none``).  Prints markdown: the map's cost, the table
of critical speeds, and the six comparisons.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from cases.run import RunStore
from cases.studies import Pool, Sweep, Variation, find_critical_velocity
from cases.studies.speeds.stability_map import stability_map
from docs.measure import stamp

SCENE = "cases/paper_p3.toml"
OVER = ["impact.attack_angle=0.5:5:0.5", "impact.oblique_angle=0:30:5"]
STORE = RunStore("runs/map-store")
POOL = Pool(progress=False)
HERE = Path(__file__).resolve().parent


def main() -> None:
    start = time.perf_counter()
    record = stability_map(SCENE, None, OVER, STORE, HERE / "map", pool=POOL)
    elapsed = time.perf_counter() - start
    points = record["points"]
    print(
        f"`penetrate map {SCENE} --grid {OVER[0]} --grid {OVER[1]}`: {len(points)} searches, {record['guided']}"
        f" guided, {record['full_runs']} full runs, {elapsed:.0f} s from an empty run store."
    )
    print()
    attacks, obliques = record["values"]
    print("| attack angle (deg) | " + " | ".join(f"oblique {b:g}" for b in obliques) + " |")
    print("|---|" + "---|" * len(obliques))
    for a in attacks:
        row = [p for p in points if p["impact.attack_angle"] == a]
        cells = [f"{p['critical_velocity']:.1f}" if p["critical_velocity"] is not None else "-" for p in row]
        print(f"| {a:g} | " + " | ".join(cells) + " |")
    print()
    chosen = np.random.default_rng(0).choice(len(points), size=6, replace=False)
    print("Six points at random, searched again without the guide (`penetrate critical --guide none`):")
    print()
    header = "| attack angle (deg) | oblique angle (deg) | map (m/s) | unguided (m/s) | difference |"
    print(header + " full runs: map / unguided |")
    print("|---|---|---|---|---|---|")
    for i in sorted(chosen):
        p = points[i]
        values = {key: p[key] for key in record["keys"]}
        base = Sweep.from_file(SCENE, None, [Variation(values)])
        search = find_critical_velocity(base, STORE, (200.0, 1600.0), 5.0, POOL, guide="none")
        mapped, again = p["critical_velocity"], search.critical_velocity
        difference = f"{again - mapped:+.1f} m/s" if mapped is not None and again is not None else "-"
        print(
            f"| {values['impact.attack_angle']:g} | {values['impact.oblique_angle']:g} | {mapped} | {again} |"
            f" {difference} | {p['runs']} / {len(search.indicator)} |"
        )
    print()
    print(stamp())


if __name__ == "__main__":
    main()
