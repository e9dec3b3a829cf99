"""Guided against unguided critical-speed searches on every shipped scene (docs/evidence-studies.md, "Guided searches").

Run from the repository root: ``python -m docs.studies.guided`` (about a minute on 2 cores; each search from
an empty store of its own, so that neither reuses the other's runs).  Each shipped scene at its own numerics,
searched over 200-1600 m/s to 5 m/s without the guide (``--guide none``, the search before the guide) and
with it (the default).  Prints markdown: a row per scene with both results, their full runs and rounds, and
what the guide said.
"""

from __future__ import annotations

from tempfile import TemporaryDirectory

from cases import SHIPPED_SCENES, scene_path
from cases.run import RunStore
from cases.studies import Pool, Sweep, find_critical_velocity
from docs.measure import stamp

POOL = Pool(progress=False)


def _result(search) -> str:  # type: ignore[no-untyped-def]
    if search.critical_velocity is None:
        return search.message
    return f"{search.critical_velocity:.1f} ({search.bracket[0]:g} - {search.bracket[1]:g})"


def main() -> None:
    print(
        "| scene | unguided (m/s) | runs / rounds | guided (m/s) | runs / rounds | guide |\n|---|---|---|---|---|---|"
    )
    totals = [0, 0]
    for name in SHIPPED_SCENES:
        base = Sweep.from_file(scene_path(name))
        searches = []
        for i, guide in enumerate(("none", "auto")):
            with TemporaryDirectory() as folder:
                search = find_critical_velocity(base, RunStore(folder), (200.0, 1600.0), 5.0, POOL, guide=guide)
            searches.append(search)
            totals[i] += len(search.indicator)
        old, new = searches
        print(
            f"| {name} | {_result(old)} | {len(old.indicator)} / {old.rounds} | {_result(new)} |"
            f" {len(new.indicator)} / {new.rounds} | {new.guide.text} |"
        )
    print()
    print(f"Full runs in all: {totals[0]} unguided, {totals[1]} guided.")
    print()
    print(stamp())


if __name__ == "__main__":
    main()
