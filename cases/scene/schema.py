"""The scene schema: what a TOML scene may say, with units and allowed ranges.

Every model forbids unknown keys and non-finite numbers.  Units are SI except
angles, which are in degrees where the name ends in ``angle``.  The projectile
(:mod:`.projectile`) and the target and effects (:mod:`.target`) have their
own modules; a :class:`Scene` builds its DAFL load function from them.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal, Self

import numpy as np
from pydantic import BeforeValidator, model_validator

from fem_loads import DAFLLoads, SurfaceQuadrature

from .base import Label, Number, Strict, Whole, field, not_boolean
from .plausible import MESH_SIZE, slip_hint
from .projectile import Projectile
from .target import Effects, Target, UserLawSpec

__all__ = ["Scene", "Impact", "Numerics", "Outputs", "MAX_STEPS", "MAX_MESH_CELLS", "STOP_SPEED_FRACTION"]

MAX_STEPS = 5_000_000  # dynamics.simulate's max_steps: no run takes more than time_limit / time_step
# the stop speed is at most this share of the impact speed V0: from a speed v, a body under a static resistance F
# still travels m v^2 / (2 F), at most (v / V0)^2 of its depth, here 0.1 % (docs/numerics.md, the end of a run)
STOP_SPEED_FRACTION = 0.03
MAX_MESH_CELLS = 2e6  # cells of mesh_size^3 in the projectile's bounding cylinder (about 1e7 tetrahedra)


class Impact(Strict):
    """Initial conditions; the tip (or, at grazing incidence, the lowest point) touches the surface."""

    speed: Number = field(unit="m/s", gt=0.0, le=1e4, description="of the centre of mass at impact")
    oblique_angle: Number = field(0.0, unit="deg", gt=-90.0, lt=90.0, description="velocity from the target normal")
    attack_angle: Number = field(
        0.0, unit="deg", ge=-90.0, le=90.0, description="axis from the velocity, in the vertical plane"
    )
    yaw_angle: Number = field(0.0, unit="deg", gt=-90.0, lt=90.0, description="axis out of the vertical plane")
    angular_velocity: tuple[Number, Number, Number] = field(
        (0.0, 0.0, 0.0), unit="rad/s", description="body frame: x along the axis, y normal to the vertical plane"
    )

    @model_validator(mode="after")
    def _bounded_spin(self) -> Self:
        if max(abs(w) for w in self.angular_velocity) > 1e5:
            raise ValueError("angular_velocity: each component must lie in [-1e5, 1e5] rad/s")
        return self


class Numerics(Strict):
    """Discretisation and integration settings."""

    mesh_size: Number = field(unit="m", gt=0.0, le=10.0, plausible=MESH_SIZE, description="target element size")
    geometry_order: Annotated[Literal[1, 2], BeforeValidator(not_boolean)] = field(
        2, description="1: flat tetrahedra; 2: curved (quadratic) ones, which follow a curved surface"
    )
    normals: Literal["exact", "mesh"] = field(
        "exact", description="the surface points and normals of the exact shape, or of the mesh's facets"
    )
    quadrature_order: Whole = field(2, ge=1, le=10, description="degree exact on each facet")
    integrator: Literal["rk4", "dopri54"] = field(
        "rk4", description="rk4: fixed steps of time_step; dopri54: adaptive Dormand-Prince steps to rtol"
    )
    time_step: Number = field(
        2e-5,
        unit="s",
        gt=0.0,
        le=1e-2,
        description="fixed step (rk4); the error control shortens no step below it (dopri54)",
    )
    rtol: Number = field(1e-6, gt=0.0, lt=1.0, description="relative tolerance (dopri54)")
    time_limit: Number = field(1.0, unit="s", gt=0.0, le=100.0, description="the run ends here at the latest")
    stop_speed: Number = field(
        0.5,
        unit="m/s",
        gt=0.0,
        le=1e3,
        description="the run ends when the speed falls below this, or below 3 % of the impact speed when that is less",
    )
    slow_fraction: Number = field(
        0.1,
        gt=0.0,
        lt=1.0,
        description="of the impact speed: a body this slow or slower that no longer moves nose first has stopped"
        " (docs/numerics.md, the end of a run)",
    )
    normal_velocity_guard: Number = field(
        1e-9, ge=0.0, le=1e-3, description="relative guard on Vn = 0 (sharp contact only)"
    )
    entry_smoothing: Number = field(
        4.0,
        ge=0.0,
        le=10.0,
        description="length over which a surface point enters the target (and crosses a"
        " layer interface), in units of its own size (the square root of its"
        " weight); 4 keeps RK4's time error under the mesh error at the longest"
        " stable step (docs/accuracy.md); 0: sharp",
    )
    energy_guard: bool = field(True, description="retake shorter any step that gains kinetic energy")
    kernel: Literal["auto", "numpy", "compiled"] = field(
        "auto",
        description="how the steps are computed: numpy (the reference), compiled (numba: the whole Runge-Kutta"
        " step in machine code, after about 0.6 s of loading per process) or auto (compiled in"
        " studies, whose workers load it once, where it is the faster: built-in laws with the smooth ramps and"
        " separation; numpy for a single run, a user's law or another switch)",
    )

    def stop_speed_at(self, impact_speed: float | np.ndarray) -> Any:
        """The speed (m/s) below which a run at ``impact_speed`` (m/s) has stopped: ``stop_speed``, at most
        :data:`STOP_SPEED_FRACTION` of the impact speed (a float, or an array for an array of speeds)."""
        stop = np.minimum(self.stop_speed, STOP_SPEED_FRACTION * np.asarray(impact_speed, dtype=float))
        return float(stop) if stop.ndim == 0 else stop

    @model_validator(mode="after")
    def _reachable_time_limit(self) -> Self:
        # rk4 steps by time_step; dopri54's error control shortens no step below it, but an event, the energy guard
        # or a sharp switch can, so this bounds the steps of rk4 and most of dopri54's
        if self.time_limit / self.time_step > MAX_STEPS:
            raise ValueError(
                f"time_step = {self.time_step:g}: {self.time_limit / self.time_step:.3g} steps to reach"
                f" time_limit = {self.time_limit:g} s (allowed: time_limit / time_step <= {MAX_STEPS:g};"
                " shorten time_limit or lengthen time_step)"
            )
        return self


class Outputs(Strict):
    """What a run writes with --out."""

    history: bool = field(True, description="write history.csv, the state at every kept step")
    history_every: Whole = field(1, ge=1, le=1_000_000, description="keep every n-th step")


class Scene(Strict):
    """A complete scene: projectile, target, impact, numerics and outputs."""

    name: Label = field("", description="the scene's name in summaries and tables (default: the file's name)")
    description: Label = field("", description="one line, printed with the summary")
    projectile: Projectile
    target: Target = Target()
    effects: Effects = Effects()
    impact: Impact
    numerics: Numerics
    outputs: Outputs = Outputs()

    @model_validator(mode="after")
    def _meshable(self) -> Self:
        # a guard against typos (1e-5 for 1e-2) that would mesh forever: the studies' finest mesh has ~1e5 cells
        p, size = self.projectile, self.numerics.mesh_size
        if p.geometry is not None:
            if self.numerics.normals == "exact" and not p.geometry.is_cad:
                raise ValueError(
                    "numerics.normals = 'exact' needs an exact surface to take the normals from, and a mesh file"
                    " has none: set numerics.normals = 'mesh' (the mesh's own; docs/geometry.md says"
                    " what they cost in accuracy)"
                )
            return self  # the file's size is known once it is read (mesh.imported checks the mesh size)
        assert p.diameter is not None and p.length is not None  # an analytic projectile has both (Projectile)
        finest = (0.25 * math.pi * p.diameter**2 * p.length / MAX_MESH_CELLS) ** (1 / 3)
        if size < finest:
            raise ValueError(
                f"numerics.mesh_size = {size:g}: too fine for this projectile (allowed: numerics.mesh_size"
                f" >= {finest:.3g} m, at most {MAX_MESH_CELLS:g} cells of mesh_size^3 in"
                " pi/4 diameter^2 length)"
            )
        if size > p.diameter:  # describes nothing of the cross-section; gmsh fails on such meshes (HXT, Newton)
            # the plausible range of a mesh size is this projectile's: finest to its diameter (mm for m is likely)
            hint = slip_hint(size, "m", finest, p.diameter)
            raise ValueError(
                f"numerics.mesh_size = {size:g}: coarser than the projectile (allowed: numerics.mesh_size"
                f" <= projectile.diameter = {p.diameter:g} m)" + (f"; {hint}" if hint else "")
            )
        return self

    @property
    def warnings(self) -> list[str]:
        """What the scene's inputs alone make doubtful, one plain-language line each (empty when nothing needs
        saying): an empirical law used outside the range of the data it was fitted to, or a shot into concrete
        fast enough for the nose to lose mass (:meth:`Target.warnings`).  Such a scene runs: these are lines for a
        run summary's warnings, as ``numerics_warnings`` gives the numerics'."""
        return self.target.warnings(self.impact.speed)

    @property
    def stop_speed(self) -> float:
        """The speed (m/s) below which a run of this scene has stopped (:meth:`Numerics.stop_speed_at`)."""
        return self.numerics.stop_speed_at(self.impact.speed)

    @property
    def compilable(self) -> bool:
        """Whether the compiled kernel computes this scene's load (:func:`fem_loads.kernels.records.compilable` of its
        target): every law and effect, except layers whose laws are not all built in or all one user function."""
        from fem_loads.kernels.records import compilable

        return compilable(self.target.build())

    @property
    def compiled_is_faster(self) -> bool:
        """Whether the compiled kernel computes this scene's load in SIMD lanes
        (:func:`fem_loads.kernels.records.in_lanes`), 1.6-11 times faster than numpy (the least with a power term,
        its pow point by point); any other load it computes point by point, no faster than numpy (a user's law, the
        sharp switch, no separation: docs/performance.md)."""
        from fem_loads.kernels.records import in_lanes

        effects, smooth_entry = self.effects, self.numerics.entry_smoothing > 0
        return in_lanes(self.target.build(), effects.separation, not effects.sharp_contact, smooth_entry)

    def with_kernel(self, many_runs: bool) -> Scene:
        """This scene with ``numerics.kernel`` resolved: ``auto`` is ``compiled`` in a process that runs
        many scenes (a study's worker loads the compiled code once, about 0.6 s) when the compiled kernel is the
        faster for the scene (:attr:`compiled_is_faster`), else ``numpy``."""
        if self.numerics.kernel != "auto":
            return self
        kernel = "compiled" if many_runs and self.compiled_is_faster else "numpy"
        return self.model_copy(update={"numerics": self.numerics.model_copy(update={"kernel": kernel})})

    @model_validator(mode="after")
    def _user_laws_see_pressing_elements(self) -> Self:
        laws = [self.target.law] + [layer.law for layer in self.target.layers or []]
        if not self.effects.separation and any(isinstance(law, UserLawSpec) for law in laws):
            raise ValueError(
                "effects.separation = false: a user law is evaluated at Vn >= 0 only (allowed with a user law:"
                " effects.separation = true; without separation use a built-in law, extended to Vn < 0 as an odd"
                " function)"
            )
        return self

    @model_validator(mode="after")
    def _free_faces_exist(self) -> Self:
        surface = self.effects.free_surface
        if surface is not None and "rear" in surface.faces and math.isinf(self.target.thickness):
            raise ValueError(
                'effects.free_surface.faces: "rear" needs a target with a rear face (allowed for this target:'
                ' ["front"]; a slab\'s last layer has a thickness)'
            )
        return self

    @model_validator(mode="after")
    def _kernel_covers_scene(self) -> Self:
        if self.numerics.kernel == "compiled" and not self.compilable:
            raise ValueError(
                'numerics.kernel = "compiled": the compiled load calls one user function, and these layers'
                ' mix laws (allowed for this scene: "numpy" or "auto")'
            )
        return self

    def loads(self, quadrature: SurfaceQuadrature) -> DAFLLoads:
        """The DAFL load function over ``quadrature`` with exactly the effects the scene asks for."""
        effects = self.effects
        free_surface = effects.free_surface.build(self.target.thickness) if effects.free_surface is not None else None
        return DAFLLoads(
            quadrature,
            self.target.build(),
            self.numerics.normal_velocity_guard,
            friction=effects.friction.build(),
            separation=effects.separation,
            free_surface=free_surface,
            **effects.contact_ramp,
            entry_smoothing=self.numerics.entry_smoothing,
            exposure=effects.exposure,
            front_face=self.target.face,
        )
