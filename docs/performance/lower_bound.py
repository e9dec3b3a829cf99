"""One DAFL load evaluation three ways, as docs/performance/loads.py and the load benchmark time it.

The numpy load (``fem_loads.DAFLLoads`` as a run calls it), the compiled kernel called ``repeat`` times
from compiled code (as inside a compiled step, :func:`compiled_call`), and a compiled lower bound: a plain
C loop over every point with the same smooth steps (:func:`c_loop_call`), built with the system C compiler
and the licence the compiled kernel has (reassociation, fused multiply-adds), called once per ``repeat``
evaluations so that the ctypes call does not count.  The state is :func:`benchmark_state`: #3 at 800 m/s
with a 1-degree attack angle and a pitch rate.
"""

from __future__ import annotations

import ctypes
import functools
import shutil
import statistics
import subprocess
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from cases.run.compiled import compiled_modules
from dynamics.quaternion import rotation_matrix
from fem_loads.factors import contact_width_scalars, speed_scale_scalars

C_LOOP = r"""
/* The DAFL load of one law with separation and both smooth ramps (the scenes' default load), over
   every point: the same arrays as fem_loads.DAFLLoads, no mirror images. */
static inline double smooth_step(double t) {
    t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    return t * t * t * (10.0 + t * (6.0 * t - 15.0));
}

void dafl(long n, const double *normal_arm /* 6 x n */, const double *points /* 3 x n */,
          const double *static_w, const double *dynamic_w, const double *inverse_entry,
          const double *g /* R^T V, omega */, const double *rz /* third row of R */, double z,
          double inverse_width, int embedded, double *out, long repeat) {
    for (long r = 0; r < repeat; ++r) {
        double acc[6] = {0, 0, 0, 0, 0, 0};
        for (long i = 0; i < n; ++i) {
            double vn = 0.0;
            for (int k = 0; k < 6; ++k) vn += normal_arm[k * n + i] * g[k];
            double s = (static_w[i] + dynamic_w[i] * vn * vn) * smooth_step(vn * inverse_width);
            if (!embedded) {
                double height = z + rz[0] * points[i] + rz[1] * points[n + i] + rz[2] * points[2 * n + i];
                s *= smooth_step(0.5 - height * inverse_entry[i]);
            }
            for (int k = 0; k < 6; ++k) acc[k] -= s * normal_arm[k * n + i];
        }
        for (int k = 0; k < 6; ++k) out[k] = acc[k];
    }
}
"""
# the licence numba's kernel has (reassociation, fused multiply-adds; fem_loads/kernels/mesh_loop.py), and no more
C_FLAGS = [
    "-O3",
    "-march=native",
    "-fno-math-errno",
    "-fno-trapping-math",
    "-fno-signed-zeros",
    "-fassociative-math",
    "-ffp-contract=fast",
]


def c_compiler() -> str | None:
    """The system C compiler (``cc`` or ``gcc``), or None."""
    return shutil.which("cc") or shutil.which("gcc")


def c_kernel(folder: Path):
    """The C loop built in ``folder``: ``(library, pointer type)``, the function ``library.dafl``."""
    compiler = c_compiler()
    if compiler is None:
        raise RuntimeError("no C compiler (cc or gcc) for the compiled lower bound")
    source, library = folder / "dafl.c", folder / "libdafl.so"
    source.write_text(C_LOOP)
    subprocess.run([compiler, *C_FLAGS, "-shared", "-fPIC", "-o", str(library), str(source)], check=True)
    lib = ctypes.CDLL(str(library))
    pointer = ctypes.POINTER(ctypes.c_double)
    lib.dafl.argtypes = [
        ctypes.c_long,
        pointer,
        pointer,
        pointer,
        pointer,
        pointer,
        pointer,
        pointer,
        ctypes.c_double,
        ctypes.c_double,
        ctypes.c_int,
        pointer,
        ctypes.c_long,
    ]
    return lib, pointer


@functools.cache
def repeated_kernel():
    """The compiled kernel called ``repeat`` times from compiled code (as inside a compiled step)."""
    from numba import njit

    kernel = compiled_modules()[1].dafl_kernel

    @njit
    def repeated(data, position, velocity, rotation, spin, out, repeat):
        for _ in range(repeat):
            kernel(data, position, velocity, rotation, spin, out)

    return repeated


def median_per_call(call: Callable[[int], object], repeats: int = 100, samples: int = 15) -> float:
    """The median over ``samples`` of the seconds per evaluation of ``call(repeats)``."""
    times = []
    for _ in range(samples):
        start = time.perf_counter()
        call(repeats)
        times.append((time.perf_counter() - start) / repeats)
    return statistics.median(times)


def benchmark_state(depth: float):
    """The state of projectile #3 at 800 m/s with a 1-degree attack angle and a pitch rate, its centre of mass at
    ``depth`` (m; -3 wholly embedded, -0.3 with the nose entering): ``(position, velocity, rotation, spin)``."""
    rotation = rotation_matrix(np.array([np.cos(np.radians(0.5)), 0.0, np.sin(np.radians(0.5)), 0.0]))
    velocity = rotation @ np.array([800.0, 10.0, 0.0])
    return np.array([0.0, 0.0, depth]), velocity, rotation, np.array([0.0, 0.5, 2.0])


def compiled_call(loads, position, velocity, rotation, spin) -> Callable[[int], np.ndarray]:
    """``call(repeat)``: the compiled kernel of ``loads`` evaluated ``repeat`` times from compiled code at this
    state; it returns the load (force and moment, world frame)."""
    data, out, repeated = compiled_modules()[1].kernel_data(loads), np.zeros(6), repeated_kernel()

    def call(repeat: int) -> np.ndarray:
        repeated(data, position, velocity, rotation, spin, out, repeat)
        return out

    return call


def c_loop_call(loads, position, velocity, rotation, spin, folder: Path) -> Callable[[int], np.ndarray]:
    """``call(repeat)``: the C loop (built in ``folder``) over every point of ``loads`` (no mirror images) at this
    state, ``repeat`` times; it returns the load (force in the body frame, moment)."""
    lib, pointer = c_kernel(folder)
    n = len(loads)
    speed_scale = speed_scale_scalars(float(np.linalg.norm(velocity)), float(np.linalg.norm(spin)), loads.max_radius)
    width = contact_width_scalars(loads.contact_width, loads.contact_incidence, speed_scale)
    weights = loads.quadrature.weights
    per_point = loads.point_arrays()
    arrays = [
        np.ascontiguousarray(a)
        for a in (
            per_point["normal_arm"],
            per_point["points"],
            loads.law.c0 * weights,
            loads.law.c2 * weights,
            1.0 / per_point["entry_length"],
            np.concatenate([velocity @ rotation, spin]),
            rotation[2],
        )
    ]
    out = np.zeros(6)

    def call(repeat: int) -> np.ndarray:
        lib.dafl(
            n,
            *(a.ctypes.data_as(pointer) for a in arrays),
            position[2],
            1.0 / width,
            int(loads.fully_embedded(position)),
            out.ctypes.data_as(pointer),
            repeat,
        )
        return out

    return call
