"""The eroded-nose study the published one left out (docs/evidence-geometry.md): #3 at normal incidence and zero
attack, its nose cut on one side by a plane of growing obliquity.

Run from the repository root: ``python -m docs.geometry.erosion`` (a few minutes from an empty store; runs are
kept in ``runs/erosion-store``).  It

1. writes the bodies with ``cases/bodies/make_bodies.py`` (gmsh OpenCASCADE; BREP, metres) into
   ``runs/erosion-bodies/``: #3 with a solid nose (the cavity 150 mm behind the tip, the counterweight placed
   for its mass and centre of mass), whole, and cut 40 mm behind the tip by planes whose normal leaves the
   axis by 0 (a flat, symmetric cut) to 60 degrees (the shipped ``cases/eroded_p3.toml``), with the list
   ``bodies.toml`` that ``penetrate sweep --list`` reads;
2. runs ``penetrate sweep``'s own function over the bodies and the impact speed (every mesh built once,
   then found in the cache by the file's digest), and ``penetrate critical``'s search for each body;
3. prints the tables as markdown and draws ``erosion_turn.png`` and ``erosion_critical.png`` beside itself.

Every run uses the paper study's numerics (20 mm, Dormand-Prince at rtol 1e-8, docs/paper.md), with the
exact normals of the CAD surfaces.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from cases.bodies.make_bodies import write_eroded_p3  # noqa: E402
from cases.run import RunStore, atomic_write_text, prepare_projectile  # noqa: E402
from cases.studies import Pool, Sweep, Variation, find_critical_velocities, run_sweep  # noqa: E402
from cases.studies.paper.plan import STUDY_NUMERICS  # noqa: E402
from cases.viz.figures import legend_below, legend_outside  # noqa: E402
from docs.record import study_main  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
BODIES = ROOT / "runs" / "erosion-bodies"
STORE = RunStore("runs/erosion-store")
POOL = Pool(progress=False)
DEPTH = 0.04  # m behind the tip
ANGLES = (0.0, 2.5, 5.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0)  # degrees of the cut's normal from the axis
SPEEDS = list(range(200, 2401, 200))  # m/s
CRITICAL_RANGE = (200.0, 2400.0)
SCENE = "cases/eroded_p3.toml"


def bodies() -> list[tuple[str, Path]]:
    """Write the bodies (label, path): whole, then each angle of cut; and ``bodies.toml`` for ``penetrate sweep``."""
    BODIES.mkdir(parents=True, exist_ok=True)
    written = [("whole", write_eroded_p3(BODIES / "whole.brep", 0.0, 0.0))]
    for angle in ANGLES:
        written.append((f"{angle:g} deg", write_eroded_p3(BODIES / f"cut_{angle:g}deg.brep", angle, DEPTH)))
    listing = "".join(f'[[run]]\n"projectile.geometry.file" = "{path}"\n\n' for _, path in written)
    atomic_write_text(BODIES / "bodies.toml", listing)
    return written


def study() -> dict:
    """Each body's mass properties, its runs over :data:`SPEEDS` and its critical impact velocity."""
    written = bodies()
    overrides = list(STUDY_NUMERICS.items())
    variations = [
        Variation({"projectile.geometry.file": str(path), "impact.speed": speed})
        for _, path in written
        for speed in SPEEDS
    ]
    swept = run_sweep(Sweep.from_file(SCENE, overrides, variations), STORE, POOL)
    per_body = [Sweep.from_file(SCENE, [*overrides, ("projectile.geometry.file", str(path))]) for _, path in written]
    searches = find_critical_velocities(per_body, STORE, CRITICAL_RANGE, 5.0, POOL)
    record = []
    for k, (label, _) in enumerate(written):
        prepared = prepare_projectile(per_body[k].scenes[0])
        mass = prepared.mass
        runs = swept.runs[k * len(SPEEDS) : (k + 1) * len(SPEEDS)]
        record.append(
            {
                "body": label,
                "mass": mass.mass,
                "centre_from_tip": mass.centre_from_tip,
                "transverse_inertia": mass.transverse_inertia,
                "mirror_planes": [{1: "y = 0", 2: "z = 0"}[axis] for axis in prepared.quadrature.mirror_planes],
                "largest_product_of_inertia": float(
                    max(abs(mass.inertia[0, 1]), abs(mass.inertia[0, 2]), abs(mass.inertia[1, 2]))
                ),
                "runs": [
                    {
                        "speed": speed,
                        "axis_turn": run.summary.axis_angle_change,
                        "max_attack_angle": run.summary.max_attack_angle,
                        "path_length": run.summary.path_length,
                        "depth": run.summary.depth,
                        "end": run.summary.end_reason,
                    }
                    for speed, run in zip(SPEEDS, runs)
                ],
                "critical_velocity": searches[k].critical_velocity,
                "critical_bracket": searches[k].bracket,
                "critical_message": searches[k].message,
            }
        )
    return {"depth": DEPTH, "speeds": SPEEDS, "bodies": record}


def report(record: dict) -> None:
    """The tables, as markdown."""
    print(
        f"#3 with a solid nose, at normal incidence and no attack; the nose cut {1e3 * record['depth']:g} mm behind"
        " the tip by a plane whose normal leaves the axis by the angle given (0: a flat, symmetric cut):"
    )
    print()
    print(
        "| nose | mirror planes | mass (kg) | centre of mass from the tip (m) | transverse inertia (kg m^2) | critical"
        " impact velocity (m/s) | axis turn at 1200 m/s (deg) | largest attack angle at 1200 m/s (deg) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for body in record["bodies"]:
        at = next(run for run in body["runs"] if run["speed"] == 1200)
        critical = (
            f"{body['critical_velocity']:.1f}"
            if body["critical_velocity"] is not None
            else f"none up to {CRITICAL_RANGE[1]:g}"
        )
        print(
            f"| {body['body']} | {', '.join(body['mirror_planes']) or 'none'} | {body['mass']:.2f} |"
            f" {body['centre_from_tip']:.4f} | "
            f"{body['transverse_inertia']:.3f} | {critical} | {at['axis_turn']:+.1f} | {at['max_attack_angle']:.2f} |"
        )
    print()
    print("Axis turn (deg) against the impact speed (m/s):")
    print()
    print("| nose | " + " | ".join(f"{v}" for v in record["speeds"]) + " |")
    print("|---|" + "---|" * len(record["speeds"]))
    for body in record["bodies"]:
        print(f"| {body['body']} | " + " | ".join(f"{run['axis_turn']:+.1f}" for run in body["runs"]) + " |")
    print()
    whole, square = (max(abs(run["axis_turn"]) for run in body["runs"]) for body in record["bodies"][:2])
    print(
        f"The largest axis turn over every speed of the two bodies of revolution: the whole nose {whole:.2g} deg,"
        f" the square cut {square:.2g} deg."
    )


def figures(record: dict) -> None:
    """The axis turn against the speed for every body; the critical speed and the turn at 1200 m/s against the cut."""
    fig, axes = plt.subplots(figsize=(6.5, 4.2))
    for k, body in enumerate(record["bodies"]):
        axes.plot(
            record["speeds"],
            [abs(run["axis_turn"]) for run in body["runs"]],
            "o-",
            ms=3,
            color=plt.cm.viridis(k / max(1, len(record["bodies"]) - 1)),
            label=body["body"],
        )
    axes.axhline(30.0, color="0.5", lw=0.8, ls="--")
    axes.set_yscale("symlog", linthresh=1.0)
    axes.set(
        xlabel="impact speed (m/s)",
        ylabel="|axis turn| (deg)",
        ylim=(0.0, 400.0),
        title="#3, normal impact, nose cut 40 mm behind the tip",
    )
    legend_outside(axes, fontsize=7, title="cut's angle")
    _save(fig, "erosion_turn.png")
    cut = [b for b in record["bodies"] if b["body"] != "whole"]
    angles = [float(b["body"].split()[0]) for b in cut]
    fig, left = plt.subplots(figsize=(6.5, 4.2))
    critical = [b["critical_velocity"] if b["critical_velocity"] is not None else math.nan for b in cut]
    left.plot(angles, critical, "o-", color="C3", label="critical impact velocity")
    left.set(
        xlabel="angle of the cut's normal from the axis (deg)",
        ylabel="critical impact velocity (m/s)",
        ylim=(0, CRITICAL_RANGE[1]),
    )
    right = left.twinx()
    right.plot(
        angles,
        [abs(next(r for r in b["runs"] if r["speed"] == 1200)["axis_turn"]) for b in cut],
        "s--",
        color="C0",
        label="axis turn at 1200 m/s",
    )
    right.set(ylabel="|axis turn| at 1200 m/s (deg)")
    handles, labels = (
        sum(pair, []) for pair in zip(left.get_legend_handles_labels(), right.get_legend_handles_labels())
    )
    legend_below(left, handles=handles, labels=labels)
    _save(fig, "erosion_critical.png")


def _save(fig, name: str) -> None:
    fig.tight_layout()
    temporary = HERE / f".{name}.tmp.png"
    fig.savefig(temporary, dpi=110)
    temporary.replace(HERE / name)
    plt.close(fig)


def main() -> None:
    study_main(HERE / "erosion.json", study, figures, report)


if __name__ == "__main__":
    main()
