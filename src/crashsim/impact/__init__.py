"""Planar impulse-momentum impact of articulated vehicles (Brach's model)."""

from .problem import (CrushSurface, ExternalImpulse, ImpactProblem, TangentialLaw, VelocityConstraint,
                    tyre_friction_impulse)
from .result import BodyImpact, ConstraintImpulse, HitchImpulse, ImpactResult, clock_direction
from .solve import CONDITION_LIMIT, ImpactBatch, compile_problem, solve_impact

__all__ = [
    "CrushSurface", "ExternalImpulse", "ImpactProblem", "TangentialLaw", "VelocityConstraint",
    "tyre_friction_impulse", "BodyImpact", "ConstraintImpulse", "HitchImpulse", "ImpactResult",
    "clock_direction", "CONDITION_LIMIT", "ImpactBatch", "compile_problem", "solve_impact",
]
