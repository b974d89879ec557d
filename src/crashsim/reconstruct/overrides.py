"""Inputs addressed by their path in the scenario file, overridden on the raw file dict.

A fit's unknowns and a Monte Carlo run's uncertain inputs name scenario inputs by the
dotted path of the file (``"vehicles.B.speed"``, ``"vehicles.A.bodies[1].mass"``,
``"impact.point[0]"``, ``"runout.road_friction"``). A value is set by writing it into the
*raw* file dict, as a file value with its unit (``"13.41 m/s"``), and the whole dict goes
through :func:`crashsim.scenario.scenario_from_dict`: every override is validated and
converted exactly like a value read from the file, so there is one path from the file to
the physics.

Per evaluation cost
-------------------
The presets are merged once (:class:`ScenarioOverrides` keeps the merged dict, without the
``preset`` keys, so :func:`scenario_from_dict` does not read the preset library again);
only the dicts and lists along the overridden paths are copied. The first scenario is
validated and built the full way (about 1.5-3 ms for the shipped scenes). After it, the
common paths (vehicle speeds, restitution, the tangential law's coefficient, the crush
normal and point of impact, the road friction) are patched into it: only the objects a
value reaches are rebuilt, the rest keep their identity (:mod:`crashsim.reconstruct.patch`,
about a third of the cost; the same scenario value for value, tested against the full
build). Any other path, and any value the fast path cannot vouch for, takes the full build
(``benchmarks/fit_mc.py`` measures both).

Path grammar
------------
``key(.key)*`` where a key may carry an index, ``name[i]``: into an array of tables
(``bodies[1]``, ``wheels[0]``, ``zones[0]``) or into a vector value (``point[0]``,
``position[1]``). The path must end at one number: a quantity (with a unit in the file) or
a plain number. The entry names of a table of named entries (``vehicles.<name>``) are the
names used in the file.
"""

from __future__ import annotations

import copy
import difflib
import math
import re
from collections import OrderedDict
from dataclasses import dataclass, replace
from typing import Any, Mapping, Sequence

from ..errors import ScenarioError
from ..scenario import SCHEMA, apply_presets, scenario_from_dict
from ..schema import ArrayOf, Field, Section, Table
from ..survey.mapping import expand_survey
from ..units import Kind
from .values import format_value, parse_value
from .variants import ScenarioVariant

__all__ = ["Target", "resolve_path", "parse_value", "format_value", "set_value", "get_value",
           "ScenarioOverrides", "INVERSE_SECTIONS", "file_contents"]

#: Top-level sections of a file that belong to the inverse side and not to the forward model;
#: they are removed before the forward scenario is built.
INVERSE_SECTIONS = ("fit", "uncertainty", "posterior")

#: Default of ``ScenarioOverrides(fast=...)``: False builds every scenario of a fit or Monte Carlo
#: run the full way (the reference the fast path is tested and benchmarked against).
FAST = True

_TOKEN = re.compile(r"^(?P<name>[A-Za-z_][A-Za-z0-9_\-]*)(?:\[(?P<index>\d+)\])?$")


@dataclass(frozen=True)
class Target:
    """One scalar input of a scenario file, addressed by its path.

    Attributes
    ----------
    path : str
        As written (``"vehicles.A.bodies[1].mass"``).
    steps : tuple
        ``(key, index or None)`` per dotted part.
    field : Field
        The schema field the path ends at (its unit kind, range and description).
    component : int or None
        Index into a vector field (``point[0]``), else None.
    """

    path: str
    steps: tuple
    field: Field
    component: int | None
    entries: tuple = ()  # indices of the steps that name an entry of a table of named entries

    @property
    def kind(self) -> str:
        """Unit kind of the value (``"speed"``, ``"angle"``, ...; ``"dimensionless"`` for a plain number)."""
        return self.field.kind.value if isinstance(self.field.kind, Kind) else Kind.DIMENSIONLESS.value

    @property
    def label(self) -> str:
        return self.path


def _close(word: str, options) -> str:
    near = difflib.get_close_matches(word, list(options), n=2)
    return f"; did you mean {' or '.join(map(repr, near))}?" if near else ""


def resolve_path(path: str, schema: Section | None = None, *, field: str = "path", any_value: bool = False) -> Target:
    """Check ``path`` against the scenario schema and return its :class:`Target`.

    Parameters
    ----------
    path : str
        Dotted path with optional indices, see the module notes.
    schema : Section, optional
        Root schema (default :data:`crashsim.scenario.SCHEMA`).
    field : str
        Where the path was written (``"fit.unknowns[0].path"``), for error messages.
    any_value : bool
        Any value of the file may be named (a choice, a flag, a whole vector or list of points:
        :func:`crashsim.run` changes any input); else only one number (an unknown of a fit or
        an uncertain input).

    Raises
    ------
    ScenarioError
        Unknown key (with the nearest valid ones), a missing or superfluous index, or a path
        that does not end at one number.
    """
    if schema is None:
        schema = SCHEMA
    if not isinstance(path, str) or not path.strip():
        raise ScenarioError(f"{path!r} is not a path such as \"vehicles.B.speed\"", field=field)
    parts = path.strip().split(".")
    steps = []
    entries: list[int] = []
    node: Any = schema
    for k, part in enumerate(parts):
        m = _TOKEN.match(part)
        if m is None:
            raise ScenarioError(f"{path!r}: {part!r} is not a key or key[index]", field=field)
        name, index = m["name"], (None if m["index"] is None else int(m["index"]))
        last = k == len(parts) - 1
        if isinstance(node, Table):  # a user-chosen entry name
            entries.append(len(steps))
            if index is not None:
                raise ScenarioError(f"{path!r}: {name!r} names an entry of [{node.name}]; it takes no index",
                                    field=field)
            steps.append((name, None))
            node = node.entry
            if last:
                raise ScenarioError(f"{path!r} ends at a table; name one of its numbers, e.g. {path}.{node.keys[0]}",
                                    field=field)
            continue
        if not isinstance(node, Section):  # pragma: no cover - guarded below
            raise ScenarioError(f"{path!r}: cannot descend into {part!r}", field=field)
        fields = {f.name: f for f in node.fields}
        subs = {s.name: s for s in node.subsections}
        if name in fields:
            f = fields[name]
            if not last:
                raise ScenarioError(f"{path!r}: {name!r} is a value, not a table", field=field)
            if any_value and (index is None or (f.n is not None and not f.points)):
                if index is not None and index >= f.n:
                    raise ScenarioError(f"{path!r}: index {index} out of range; {name!r} has {f.n} components",
                                        field=field)
                if index is not None or f.n is not None or f.points or not (f.is_quantity or f.kind == "float"):
                    steps.append((name, index))
                    return Target(path.strip(), tuple(steps), f, index, tuple(entries))
            if not (f.is_quantity or f.kind == "float"):
                raise ScenarioError(f"{path!r} is a {f.kind} value, not a number; only numbers (quantities or "
                                    "plain numbers) can be fitted or sampled", field=field)
            if f.points:
                raise ScenarioError(f"{path!r} is a list of points; it cannot be an unknown", field=field)
            if f.n is not None and index is None:
                raise ScenarioError(f"{path!r} is a vector of {f.n} values; name one component, e.g. "
                                    f"{path}[0] and {path}[1]", field=field)
            if f.n is None and index is not None:
                raise ScenarioError(f"{path!r}: {name!r} is a single value; remove [{index}]", field=field)
            if index is not None and index >= f.n:
                raise ScenarioError(f"{path!r}: index {index} out of range; {name!r} has {f.n} components",
                                    field=field)
            steps.append((name, index))
            return Target(path.strip(), tuple(steps), f, index, tuple(entries))
        if name in subs:
            sub = subs[name]
            if isinstance(sub, ArrayOf):
                if index is None:
                    raise ScenarioError(f"{path!r}: {name!r} is an array of tables; give the item, e.g. {name}[0]",
                                        field=field)
                steps.append((name, index))
                node = sub.entry
            else:
                if index is not None:
                    raise ScenarioError(f"{path!r}: {name!r} is a table; it takes no index", field=field)
                steps.append((name, None))
                node = sub
            if last:
                raise ScenarioError(f"{path!r} ends at a table; name one of its values", field=field)
            continue
        raise ScenarioError(f"{path!r}: unknown key {name!r}{_close(name, node.keys)} "
                            f"Valid keys here: {', '.join(node.keys)}", field=field)
    raise ScenarioError(f"{path!r} does not end at a value", field=field)  # pragma: no cover


def _container(data: dict, target: Target, *, create: bool, copy_path: bool):
    """The dict holding the target's key (copied along the way when ``copy_path``)."""
    node = data
    for depth, (key, index) in enumerate(target.steps[:-1]):
        where = ".".join(k if i is None else f"{k}[{i}]" for k, i in target.steps[:depth + 1])
        if not isinstance(node, dict):
            raise ScenarioError(f"{where} is not a table in the scenario", field=target.path)
        nxt = node.get(key)
        if nxt is None and depth in target.entries:
            table = ".".join(k for k, _ in target.steps[:depth]) or "the file"
            names = [str(k) for k in node]
            raise ScenarioError(f"{target.path!r} names {key!r}, but the scenario has no entry {key!r} in [{table}]"
                                f"{_close(key, names)} Entries: {', '.join(map(repr, names)) or 'none'}",
                                field=target.path)
        if nxt is None:
            if not create or index is not None:
                raise ScenarioError(f"the scenario has no {where}; {target.path!r} cannot be set", field=target.path)
            nxt = {}
            node[key] = nxt
        if index is not None:
            if not isinstance(nxt, list) or index >= len(nxt):
                n = len(nxt) if isinstance(nxt, list) else 0
                raise ScenarioError(f"the scenario has {n} item(s) in {where.rsplit('[', 1)[0]}; "
                                    f"{target.path!r} names item {index}", field=target.path)
            if copy_path:
                nxt = list(nxt)
                node[key] = nxt
            item = nxt[index]
            if copy_path:
                item = dict(item) if isinstance(item, dict) else item
                nxt[index] = item
            node = item
        else:
            if copy_path and isinstance(nxt, dict):
                nxt = dict(nxt)
                node[key] = nxt
            node = nxt
    if not isinstance(node, dict):
        raise ScenarioError(f"{target.path!r}: its parent is not a table in the scenario", field=target.path)
    return node


def get_value(data: dict, target: Target) -> Any:
    """The raw value at ``target`` as written in the file (None if absent)."""
    try:
        node = _container(data, target, create=False, copy_path=False)
    except ScenarioError:
        return None
    key, index = target.steps[-1]
    v = node.get(key)
    if v is None or index is None:
        return v
    return v[index] if isinstance(v, (list, tuple)) and index < len(v) else None


def set_value(data: dict, target: Target, x: float, *, copy_path: bool = True, like: bool = False) -> dict:
    """Write SI value ``x`` at ``target`` into the raw dict ``data`` (as a file value with its unit).

    With ``copy_path`` (default) ``data`` is not changed: the dicts and lists along the path
    are copied (the rest is shared) and the new top-level dict is returned. With ``like`` the
    value is written in the unit of the value it replaces (SI where there is none).
    """
    old = get_value(data, target) if like else None
    return _write(data, target, format_value(x, target, old), copy_path)


def set_written(data: dict, target: Target, value: Any) -> dict:
    """Write ``value`` as written in a file (``"compiled"``, ``["1 m", "2 m"]``, ``"35 mph"``) at
    ``target`` into a copy of the raw dict ``data``; it is validated when the scenario is built."""
    return _write(data, target, value, True)


def _write(data: dict, target: Target, value: Any, copy_path: bool) -> dict:
    """Put ``value`` at ``target`` (a vector's component where the target names one)."""
    out = dict(data) if copy_path else data
    node = _container(out, target, create=True, copy_path=copy_path)
    key, index = target.steps[-1]
    if index is None:
        node[key] = value
    else:
        vec = node.get(key)
        if not isinstance(vec, (list, tuple)) or len(vec) != target.field.n:
            raise ScenarioError(f"the scenario has no vector {target.path.rsplit('[', 1)[0]} of "
                                f"{target.field.n} values to set component {index} of", field=target.path)
        vec = list(vec)
        vec[index] = value
        node[key] = vec
    return out


def forward_data(data: dict, *, file: str | None = None) -> dict:
    """The forward part of a raw scenario dict: without [fit]/[uncertainty], presets merged.

    The ``preset`` keys are dropped after merging (their values are in the body now), so
    building a scenario from the result does not read the preset library again.
    """
    base = {k: v for k, v in data.items() if k not in INVERSE_SECTIONS}
    merged = apply_presets(base, file)
    if merged is base:
        merged = copy.deepcopy(base)
    for v in (merged.get("vehicles") or {}).values():
        if isinstance(v, dict) and isinstance(v.get("bodies"), list):
            v["bodies"] = [{k: x for k, x in b.items() if k != "preset"} if isinstance(b, dict) else b
                           for b in v["bodies"]]
    return merged


def _engine_options(options, engine: str | None):
    """RunoutOptions with ``engine`` set (None: as they are)."""
    return options if engine is None else replace(options, engine=engine)


def file_contents(source, file: str | None = None) -> tuple[dict, str | None]:
    """The raw file contents a fit, Monte Carlo or posterior run varies, and the file name.

    ``source``: the file's contents (a dict, as from TOML), or a
    :class:`~crashsim.scenario.Scenario` built from them (its
    :attr:`~crashsim.scenario.Scenario.file_data`; the file name its ``path`` unless ``file``
    is given).
    """
    if isinstance(source, Mapping):
        return source, file
    data = getattr(source, "file_data", None)
    if data is None:
        raise ScenarioError(f"cannot vary the inputs of {type(source).__name__}: give the file's contents (a dict) "
                            "or a Scenario built from them (crashsim.load, scenario_from_dict)", field="scenario")
    return data, getattr(source, "path", None) if file is None else file


def default_engine() -> str:
    """The run-out engine of fit, Monte Carlo, posterior and live view samples: the compiled one (numba is
    a dependency, its kernels part of the package)."""
    return "compiled"


class ScenarioOverrides:
    """Build scenarios from one raw file dict with some inputs replaced.

    Parameters
    ----------
    data : dict
        The raw scenario (as from TOML); [fit] and [uncertainty] are ignored here.
    paths : sequence of str
        The inputs to override, in the order of the value vectors given to :meth:`scenario`.
    engine : str or None
        Run-out engine to set in every scenario's RunoutOptions (None: the file's).
    file : str, optional
        For error messages.
    cache : int
        Number of recent scenarios kept (keyed by the value vector).
    max_wall_time : float, optional
        Wall-clock limit [s] of each run-out (``RunoutOptions.max_wall_time``); None: the file's.
    fast : bool, optional
        Default :data:`FAST`. Build the scenarios of the common paths (speeds, impact coefficients, point of impact,
        road friction) from the first one built, changing only the objects each value reaches
        (:mod:`crashsim.reconstruct.patch`: the same scenario, value for value); other paths and
        invalid values go through the full build. False: every scenario the full way.

    Examples
    --------
    >>> ov = ScenarioOverrides(raw, ["vehicles.B.speed"])           # doctest: +SKIP
    >>> sc = ov.scenario([15.0])    # B at 15 m/s, validated like "15.0 m/s" in the file  # doctest: +SKIP
    """

    def __init__(self, data: dict, paths: Sequence[str], *, engine: str | None = None, file: str | None = None,
                 cache: int = 8, field_prefix: str = "path", max_wall_time: float | None = None,
                 fast: bool | None = None):
        self.file = file
        self.fast = FAST if fast is None else bool(fast)
        self._fast_base = None  # the first scenario built the full way (the base of the fast path)
        self._variant = None  # ScenarioVariant of the base and the paths, when they can be patched
        self.engine = engine
        self.max_wall_time = max_wall_time

        data = expand_survey(data, file)  # a [survey] read here once: the samples rebuild from its items
        self.base = forward_data(data, file=file)
        self.targets = tuple(resolve_path(p, SCHEMA, field=f"{field_prefix}[{i}]" if len(paths) > 1 else field_prefix)
                             for i, p in enumerate(paths))
        seen = {}
        for i, t in enumerate(self.targets):
            if t.path in seen:
                raise ScenarioError(f"{t.path!r} is named twice (items {seen[t.path]} and {i})", field=field_prefix)
            seen[t.path] = i
        for i, t in enumerate(self.targets):  # fails early, with the path, if the file cannot hold it
            try:
                _container(copy.deepcopy(self.base), t, create=True, copy_path=False)
            except ScenarioError as exc:
                where = f"{field_prefix}[{i}]" if len(self.targets) > 1 else field_prefix
                msg = str(exc).removeprefix(f"{exc.field}: ") if exc.field else str(exc)
                raise ScenarioError(msg, field=where, file=file) from None
        self._cache: OrderedDict = OrderedDict()
        self._cache_size = int(cache)

    def data(self, values: Sequence[float]) -> dict:
        """The raw forward dict with ``values`` (SI, one per path) written in."""
        if len(values) != len(self.targets):
            raise ValueError(f"expected {len(self.targets)} values, got {len(values)}")
        out = self.base
        for t, x in zip(self.targets, values):
            if not math.isfinite(float(x)):
                raise ScenarioError(f"{float(x)!r} is not a finite number", field=t.path)
            out = set_value(out, t, float(x))
        return out

    def base_value(self, i: int) -> float | None:
        """The file's own value of input ``i`` in SI (None if the file does not give it)."""
        t = self.targets[i]
        raw = get_value(self.base, t)
        if raw is None:
            return None
        return parse_value(raw, t, field=t.path)

    def scenario(self, values: Sequence[float] = ()):
        """A validated :class:`~crashsim.scenario.Scenario` with ``values`` (SI) at the paths.

        Raises
        ------
        ScenarioError
            If a value is not valid there (out of range, inconsistent with other inputs),
            exactly as if it had been written in the file.
        """
        key = tuple(float(v) for v in values)
        hit = self._cache.get(key)
        if hit is not None:
            self._cache.move_to_end(key)
            return hit
        sc = None
        if self._variant is not None:
            sc = self._variant.scenario(key)
        if sc is None:
            sc = scenario_from_dict(self.data(key), file=self.file)  # approaches: in the run
            if sc.runout is not None and (self.engine is not None or self.max_wall_time is not None):
                options = _engine_options(sc.runout.options, self.engine)
                if self.max_wall_time is not None:
                    options = replace(options, max_wall_time=float(self.max_wall_time))
                sc = replace(sc, runout=replace(sc.runout, options=options))
            if self.fast and self._fast_base is None:
                self._fast_base = sc
                self._variant = ScenarioVariant(sc, self.targets, self.file)
                if not self._variant.patchable:
                    self._variant = None
        self._cache[key] = sc
        while len(self._cache) > self._cache_size:
            self._cache.popitem(last=False)
        return sc
