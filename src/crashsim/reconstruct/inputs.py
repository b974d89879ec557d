"""A scene built once, its inputs varied by name: the one door through which a fit, a Monte Carlo
run, the posterior and the live view run a scene.

>>> scene = Scene(load("scenarios/fit/intersection_fit.toml"))             # doctest: +SKIP
>>> speeds = scene.inputs(["vehicles.A.speed", "vehicles.B.speed"])        # doctest: +SKIP
>>> result = speeds.run([13.4, 13.4])                  # the full SceneResult  # doctest: +SKIP
>>> rest = speeds.run([13.4, 12.0], record=lambda r: r.runout["B"].bodies["B"].rest_position)  # doctest: +SKIP

:class:`Scene` takes a :class:`~crashsim.scenario.Scenario` (or the file's contents) with the
run-out engine and the wall-clock limit of a sample; :meth:`Scene.inputs` names the inputs a
sample changes, by their paths in the file (``"vehicles.B.speed"``, ``"impact.restitution"``,
:func:`~crashsim.reconstruct.overrides.resolve_path`), and returns a :class:`SceneInputs`.  Its
:meth:`~SceneInputs.run` takes the SI values, one per path, and returns the whole
:class:`~crashsim.scene.run.SceneResult`, or, with ``record``, only what ``record`` reads of the
lean result (:func:`~crashsim.scene.run.run_scene` ``lean=True``: the same numbers, without what
no record reads).

Per sample a value is applied where it can be by replacing only the objects it reaches
(:mod:`crashsim.reconstruct.variants`), else by the full build from the file's contents, with
the same result and the same errors as the value written in the file
(:class:`~crashsim.reconstruct.overrides.ScenarioOverrides`); the run-out's scene model is kept
by the inputs and reused by every sample that shares its model inputs
(:class:`~crashsim.scene.models.ModelReuse`).
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

from ..scene.models import ModelReuse
from ..scene.run import SceneResult, run_scene
from .overrides import ScenarioOverrides, default_engine, file_contents

__all__ = ["Scene", "SceneInputs"]


class Scene:
    """A scene to run with some of its inputs varied by name.

    Parameters
    ----------
    source : Scenario or dict
        The scenario (:func:`crashsim.load`, :func:`~crashsim.scenario.scenario_from_dict`), or the
        file's contents (a dict, as from TOML; [fit], [uncertainty] and [posterior] are not part of
        the scene).
    engine : {"compiled", "scipy"}, optional
        Run-out engine of every run (default: the compiled one where it is installed).
    file : str, optional
        The file's name, for messages (default: the scenario's path).
    max_wall_time : float, optional
        Wall-clock limit [s] of each run's run-out (``RunoutOptions.max_wall_time``); None: the file's.
    """

    def __init__(self, source, *, engine: str | None = None, file: str | None = None,
                 max_wall_time: float | None = None):
        self.data, self.file = file_contents(source, file)
        self.engine = default_engine() if engine is None else engine
        self.max_wall_time = max_wall_time

    def inputs(self, paths: Sequence[str] = (), *, field: str = "path", cache: int = 8) -> "SceneInputs":
        """The inputs at ``paths`` (checked against the file's schema now: an unknown path, or one the
        file cannot hold, is a ScenarioError naming ``field``); ``cache`` scenarios are kept by their
        values."""
        return SceneInputs(self, paths, field=field, cache=cache)

    def run(self, *, record: Callable[[SceneResult], Any] | None = None):
        """The scene as the file gives it (:meth:`SceneInputs.run` with no inputs varied)."""
        return self.inputs().run((), record=record)


class SceneInputs:
    """Inputs of a :class:`Scene` named by their paths; values in SI, one per path, in their order.

    Attributes
    ----------
    scene : Scene
    paths : tuple of str
    targets : tuple of Target
        Each path resolved against the schema (its field, unit kind and range).
    """

    def __init__(self, scene: Scene, paths: Sequence[str], *, field: str = "path", cache: int = 8):
        self.scene = scene
        self.paths = tuple(paths)
        self._overrides = ScenarioOverrides(scene.data, self.paths, engine=scene.engine, file=scene.file, cache=cache,
                                            field_prefix=field, max_wall_time=scene.max_wall_time)
        self.targets = self._overrides.targets
        self._models = ModelReuse()

    def scenario(self, values: Sequence[float] = ()):
        """The validated :class:`~crashsim.scenario.Scenario` with ``values`` (SI) at the paths.

        Raises
        ------
        ScenarioError
            A value not valid there (out of range, inconsistent with other inputs), exactly as if it
            had been written in the file.
        """
        return self._overrides.scenario(values)

    def base_value(self, i: int) -> float | None:
        """The file's own value of input ``i`` in SI (None where the file does not give it)."""
        return self._overrides.base_value(i)

    def data(self, values: Sequence[float]) -> dict:
        """The file's contents with ``values`` written in (as a file would hold them)."""
        return self._overrides.data(values)

    @property
    def patched(self) -> bool:
        """Whether samples are applied to the first scenario built (the fast path), not built from the file."""
        return self._overrides._variant is not None

    def run(self, values: Sequence[float] = (), *, record: Callable[[SceneResult], Any] | None = None,
            lean: bool | None = None, mark_checks: bool = True):
        """Run the scene with ``values`` (SI) at the paths.

        Parameters
        ----------
        values : sequence of float
        record : callable, optional
            Given the lean result (the numbers a record, a residual or an evidence check reads, without
            the rest), its return value is returned; None: the full :class:`SceneResult`.
        lean : bool, optional
            Override of the result's kind (default: lean with a record, full without).
        mark_checks : bool
            False: no tyre-mark checks in the evidence report (a caller that measures the marks
            itself, as the fit does).

        Raises
        ------
        ScenarioError, SolverError
            As :func:`~crashsim.scene.run.run_scene` and :meth:`scenario` raise them.
        """
        lean = (record is not None) if lean is None else bool(lean)
        result = run_scene(self.scenario(values), lean=lean, models=self._models, mark_checks=mark_checks)
        return result if record is None else record(result)
