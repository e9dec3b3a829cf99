"""A multi-fidelity ensemble of #3 against an all-3-D one (docs/evidence-ensembles.md, "Multi-fidelity ensembles").

Run from the repository root: ``python -m docs.ensembles.multifidelity`` (about three minutes on 2 cores from
an empty store; runs are kept in ``runs/multifidelity-store``).  #3 at 20 mm, the impact speed uniform on
700-1300 m/s and the attack angle half-normal with a 1 degree scale: 1 024 runs of a scrambled Sobol' design,
every one a full run, and 100 000 samples with ``--fidelity multi`` (the reduced model sorts them, 1 024 full
runs measure the sorts).  Prints markdown: the times and counts, and P(unstable) in each 100 m/s bin from
both, with whether the multi-fidelity estimate lies inside the all-3-D ensemble's 95 % interval.
"""

from __future__ import annotations

import time
from pathlib import Path
from tempfile import TemporaryDirectory

from cases.run import RunStore
from cases.studies import Pool
from cases.studies.ensemble.study import run_ensemble
from docs.measure import stamp

SCENE = "cases/paper_p3.toml"
SETTINGS = {"numerics.mesh_size": 0.02}
SAMPLES = ["impact.speed=uniform:700:1300", "impact.attack_angle=halfnormal:1"]
BY = "impact.speed=700:1300:100"
STORE = RunStore("runs/multifidelity-store")
POOL = Pool(progress=False)


def _run(out: Path, count: int, **options: object) -> tuple[dict, float]:
    start = time.perf_counter()
    record = run_ensemble(SCENE, SETTINGS, SAMPLES, count, STORE, out, by=BY, pool=POOL, **options)  # type: ignore[arg-type]
    return record, time.perf_counter() - start


def main() -> None:
    with TemporaryDirectory() as folder:
        full, full_time = _run(Path(folder) / "full", 1024, design="sobol")
        multi, multi_time = _run(Path(folder) / "multi", 100_000, fidelity="multi")
    strata = multi["by_stratum"]
    print(
        f"All 3-D: 1024 Sobol' runs, {full_time:.0f} s. Multi-fidelity: 100000 samples sorted by the reduced model"
        f" in {multi['sort_time']:.0f} s (stable {strata['stable']['samples']}, unstable"
        f" {strata['unstable']['samples']}, near {strata['near']['samples']}), {multi['full_runs']} full runs"
        f" ({strata['near']['runs']} near, an audit of {strata['stable']['runs']} stable and"
        f" {strata['unstable']['runs']} unstable, of which {strata['stable']['count']} and"
        f" {strata['unstable']['runs'] - strata['unstable']['count']} disagreed with the sort), {multi_time:.0f} s"
        " in all, from an empty run store."
    )
    print()
    print(
        "| impact speed (m/s) | all 3-D: P(unstable) | 95 % interval | multi-fidelity: P(unstable) | 95 % interval |"
        " full runs in the bin | inside the all-3-D interval |"
    )
    print("|---|---|---|---|---|---|---|")
    inside = 0
    for a, b in zip(full["curve"], multi["curve"]):
        low, high = a["interval"]["unstable"]
        ok = low <= b["unstable"] <= high
        inside += ok
        m_low, m_high = b["interval"]["unstable"]
        print(
            f"| {a['bin'][0]:g} - {a['bin'][1]:g} | {a['unstable']:.3f} | {low:.3f} - {high:.3f} |"
            f" {b['unstable']:.3f} | {m_low:.3f} - {m_high:.3f} | {b['full_runs']} | {'yes' if ok else 'no'} |"
        )
    print()
    print(f"{inside} of {len(full['curve'])} bins inside.")
    print()
    print(stamp())


if __name__ == "__main__":
    main()
