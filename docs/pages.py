"""The pages of the documentation by kind, in the order a newcomer walks them: the one list.

``python -m docs.pages map`` prints the lists of docs/README.md; ``python -m docs.pages words`` the words of each
kind.  A word is a run of letters or digits (with the apostrophes, dots and hyphens inside it), counted in a page's
text outside its generated blocks and HTML comments: the generated tables and figures are the commands' output,
not prose.  The pages a user reads (:data:`USER_KINDS`) carry no development history (tests/docs/test_user_pages.py).
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path
from typing import NamedTuple

ROOT = Path(__file__).resolve().parents[1]


class Page(NamedTuple):
    path: str  #: from the repository root
    title: str
    about: str  #: what a reader finds there, one line


#: kind -> (heading of docs/README.md, its pages in reading order)
KINDS: dict[str, tuple[str, tuple[Page, ...]]] = {
    "tutorial": (
        "Tutorial",
        (
            Page(
                "docs/tutorial.md",
                "Your first runs",
                "a shipped scene, a scene of your own projectile, reading the summary, a sweep over impact speed, "
                "a picture of the stress, an oblique shell into concrete (a half-space, a slab, its ballistic limit)",
            ),
        ),
    ),
    "how-to": (
        "How-to: one task each",
        (
            Page(
                "docs/scenes.md",
                "Describe a projectile and a shot",
                "the scene file, copying a shipped scene, overriding keys from the command line, the mass options, "
                "the shipped scenes",
            ),
            Page(
                "docs/geometry.md",
                "Use a measured profile, a CAD file or a volume mesh",
                "units, axes, mirror planes, surface the target cannot reach",
            ),
            Page(
                "docs/laws.md",
                "Choose a resistance law and its constants",
                "cavity expansion, polynomial, power, strength growing with depth, a law of your own, where the "
                "constants come from",
            ),
            Page("docs/effects.md", "Add effects", "friction, separation, free surface, gravity"),
            Page(
                "docs/targets.md",
                "Targets beyond a half-space",
                "slabs and perforation, gaps, inclined faces, the ballistic limit",
            ),
            Page(
                "docs/studies.md",
                "Sweeps, characteristic speeds and stability maps",
                "grids of runs on every core or a Dask cluster, the critical and convergent velocities, maps over "
                "two inputs",
            ),
            Page("docs/ensembles.md", "Ensembles", "outcome probabilities when the impact conditions scatter"),
            Page(
                "docs/series.md",
                "Your measured shots",
                "a test series in a CSV file, predicted against measured, laws ranked on the shots",
            ),
            Page(
                "docs/calibration.md",
                "Fit constants to shots",
                "unknown constants fitted to measurements, with held-out shots predicted",
            ),
            Page(
                "docs/rendering.md",
                "Pictures",
                "off-screen images of the stress on the surface, animations, ParaView files",
            ),
            Page("docs/examples.md", "The Python API", "the library from Python; every example runs as a test"),
            Page(
                "docs/troubleshooting.md",
                "Troubleshooting",
                "set-up, meshing, pictures, and runs that end early",
            ),
        ),
    ),
    "reference": (
        "Reference",
        (
            Page("docs/reference/scene.md", "Scene keys", "every key with its unit, default and allowed range"),
            Page("docs/reference/cli.md", "The penetrate command", "every command and option"),
            Page(
                "docs/reference/run-outputs.md", "What a run writes", "the summary's fields and the history's columns"
            ),
            Page("docs/reference/study-outputs.md", "What the studies write", "each study's files, columns and fields"),
            Page(
                "docs/reference/ends.md",
                "End reasons, warnings and exit codes",
                "each with what it means and what to do",
            ),
            Page("docs/reference/units.md", "Units, frames and signs", "SI units, the frames, the angles' signs"),
            Page("docs/reference/glossary.md", "Glossary", "every term these pages use"),
        ),
    ),
    "explanation": (
        "Explanation",
        (
            Page(
                "docs/model.md",
                "The model",
                "the differential area force law, the contact and entry ramps, the rigid-body motion, the mass "
                "properties, and where each comes from",
            ),
            Page(
                "docs/numerics.md",
                "Numerics",
                "meshing, quadrature, integrators and step control, the end of a run, the warnings a run carries, "
                "the known weaknesses",
            ),
            Page(
                "docs/theory.md",
                "The reduced model",
                "the characteristic speeds predicted in milliseconds, and why the convergent velocity belongs to the "
                "projectile and the target",
            ),
        ),
    ),
    "evidence": (
        "Evidence",
        (
            Page(
                "docs/validation.md",
                "Validation",
                "closed forms, 1-D integrals, and the shipped test series against their measurements",
            ),
            Page(
                "docs/accuracy.md",
                "Accuracy against cost",
                "error against run time for mesh size, quadrature and time step; the recommended settings",
            ),
            Page(
                "docs/evidence-formulas.md",
                "The empirical formulas beside the model",
                "Young, NDRC, ACE, UKAEA, Li and Chen: what each says, its source, what was checked",
            ),
            Page("docs/paper.md", "The paper's study reproduced", "the instability study, with every gap"),
            Page("docs/paper/results.md", "The paper's study: tables and figures", "generated"),
            Page("docs/paper/variants.md", "The paper's variants", "friction, a conical nose, other soils"),
            Page(
                "docs/evidence-numerics.md",
                "Numerics and the contact model: the evidence",
                "the contact ramps measured down to their limits, the two kernels against each other, the hard cases",
            ),
            Page(
                "docs/evidence-geometry.md",
                "Projectiles from files: the evidence",
                "files against the analytic bodies, what flat facets cost, mirror planes, exact normals, exposure, "
                "the shipped non-axisymmetric bodies, the eroded nose",
            ),
            Page(
                "docs/evidence-laws.md",
                "Resistance laws: the evidence",
                "every law family against a 1-D integration, six laws compared on test 2 and #3",
            ),
            Page(
                "docs/evidence-effects.md",
                "Effects: the evidence",
                "friction against its closed form, a free surface on the concrete series, what each effect costs",
            ),
            Page(
                "docs/evidence-targets.md",
                "Targets: the evidence",
                "slabs, gaps and inclined faces against the 1-D model of the nose, the ballistic-limit search",
            ),
            Page(
                "docs/evidence-studies.md",
                "Studies: the evidence",
                "the 30-degree rule, the convergence speed, guided against unguided searches, a stability map of #3",
            ),
            Page(
                "docs/evidence-ensembles.md",
                "Ensembles: the evidence",
                "the probability that #3 turns unstable under scattered disturbances, multi-fidelity against full runs",
            ),
            Page(
                "docs/evidence-calibration.md",
                "Calibration: the evidence",
                "the soil fitted to Forrestal and Luk's shots, the family's interior fitted to #3 alone",
            ),
            Page(
                "docs/evidence-theory.md",
                "The reduced model: the evidence",
                "predicted against measured characteristic speeds for the family, the variants and two other noses",
            ),
            Page(
                "docs/evidence-rendering.md",
                "Pictures: the evidence",
                "a picture shows the integrated field; what a render costs",
            ),
        ),
    ),
    "contributors": (
        "For contributors",
        (
            Page(
                "docs/architecture.md",
                "Architecture",
                "the packages (rooms) and what each may import, one run followed through the code, the caches, CI",
            ),
            Page(
                "docs/performance.md",
                "Performance",
                "what runs and studies cost, the compiled step, benchmarks",
            ),
            Page("docs/performance/scaling.md", "Scaling", "how times grow with points, steps, runs and workers"),
            Page("docs/robustness.md", "Robustness", "bad input, killed runs, reproducible bits, fuzzing"),
            Page(
                "docs/dev-numerics.md",
                "Numerics: the code",
                "where meshing, quadrature, integration and the compiled step live; the caches; numba",
            ),
            Page(
                "docs/dev-geometry.md",
                "Projectiles from files: code and tests",
                "CAD files, volume meshes, mirror planes, exact-surface quadrature and exposure in the code",
            ),
            Page(
                "docs/dev-laws.md",
                "Laws, effects and targets: code and tests",
                "the single law definition, compiling user laws, the friction sums, nose shapes",
            ),
            Page(
                "docs/dev-studies.md",
                "Studies: code and tests",
                "where each study lives, forked and Dask workers, the run store, the guide's internals",
            ),
            Page("docs/dev-rendering.md", "Pictures: code and tests", "the viz modules, off-screen EGL, render tests"),
            Page(
                "docs/dev-evidence.md",
                "The evidence pages: code and tests",
                "the scripts behind the evidence tables, and which test checks which claim",
            ),
        ),
    ),
}

#: the kinds of page a user reads: no commit hashes, history or module paths (except the Python API page)
USER_KINDS = ("tutorial", "how-to", "reference", "explanation", "evidence")
#: the kinds whose words count against the budget (docs/README.md)
BUDGET_KINDS = ("tutorial", "how-to", "reference", "explanation")
#: the most words the README and the pages of BUDGET_KINDS may hold
WORD_BUDGET = 30_000
#: the user pages that name modules by necessity
API_PAGES = ("docs/examples.md",)


def pages(*kinds: str) -> list[Page]:
    """The pages of these kinds (every kind by default), in reading order."""
    return [page for kind in kinds or tuple(KINDS) for page in KINDS[kind][1]]


def prose(text: str) -> str:
    """A page's text without its generated blocks and HTML comments."""
    text = re.sub(r"<!-- generated by:.*?<!-- end generated[^>]*-->", "", text, flags=re.S)
    return re.sub(r"<!--.*?-->", "", text, flags=re.S)


def words(text: str) -> int:
    """The words of :func:`prose`: runs of letters or digits."""
    return len(re.findall(r"[A-Za-z0-9](?:[\w'.-]*\w)?", prose(text)))


def print_map() -> None:
    for heading, listed in KINDS.values():
        print(f"## {heading}\n")
        for page in listed:
            link = Path(page.path).relative_to("docs").as_posix()
            print(f"* [{page.title}]({link}): {page.about}.")
        print()


def _words_of(paths: list[str]) -> int:
    return sum(words((ROOT / path).read_text()) for path in paths if (ROOT / path).exists())


def budget_words() -> int:
    """The words of the README and the pages of :data:`BUDGET_KINDS`, which :data:`WORD_BUDGET` bounds."""
    return _words_of(["README.md", *(page.path for page in pages(*BUDGET_KINDS))])


def print_words() -> None:
    print("| pages | words |")
    print("|---|---|")
    print(f"| the README | {_words_of(['README.md'])} |")
    for heading, listed in KINDS.values():
        print(f"| {heading} | {_words_of([page.path for page in listed])} |")
    total = f"**{budget_words()}** (at most {WORD_BUDGET})"
    print(f"| **the README, tutorial, how-to, reference and explanation** | {total} |")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m docs.pages", description=(__doc__ or "").split("\n")[0])
    parser.add_argument("what", choices=("map", "words"))
    options = parser.parse_args(argv)
    print_map() if options.what == "map" else print_words()


if __name__ == "__main__":
    main()
