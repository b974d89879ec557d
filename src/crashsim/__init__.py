"""crashsim: reconstruction of collisions involving articulated vehicles.

Impact (impulse-momentum, pin-connected rigid bodies), run-out to rest, and evidence checks.
"""

from .errors import CrashsimError, IllConditionedError, ScenarioError, SolverError
from .vehicles import Axle, Body, BodyState, Hitch, Vehicle, chain_states
from .impact import (CrushSurface, ExternalImpulse, ImpactBatch, ImpactProblem, ImpactResult, TangentialLaw,
                     VelocityConstraint, solve_impact, tyre_friction_impulse)

__version__ = "0.1.0"

__all__ = [
    "CrashsimError", "IllConditionedError", "ScenarioError", "SolverError",
    "Axle", "Body", "BodyState", "Hitch", "Vehicle", "chain_states",
    "CrushSurface", "ExternalImpulse", "ImpactBatch", "ImpactProblem", "ImpactResult", "TangentialLaw",
    "VelocityConstraint", "solve_impact", "tyre_friction_impulse",
]
