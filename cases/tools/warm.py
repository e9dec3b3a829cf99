"""Warm the caches a first study would otherwise fill: numba's machine code and the shipped scenes' meshes.

``./dev`` runs ``python -m cases.tools.warm`` after installing, so that the first run or study on a
fresh machine compiles nothing and meshes nothing (the README's promise).  Each shipped scene (or each
scene given) is prepared (gmsh mesh, mass properties and quadrature, into the disk cache of
:func:`cases.run.cache_dir`); a scene a study would run compiled builds its compiled step (numba compiles
each argument type once: a scene with gravity is another signature), and a scene the reduced model takes
runs one reduced trajectory and the ensembles' sort of samples.  On a warm cache this only loads (a few
seconds); what it has to compile or mesh it announces on stderr first.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from .. import SCENE_DIR
from ..run import PreparedProjectile, prepare_projectile
from ..run.compiled import ENTRY_POINTS, needs_compiling
from ..run.prepare import preparation_key, prepared_path
from ..run.runner import compiled_driving
from ..scene import InputError, Scene, load_scene

__all__ = ["warm_caches", "main"]


def _compiled(scene: Scene, prepared: PreparedProjectile) -> None:
    from dynamics import METHODS, RigidBody

    body = RigidBody(prepared.mass.mass, prepared.mass.inertia)
    compiled_driving(scene, scene.loads(prepared.quadrature), body, METHODS[scene.numerics.integrator]())


def _reduced(scene: Scene, prepared: PreparedProjectile) -> None:
    from ..studies.reduced.pitch_plane import ReducedModel

    try:
        model = ReducedModel(scene, prepared)
    except InputError:  # a body or target the reduced model does not take: nothing of it to compile
        return
    model.run(scene.impact.speed)
    model.unstable(np.zeros(0), np.zeros((0, 6)))  # the multi-fidelity sort's many runs in one call


def warm_caches(
    scenes: Sequence[Path], say: Callable[[str], None] = lambda line: print(line, file=sys.stderr, flush=True)
) -> tuple[float, bool]:
    """Prepare each scene and compile what its studies run; return the wall time (s) and whether
    anything had to be meshed or compiled (else everything was cached already)."""
    start = time.perf_counter()
    filled = any(needs_compiling(entry) for entry in ENTRY_POINTS)
    for path in scenes:
        scene = load_scene(path).with_kernel(many_runs=True)
        if not prepared_path(*preparation_key(scene)).exists():
            filled = True
            say(f"penetrate: meshing {path.name} (gmsh; a few seconds, once)")
        prepared = prepare_projectile(scene)
        if scene.numerics.kernel == "compiled":
            _compiled(scene, prepared)
        _reduced(scene, prepared)
    return time.perf_counter() - start, filled


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m cases.tools.warm", description=(__doc__ or "").split("\n\n", maxsplit=1)[0]
    )
    parser.add_argument("scenes", nargs="*", type=Path, help="scene files (default: every shipped scene)")
    options = parser.parse_args(argv)
    scenes = options.scenes or sorted(SCENE_DIR.glob("*.toml"))
    seconds, filled = warm_caches(scenes)
    if filled:  # silent when everything was cached: ./dev runs this before every command
        print(f"penetrate: caches warm for {len(scenes)} scenes ({seconds:.1f} s)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
