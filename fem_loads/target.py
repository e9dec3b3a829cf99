"""Targets and optional load effects: layers, free-surface reduction, friction.

Every effect here is optional; :class:`~fem_loads.dafl.DAFLLoads` takes the
cheap path when an effect is absent, so a scene pays only for what it asks.

Equations (docs/effects.md):

* **Layers**: interfaces at depths ``d_1 < d_2 < ...`` below the surface;
  a point at depth ``d`` uses the law of the layer containing it, blended
  smoothly across each interface over the point's own extent ``l``
  (``S((d - d_k)/l + 1/2)``, :mod:`fem_loads.ramps`); ``l = 0`` is the sharp switch.
* **Free-surface reduction**: the normal stress of a point at depth ``d`` is
  multiplied by ``f(d) = f0 + (1 - f0) S(d / D)``, ``S`` the smooth step of
  :mod:`fem_loads.ramps` (from ``f0`` at the surface to 1 below ``D``): the
  resistance of a near-surface element is lowered because the target
  material can flow to the free surface.  This follows the idea of the
  free-surface corrections of Warren and Poormon (2001) and Warren, Hanchak
  and Poormon (2004), which reduce the cavity-expansion stress with the
  element's proximity to the free surface; the ramp with the two parameters
  ``D`` (``depth``) and ``f0`` (``surface_fraction``) is our simplest form of
  it, not their calibrated function.  (A linear ramp would put kinks in the
  load at ``d = 0`` and ``d = D``, which cost a Runge-Kutta method its order.)
* **Friction**: a tangential stress ``tau`` opposite to the local slip
  ``u_t = u - Vn n``: Coulomb ``tau = mu sigma_n`` or capped
  ``tau = min(mu sigma_n, tau_s)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .ramps import smooth_step
from .resistance import ResistanceLaw

__all__ = ["LayeredTarget", "FreeSurface", "Friction"]


@dataclass(frozen=True)
class LayeredTarget:
    """Layers parallel to the surface, from the top down.

    Parameters
    ----------
    thicknesses : sequence of float
        Thickness (m) of every layer but the last, which extends to infinity.
    laws : sequence of ResistanceLaw
        One law per layer (``len(thicknesses) + 1`` of them).
    """

    thicknesses: tuple[float, ...]
    laws: tuple[ResistanceLaw, ...]
    # derived in __post_init__: the interfaces' depths (m) and each layer's ``A sigma_0`` and ``B rho_0``
    _interfaces: np.ndarray = field(init=False, repr=False, compare=False)
    _static: np.ndarray = field(init=False, repr=False, compare=False)
    _dynamic: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if len(self.laws) != len(self.thicknesses) + 1:
            raise ValueError("layers: every layer but the last needs a thickness")
        if not all(t > 0 and math.isfinite(t) for t in self.thicknesses):
            raise ValueError("layers: thicknesses must be finite numbers > 0")
        object.__setattr__(self, "_interfaces", np.cumsum(self.thicknesses))
        object.__setattr__(self, "_static", np.array([law.static_stress for law in self.laws]))
        object.__setattr__(self, "_dynamic", np.array([law.dynamic_density for law in self.laws]))

    def coefficients(self, depth: np.ndarray, lengths: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``A sigma_0`` and ``B rho_0`` at each depth (m below the surface).

        ``lengths`` (m, one per point, or None): the width over which each point's
        coefficients blend from one layer to the next, centred on the interface; zero or
        None is the sharp switch.
        """
        if lengths is None or not np.any(lengths):
            layer = np.searchsorted(self._interfaces, depth, side="right")
            return self._static[layer], self._dynamic[layer]
        static = np.full(np.shape(depth), self._static[0])
        dynamic = np.full(np.shape(depth), self._dynamic[0])
        for k, interface in enumerate(self._interfaces):
            blend = smooth_step((depth - interface) / lengths + 0.5)
            static += (self._static[k + 1] - self._static[k]) * blend
            dynamic += (self._dynamic[k + 1] - self._dynamic[k]) * blend
        return static, dynamic


@dataclass(frozen=True)
class FreeSurface:
    """Linear free-surface reduction of the normal stress near the surface.

    Parameters
    ----------
    depth : float
        Depth ``D`` (m) below which the full resistance acts.
    surface_fraction : float
        Fraction ``f0`` of the resistance at the surface itself, 0 <= f0 <= 1.
    """

    depth: float
    surface_fraction: float = 0.0

    def factor(self, depth: np.ndarray) -> np.ndarray:
        """``f0 + (1 - f0) S(depth / D)``: ``f0`` at and above the surface, 1 below ``D``."""
        return self.surface_fraction + (1.0 - self.surface_fraction) * smooth_step(np.asarray(depth) / self.depth)


@dataclass(frozen=True)
class Friction:
    """Tangential stress opposite to the slip: ``mu sigma_n``, capped at ``cap`` (Pa) if given."""

    coefficient: float
    cap: float | None = None

    def stress(self, sigma: np.ndarray) -> np.ndarray:
        tau = self.coefficient * sigma
        return tau if self.cap is None else np.minimum(tau, self.cap)
