"""Planar impulse-momentum impact of articulated vehicles (Brach's model).

The names are imported from their modules on first use (PEP 562): the problem types
(:mod:`.problem`) load numpy only; the result (:mod:`.result`) and the solver (:mod:`.solve`) load
the compiled kernel's module (numba).
"""

from .._lazy import lazy_exports

__all__ = [
    "CrushSurface", "ExternalImpulse", "ImpactProblem", "TangentialLaw", "VelocityConstraint",
    "tyre_friction_impulse", "BodyImpact", "ConstraintImpulse", "HitchImpulse", "ImpactResult",
    "clock_direction", "CONDITION_LIMIT", "ImpactBatch", "compile_problem", "solve_impact",
]

__getattr__, __dir__ = lazy_exports(__name__, {
    **dict.fromkeys(("CrushSurface", "ExternalImpulse", "ImpactProblem", "TangentialLaw", "VelocityConstraint",
                     "tyre_friction_impulse"), ".problem"),
    **dict.fromkeys(("BodyImpact", "ConstraintImpulse", "HitchImpulse", "ImpactResult", "clock_direction"),
                    ".result"),
    **dict.fromkeys(("CONDITION_LIMIT", "ImpactBatch", "compile_problem", "solve_impact"), ".solve"),
})
