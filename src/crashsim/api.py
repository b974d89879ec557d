"""The Python API for scripts and notebooks: load a scenario file, run it, fit it, sample it.

Each function is a thin door to the same code the command line uses (``crashsim run``,
``fit``, ``mc``), so a number computed in a notebook is the number of the report.

>>> import crashsim
>>> scene = crashsim.run("scenarios/scenes/intersection_car_trailer_wheels.toml")  # doctest: +SKIP
>>> scene.impact.bodies["car"].delta_v_magnitude                                   # doctest: +SKIP
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

from .errors import ScenarioError
from .reconstruct import run_scene
from .reconstruct.fit import fit_scene
from .reconstruct.montecarlo import monte_carlo as _mc
from .reconstruct.overrides import parse_value, resolve_path, set_value, set_written
from .reconstruct.posterior import run_posterior
from .scenario import Scenario, load_scenario, scenario_from_dict
from .schema import load_toml

__all__ = ["load", "run", "fit", "monte_carlo", "posterior", "with_overrides"]


def _raw(source) -> tuple[dict, str | None]:
    """The file contents (raw TOML dict) and the file name of a path, a Scenario or a dict.

    A Scenario gives the contents it was built from (:attr:`crashsim.scenario.Scenario.file_data`,
    not read again), else those of its file."""
    if isinstance(source, (str, Path)):
        return load_toml(source), str(source)
    if isinstance(source, Mapping):
        return dict(source), None
    data = getattr(source, "file_data", None)
    if data is not None:
        return data, getattr(source, "path", None)
    path = getattr(source, "path", None)
    if path is None:
        raise ScenarioError(f"cannot read scenario inputs from {type(source).__name__}: give a file path, a dict of "
                            "the file's contents, or a Scenario loaded from a file", field="scenario")
    return load_toml(path), str(path)


def _validated(source, data: dict, file: str | None) -> None:
    """The whole file validated first, as the CLI does (a Scenario built from ``data`` already was)."""
    if not (isinstance(source, Scenario) and source.file_data is data):
        scenario_from_dict(data, file=file)


def with_overrides(data: Mapping, overrides: Mapping[str, Any] | None = None, **kwargs) -> dict:
    """A copy of a scenario's file contents with some inputs replaced.

    Parameters
    ----------
    data : dict
        The file's contents (as read by :func:`crashsim.schema.load_toml`).
    overrides : dict, optional
        ``{path: value}`` with a path as in ``[fit]`` unknowns (``"vehicles.car.speed"``,
        ``"impact.point[0]"``) and the value written as in the file, with its unit
        (``"35 mph"``, ``0.1``).
    **kwargs
        The same with ``__`` for each dot: ``vehicles__car__speed="35 mph"``. Any value of the
        file may be changed: a number with its unit, a choice (``runout__engine="compiled"``), a
        flag, a whole vector (``vehicles__car__position=["1 m", "2 m"]``).

    Raises
    ------
    ScenarioError
        A path the schema does not have, or a value that cannot be read (naming the path).
    """
    items = dict(overrides or {})
    items.update({k.replace("__", "."): v for k, v in kwargs.items()})
    out = dict(data)
    for path, value in items.items():
        target = resolve_path(path, field=path, any_value=True)
        f = target.field
        one_number = (f.is_quantity or f.kind == "float") and not f.points and (f.n is None or target.component is not None)
        if one_number:
            out = set_value(out, target, parse_value(value, target, field=path))
        else:  # a choice, a flag, a vector or points: as written, validated with the scenario
            out = set_written(out, target, value)
    return out


def load(path):
    """Read and validate a scenario file (TOML); returns a :class:`crashsim.scenario.Scenario`.

    Raises :class:`~crashsim.errors.ScenarioError` naming the file, key, value and allowed
    range of anything wrong.
    """
    return load_scenario(path)


def run(scenario, overrides: Mapping[str, Any] | None = None, **kwargs):
    """Solve a scene: the impact, the run-out to rest, the evidence checks.

    Parameters
    ----------
    scenario : str, Path, Scenario or dict
        A scenario file, a scenario from :func:`load`, or a file's contents as a dict.
    overrides, **kwargs
        Inputs to change first (see :func:`with_overrides`), e.g.
        ``crashsim.run("scene.toml", vehicles__car__speed="35 mph")``.

    Returns
    -------
    SceneResult
        With ``.report(units=...)``, ``.to_dict()``, ``.plot(ax=None)``, ``.animate(path)``,
        ``.history(dt)`` (arrays) and ``.history_frame(dt)`` (pandas).
    """
    if isinstance(scenario, Scenario) and not overrides and not kwargs:
        return run_scene(scenario)
    if isinstance(scenario, (str, Path)) and not overrides and not kwargs:
        return run_scene(load(scenario))
    data, file = _raw(scenario)
    return run_scene(scenario_from_dict(with_overrides(data, overrides, **kwargs), file=file))


def fit(scenario, **options):
    """Fit the ``[fit]`` unknowns of a scenario to its evidence (as ``crashsim fit``).

    ``options`` go to :func:`crashsim.reconstruct.fit.fit_scene` (``engine``, ``workers``,
    ``progress``, ``sample_time_limit``). Returns a :class:`~crashsim.reconstruct.fit.FitResult`.
    """
    data, file = _raw(scenario)
    _validated(scenario, data, file)
    return fit_scene(data, None, file=file, **options)


def monte_carlo(scenario, samples: int | None = None, **options):
    """Monte Carlo of the ``[uncertainty]`` inputs through impact and run-out (as ``crashsim mc``).

    ``options`` go to :func:`crashsim.reconstruct.montecarlo.monte_carlo` (``seed``,
    ``engine``, ``workers``, ``out_path``, ``progress``, ...). Returns an
    :class:`~crashsim.reconstruct.montecarlo.MCResult`.
    """
    data, file = _raw(scenario)
    _validated(scenario, data, file)
    options.setdefault("progress", False)
    return _mc(data, None, samples, file=file, **options)


def posterior(scenario, **options):
    """MCMC posterior of the ``[fit]`` unknowns given the evidence (as ``crashsim posterior``).

    ``options`` go to :func:`crashsim.reconstruct.posterior.run_posterior` (``steps``, ``seed``,
    ``start``, ``engine``, ``workers``, ``dask_address``, ``chain_path``, ``progress``, ...).
    Returns a :class:`~crashsim.reconstruct.posterior.PosteriorResult`.
    """
    data, file = _raw(scenario)
    _validated(scenario, data, file)
    options.setdefault("progress", False)
    return run_posterior(data, None, file=file, **options)
