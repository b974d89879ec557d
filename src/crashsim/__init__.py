"""crashsim: reconstruction of collisions involving articulated vehicles.

Impact (impulse-momentum, pin-connected rigid bodies), run-out of the whole scene to rest,
and the checks against the evidence found at the scene.

Start here
----------
load(path)
    Read and validate a scenario file (TOML) -> Scenario.
run(scenario_or_path, **overrides)
    Impact, run-out and evidence of a scene -> SceneResult, e.g.
    ``scene = crashsim.run("scene.toml", vehicles__car__speed="35 mph")``.
    The result has ``.report(units="US")``, ``.to_dict()``, ``.plot(ax=None)``,
    ``.animate("scene.gif")``, ``.history(dt)`` (arrays), ``.history_frame(dt)`` (pandas),
    ``.write_csv(dir, system=..., dt=...)``, and the parts: ``.impact`` (ImpactResult),
    ``.runout`` (per vehicle), ``.impacts`` (every impact), ``.evidence``.
fit(scenario_or_path, **options)
    Fit the ``[fit]`` unknowns to the evidence -> FitResult.
monte_carlo(scenario_or_path, samples, **options)
    Propagate the ``[uncertainty]`` inputs -> MCResult.
posterior(scenario_or_path, **options)
    MCMC posterior of the ``[fit]`` unknowns given the evidence -> PosteriorResult.
Scene(scenario)
    A scene built once, its inputs varied by name: ``Scene(load(path)).inputs(["vehicles.B.speed"])``
    gives a SceneInputs whose ``.run([12.5])`` (SI values, one per path) returns the SceneResult, or
    with ``record=`` only what the record reads; the door fit, Monte Carlo, posterior and the live
    view run through.
open_live(path)
    The live view of a scene, served on 127.0.0.1 in the background -> LiveServer (a notebook
    shows it inline; ``.url``, ``.stop()``; the ``live`` extra).

Lower levels: :func:`solve_impact` with :class:`ImpactProblem` (the impulse-momentum solver),
:mod:`crashsim.motion` (run-outs), :mod:`crashsim.plotting`, :mod:`crashsim.units`.
Everything inside is SI; units are converted at the edges (:mod:`crashsim.units`).
"""

import logging as _logging

from ._lazy import lazy_exports as _lazy_exports
from ._version import __version__
from .errors import CrashsimError, IllConditionedError, ScenarioError, SolverError

# Library code never prints: warnings go to the "crashsim" logger, silent unless the
# application configures logging (the standard library's advice for libraries).
_logging.getLogger("crashsim").addHandler(_logging.NullHandler())

__all__ = [
    "load", "run", "fit", "monte_carlo", "posterior", "open_live", "Scene",
    "CrashsimError", "IllConditionedError", "ScenarioError", "SolverError",
    "Axle", "Body", "BodyState", "Hitch", "Vehicle", "chain_states",
    "CrushSurface", "ExternalImpulse", "ImpactBatch", "ImpactProblem", "ImpactResult", "TangentialLaw",
    "VelocityConstraint", "solve_impact", "tyre_friction_impulse",
]

# The light face: everything but the version and the errors is imported on first use (PEP 562), so
# ``import crashsim`` loads neither numpy nor the kernels (numba), SciPy or matplotlib.
__getattr__, __dir__ = _lazy_exports(__name__, {
    **dict.fromkeys(("fit", "load", "monte_carlo", "posterior", "run"), ".api"),
    "open_live": ".live.server",
    "Scene": ".reconstruct.inputs",
    **dict.fromkeys(("CrushSurface", "ExternalImpulse", "ImpactBatch", "ImpactProblem", "ImpactResult",
                     "TangentialLaw", "VelocityConstraint", "solve_impact", "tyre_friction_impulse"), ".impact"),
    **dict.fromkeys(("Axle", "Body", "BodyState", "Hitch", "Vehicle", "chain_states"), ".vehicles"),
})
