"""crashsim: reconstruction of collisions involving articulated vehicles.

Impact (impulse-momentum, pin-connected rigid bodies), run-out to rest, and evidence checks.
"""

import logging as _logging

from .errors import CrashsimError, IllConditionedError, ScenarioError, SolverError
from .vehicles import Axle, Body, BodyState, Hitch, Vehicle, chain_states
from .impact import (CrushSurface, ExternalImpulse, ImpactBatch, ImpactProblem, ImpactResult, TangentialLaw,
                     VelocityConstraint, solve_impact, tyre_friction_impulse)

__version__ = "0.1.0"

# Library code never prints: warnings go to the "crashsim" logger, silent unless the
# application configures logging (the standard library's advice for libraries).
_logging.getLogger("crashsim").addHandler(_logging.NullHandler())

__all__ = [
    "CrashsimError", "IllConditionedError", "ScenarioError", "SolverError",
    "Axle", "Body", "BodyState", "Hitch", "Vehicle", "chain_states",
    "CrushSurface", "ExternalImpulse", "ImpactBatch", "ImpactProblem", "ImpactResult", "TangentialLaw",
    "VelocityConstraint", "solve_impact", "tyre_friction_impulse",
]
