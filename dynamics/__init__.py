"""Rigid-body dynamics: state, quaternion kinematics, Runge-Kutta integrators, step control and events.

This package takes a load function and knows nothing of meshes or resistance laws.
What it may import is written once, in pyproject.toml's [tool.penetrate.rooms].
"""

from .control import ENERGY_TOLERANCE, NON_FINITE, STEP_FLOOR, EnergyGuard, ErrorControl, FixedStep, StepControl
from .integrators import METHODS, RK4, DormandPrince54, RungeKutta
from .rigid_body import LoadFunction, RigidBody, State
from .simulate import MAX_STEPS, TIME_LIMIT, AdvanceEnds, Event, SpeedBelow, Trajectory, simulate

__all__ = [
    "RigidBody",
    "State",
    "LoadFunction",
    "RungeKutta",
    "RK4",
    "DormandPrince54",
    "METHODS",
    "StepControl",
    "FixedStep",
    "ErrorControl",
    "EnergyGuard",
    "ENERGY_TOLERANCE",
    "Event",
    "SpeedBelow",
    "AdvanceEnds",
    "Trajectory",
    "simulate",
    "TIME_LIMIT",
    "NON_FINITE",
    "MAX_STEPS",
    "STEP_FLOOR",
]
