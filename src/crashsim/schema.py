"""A small declarative schema for scenario files: validated and documented by one object.

A schema is a tree of :class:`Section` (a TOML table with fixed keys), :class:`Table`
(a TOML table whose keys are names chosen by the user, each entry validated by the same
section: ``[vehicles.A]``, ``[vehicles.B]``) and :class:`ArrayOf` (a TOML array of tables:
``[[impact.constraints]]``), whose leaves are :class:`Field` s. :func:`validate` checks a
loaded file against it and returns plain dicts of SI floats, strings, booleans and tuples
with defaults filled; :func:`document` prints the same tree as reference text.

Rules of validation
-------------------
* Unknown keys are errors; the nearest valid keys are suggested (difflib).
* A quantity field (``kind`` a :class:`crashsim.units.Kind`) needs its unit written with
  the value (``"30 mph"``) and is returned in SI; its ``minimum``/``maximum`` are SI.
* A missing required key is an error naming its description and an example. An optional
  field that is absent gets its ``default`` (written like a file value, with its unit, and
  read the same way), or ``None`` when it has none.
* An absent optional :class:`Section` is filled with its defaults when it has no required
  key, else it is ``None``; an absent optional :class:`Table` is ``{}`` and an absent
  optional :class:`ArrayOf` is ``[]``.
* Every problem in the file is collected; one :class:`ScenarioValidationError` (a
  :class:`~crashsim.errors.ScenarioError`) lists them all, one per line, the first as its
  main message and its ``field``.

Examples
--------
>>> from crashsim.units import Kind
>>> impact = Section("impact", [
...     Field("restitution", "float", minimum=0, maximum=1, default=0.05,
...           description="Coefficient of restitution e (paper eq. 4)"),
...     Field("speed", Kind.SPEED, minimum=0, description="Closing speed", example="30 mph"),
... ], description="Impact parameters")
>>> root = Section("scenario", subsections=[impact], description="A scenario")
>>> validate({"impact": {"speed": "30 mph"}}, root)
{'impact': {'restitution': 0.05, 'speed': 13.4112}}
"""

from __future__ import annotations

import difflib
import math
import os
import re
import tomllib
from collections.abc import Sequence
from dataclasses import KW_ONLY, dataclass, replace
from typing import Any, Literal, TypeAlias, cast

from crashsim import units
from crashsim.errors import ScenarioError
from crashsim.units import Kind, toml_repr

__all__ = [
    "MISSING",
    "Field",
    "Section",
    "Table",
    "ArrayOf",
    "ScenarioValidationError",
    "validate",
    "validate_collect",
    "load_toml",
    "document",
]


class _Missing:
    def __repr__(self) -> str:
        return "MISSING"


MISSING: Any = _Missing()
"""Marks a :class:`Field` without a default."""

_PLAIN_KINDS = ("str", "bool", "int", "float", "choice")
_TYPE_NAMES = {"str": "string", "bool": "boolean", "int": "integer", "float": "number"}


@dataclass(frozen=True)
class Field:
    """One key of a section.

    Parameters
    ----------
    name
        The TOML key.
    kind
        A quantity kind (:class:`crashsim.units.Kind` or its value, e.g. ``"speed"``): the
        value is a string with its unit, returned in SI. Or one of ``"str"``, ``"bool"``,
        ``"int"``, ``"float"`` (a plain number), ``"choice"``. ``None`` means ``"choice"``
        and then needs ``choices``.
    description
        What the value is, for error messages and documentation (required).
    required
        Whether the key must be present. Defaults to ``True`` unless a ``default`` is given.
    default
        Value used when the key is absent, written as in a file (``"0 deg"``).
    minimum, maximum
        Allowed range, in SI for quantities; inclusive unless ``exclusive_minimum`` /
        ``exclusive_maximum``. For a vector, applied to every component.
    choices
        Allowed strings of a ``"choice"`` field.
    n
        For a vector of quantities (or of plain numbers): the number of components; the
        value is then a list such as ``["1 m", "2 m"]``, returned as a tuple.
    counts
        For a list of quantities whose length may vary (``n`` not given): the allowed numbers
        of values, e.g. ``(2, 4, 6)``; returned as a tuple.
    example
        An example value as written in a file, for messages and documentation.
    required_if
        ``(key, values)``: the field is required when the sibling ``key`` of the same table has
        one of ``values`` (e.g. ``("state", ("rolling", "braked"))``); validated and documented
        ("required if state = 'rolling' or 'braked'").
    unless
        Sibling keys any one of which stands in for this field when ``required_if`` holds
        (``cornering_stiffness`` for ``cornering_coefficient``).
    """

    name: str
    kind: Kind | str | None = None
    _: KW_ONLY
    description: str
    required: bool | None = None
    default: Any = MISSING
    minimum: float | None = None
    maximum: float | None = None
    exclusive_minimum: bool = False
    exclusive_maximum: bool = False
    choices: tuple[str, ...] = ()
    n: int | None = None
    points: bool = False
    min_points: int = 1
    example: str | None = None
    counts: tuple[int, ...] = ()
    required_if: tuple[str, tuple[str, ...]] | None = None
    unless: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        where = f"Field {self.name!r}"
        kind: Kind | str | None = self.kind
        if kind is None:
            if not self.choices:
                raise TypeError(f"{where}: give kind= (a units Kind or one of "
                                f"{', '.join(_PLAIN_KINDS)}) or choices=")
            kind = "choice"
        elif kind not in _PLAIN_KINDS:
            try:
                kind = Kind(kind)
            except ValueError:
                raise TypeError(f"{where}: unknown kind {kind!r}; use a units Kind or one of "
                                f"{', '.join(_PLAIN_KINDS)}") from None
        object.__setattr__(self, "kind", kind)
        object.__setattr__(self, "choices", tuple(self.choices))
        if not self.description.strip():
            raise TypeError(f"{where}: a description is required")
        if self.required is None:
            object.__setattr__(self, "required", self.default is MISSING)
        elif self.required and self.default is not MISSING:
            raise TypeError(f"{where}: a required field cannot have a default")
        if (kind == "choice") != bool(self.choices):
            raise TypeError(f"{where}: choices= goes with kind='choice' and only with it")
        numeric = isinstance(kind, Kind) or kind in ("int", "float")
        if not numeric and (self.minimum is not None or self.maximum is not None):
            raise TypeError(f"{where}: minimum/maximum need a numeric or quantity kind")
        if self.n is not None and not (isinstance(kind, Kind) or kind == "float"):
            raise TypeError(f"{where}: n= (a vector) needs a quantity kind or 'float'")
        if self.points and self.n is None:
            raise TypeError(f"{where}: points=True (a list of points) needs n= (components per point)")
        if self.required_if is not None:
            key, values = self.required_if
            if self.required or self.default is not MISSING:
                raise TypeError(f"{where}: required_if= goes with an optional field without a default")
            object.__setattr__(self, "required_if", (str(key), tuple(values)))
        object.__setattr__(self, "unless", tuple(self.unless))
        if self.unless and self.required_if is None:
            raise TypeError(f"{where}: unless= (keys that stand in for this one) goes with required_if=")
        object.__setattr__(self, "counts", tuple(self.counts))
        if self.counts and (self.n is not None or self.points or not isinstance(kind, Kind)):
            raise TypeError(f"{where}: counts= (a list of varying length) needs a quantity kind, without n= or points=")

    @property
    def is_quantity(self) -> bool:
        """Whether the value carries a unit (``kind`` is a :class:`~crashsim.units.Kind`)."""
        return isinstance(self.kind, Kind)


@dataclass(frozen=True)
class Section:
    """A TOML table with a fixed set of keys.

    Parameters
    ----------
    name
        The TOML key of the table (ignored for the root section of a schema).
    fields
        Its keys holding values.
    subsections
        Its keys holding tables: :class:`Section`, :class:`Table` or :class:`ArrayOf`.
    description
        What the table describes, for messages and documentation.
    required
        Whether the table must be present (see the module notes for absent optional ones).
    """

    name: str
    fields: Sequence[Field] = ()
    subsections: Sequence[Node] = ()
    _: KW_ONLY
    description: str
    required: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "fields", tuple(self.fields))
        object.__setattr__(self, "subsections", tuple(self.subsections))
        names = [f.name for f in self.fields] + [s.name for s in self.subsections]
        repeated = sorted({n for n in names if names.count(n) > 1})
        if repeated:
            raise TypeError(f"Section {self.name!r}: repeated keys {repeated}")

    @property
    def keys(self) -> tuple[str, ...]:
        """The valid keys, in schema order."""
        return tuple(f.name for f in self.fields) + tuple(s.name for s in self.subsections)


@dataclass(frozen=True)
class Table:
    """A TOML table whose keys are names chosen by the user, each entry a :class:`Section`.

    ``Table("vehicles", vehicle)`` validates ``[vehicles.A]``, ``[vehicles.B]``, ... each
    against ``vehicle``; the result maps each name to its validated entry.
    """

    name: str
    entry: Section
    _: KW_ONLY
    description: str = ""
    required: bool = True
    min_entries: int = 0
    placeholder: str = "<name>"


@dataclass(frozen=True)
class ArrayOf:
    """A TOML array of tables (``[[impact.constraints]]``), each validated by ``entry``."""

    name: str
    entry: Section
    _: KW_ONLY
    description: str = ""
    required: bool = True
    min_items: int = 0
    max_items: int | None = None


Node: TypeAlias = Section | Table | ArrayOf


class ScenarioValidationError(ScenarioError):
    """Every problem :func:`validate` found in one scenario.

    Attributes
    ----------
    problems
        ``(dotted key path, message)`` for each problem, in the order found; the first is
        the main message and ``field``.
    """

    def __init__(self, problems: Sequence[tuple[str, str]], *, file: str | None = None):
        self.problems = tuple(problems)
        (field, message), rest = self.problems[0], self.problems[1:]
        if rest:
            message += f"\n{len(rest)} more problem{'s' if len(rest) > 1 else ''}:"
            message += "".join(f"\n  {path}: {text}" for path, text in rest)
        super().__init__(message, field=field, file=file)


# ----------------------------------------------------------------------------- validation

_Problems = list[tuple[str, str]]


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def _num(x: float) -> str:
    return format(x, ".12g")


def interval_text(f: Field, like: object = None) -> str:
    """The allowed range of a numeric field as text, e.g. ``"[0, 1]"`` or ``"(0, inf) m/s"`` (SI bounds,
    brackets closed or open as the field says); used in error messages here and by the inverse sections.
    ``like``: a value as the file writes it (``"3000 lb"``); where its unit is not the SI one, the range
    follows in that unit too (``"(0, inf) kg = (0, inf) lb"``), so the message speaks the file's units."""
    lo = "-inf" if f.minimum is None else _num(f.minimum)
    hi = "inf" if f.maximum is None else _num(f.maximum)
    left = "(" if f.exclusive_minimum or f.minimum is None else "["
    right = ")" if f.exclusive_maximum or f.maximum is None else "]"
    si = units.si_unit(f.kind) if f.is_quantity else ""
    out = f"{left}{lo}, {hi}{right}{' ' + si if si else ''}"
    if not si or not isinstance(like, str):
        return out
    try:
        per_si, unit = units.number_and_unit(units.write_like(1.0, f.kind, like))
    except (TypeError, ValueError):
        return out
    if not unit or unit == si or not per_si:
        return out
    lo2 = "-inf" if f.minimum is None else format(f.minimum * per_si, ".6g")
    hi2 = "inf" if f.maximum is None else format(f.maximum * per_si, ".6g")
    return f"{out} = {left}{lo2}, {hi2}{right} {unit}"


def in_range(x: float, f: Field) -> bool:
    """Whether the SI value ``x`` lies in the field's range (its minimum/maximum, open or closed)."""
    if f.minimum is not None and (x < f.minimum or (f.exclusive_minimum and x == f.minimum)):
        return False
    return f.maximum is None or not (x > f.maximum or (f.exclusive_maximum and x == f.maximum))


def _example(f: Field) -> str | None:
    """An example of the field's value as TOML text (quoted where TOML needs quotes)."""
    quoted = f.n is None and not f.counts and (f.is_quantity or f.kind in ("str", "choice"))
    if f.example is not None:
        return f'"{f.example}"' if quoted else f.example
    if isinstance(f.kind, Kind):
        one = f'"{units.example(f.kind)}"'
        return one if f.n is None else "[" + ", ".join([one] * f.n) + "]"
    return f'"{f.choices[0]}"' if f.choices else None


def _short_type(f: Field) -> str:
    if isinstance(f.kind, Kind):
        unit = units.si_unit(f.kind)
        text = f.kind.value.replace("_", " ") + (f" [{unit}]" if unit else " number")
    elif f.kind == "choice":
        text = "one of " + ", ".join(f"'{c}'" for c in f.choices)
    else:
        text = _TYPE_NAMES[str(f.kind)]
    if f.points:
        return f"list of points, each {f.n} x {text}"
    if f.counts:
        return f"list of {_counts(f)} x {text}"
    return f"list of {f.n} x {text}" if f.n else text


def _counts(f: Field) -> str:
    """The allowed list lengths of a ``counts`` field in words: "2, 4 or 6"."""
    c = [str(k) for k in f.counts]
    return c[0] if len(c) == 1 else ", ".join(c[:-1]) + " or " + c[-1]


def _number(value: object, path: str, integer: bool, problems: _Problems) -> float | None:
    if integer and (isinstance(value, bool) or not isinstance(value, int)):
        problems.append((path, f"{toml_repr(value)} is not an integer"))
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        problems.append((path, f"{toml_repr(value)} is not a number; write a plain number "
                               "such as 0.6 (no quotes, no unit)"))
        return None
    if not math.isfinite(value):
        problems.append((path, f"{toml_repr(value)} is not a finite number"))
        return None
    return value if integer else float(value)


def _interval_in(f: Field, unit: str) -> str | None:
    """The allowed range of ``f`` in the unit the user wrote (None if that unit is the SI one)."""
    if not unit or unit == units.si_unit(f.kind):
        return None
    try:
        lo = None if f.minimum is None else units.convert(f.minimum, units.si_unit(f.kind), unit, f.kind)
        hi = None if f.maximum is None else units.convert(f.maximum, units.si_unit(f.kind), unit, f.kind)
    except ScenarioError:
        return None
    left = "(" if f.exclusive_minimum or lo is None else "["
    right = ")" if f.exclusive_maximum or hi is None else "]"
    return f"{left}{'-inf' if lo is None else format(lo, '.4g')}, {'inf' if hi is None else format(hi, '.4g')}{right} {unit}"


def _check_range(x: float, raw: object, f: Field, path: str, problems: _Problems) -> None:
    if in_range(x, f):
        return
    shown = toml_repr(raw)
    allowed = interval_text(f)
    if f.is_quantity and isinstance(raw, str):
        si = f"{_num(x)} {units.si_unit(f.kind)}".strip()
        match = units._NUMBER.fullmatch(raw)
        own = _interval_in(f, match.group("unit")) if match else None
        if own:  # the range in the user's unit first, then in SI
            allowed = f"{own} ({allowed})"
        elif raw.strip() != si:
            shown += f" (= {si})"
    problems.append((path, f"{shown} is out of range; allowed {allowed}"))


def _field(value: object, f: Field, path: str, problems: _Problems) -> Any:
    if f.points:
        if not isinstance(value, list) or len(value) < f.min_points:
            problems.append((path, f"{toml_repr(value)} is not a list of at least {f.min_points} points, "
                                   f"each a list of {f.n} values such as {_example(f) or '[...]'}"))
            return None
        item = replace(f, points=False, example=None)
        got = [_field(v, item, f"{path}[{i}]", problems) for i, v in enumerate(value)]
        return None if any(g is None for g in got) else tuple(got)
    kind = f.kind
    if f.counts:
        if 1 in f.counts and isinstance(value, (str, int, float)) and not isinstance(value, bool):
            value = [value]  # one value where a list of one is allowed: "80 kN" for ["80 kN"]
        if not isinstance(value, list) or len(value) not in f.counts:
            what = f"has {len(value)} values" if isinstance(value, list) else "is not a list"
            problems.append((path, f"{toml_repr(value)} {what}; allowed a list of {_counts(f)} values such as "
                                   f"{_example(f) or '[...]'}"))
            return None
        try:
            got = units.parse_vector(value, kind, None, field=path)
        except ScenarioError as exc:
            problems.append((exc.field or path, str(exc).removeprefix(f"{exc.field}: ")))
            return None
        for i, (x, raw) in enumerate(zip(got, value)):
            _check_range(x, raw, f, f"{path}[{i}]", problems)
        return got
    if isinstance(kind, Kind):
        try:
            if f.n is not None:
                got = units.parse_vector(value, kind, f.n, field=path)
                for i, (x, raw) in enumerate(zip(got, cast(Sequence[object], value))):
                    _check_range(x, raw, f, f"{path}[{i}]", problems)
                return got
            x = units.parse(value, kind, field=path)
        except ScenarioError as exc:
            problems.append((exc.field or path, str(exc).removeprefix(f"{exc.field}: ")))
            return None
        _check_range(x, value, f, path, problems)
        return x
    if kind in ("int", "float"):
        if f.n is not None:
            if not isinstance(value, list) or len(value) != f.n:
                problems.append((path, f"{toml_repr(value)} is not a list of {f.n} numbers"))
                return None
            items = [_field(v, _scalar(f), f"{path}[{i}]", problems) for i, v in enumerate(value)]
            return tuple(items)
        number = _number(value, path, kind == "int", problems)
        if number is not None:
            _check_range(number, value, f, path, problems)
        return number
    if kind == "bool":
        if not isinstance(value, bool):
            problems.append((path, f"{toml_repr(value)} is not a boolean; write true or false"))
            return None
        return value
    if not isinstance(value, str):
        problems.append((path, f"{toml_repr(value)} is not a string; write it in quotes"))
        return None
    if kind == "choice" and value not in f.choices:
        close = difflib.get_close_matches(value, f.choices, n=1)
        hint = f"did you mean '{close[0]}'? " if close else ""
        allowed = ", ".join(f"'{c}'" for c in f.choices)
        problems.append((path, f"{toml_repr(value)} is not a valid choice; {hint}"
                               f"allowed: {allowed}"))
    return value


def _scalar(f: Field) -> Field:
    """The same field without its vector length (for one component)."""
    return Field(f.name, f.kind, description=f.description, minimum=f.minimum,
                 maximum=f.maximum, exclusive_minimum=f.exclusive_minimum,
                 exclusive_maximum=f.exclusive_maximum)


def _default(f: Field, path: str) -> Any:
    if f.default is MISSING or f.default is None:
        return None
    problems: _Problems = []
    value = _field(f.default, f, path, problems)
    if problems:  # a bug in the schema, not in the user's file
        raise ValueError(f"schema default of {path} is invalid: {problems[0][1]}")
    return value


def _has_required(section: Section) -> bool:
    return any(f.required for f in section.fields) or any(
        s.required and (not isinstance(s, Section) or _has_required(s))
        for s in section.subsections)


def _absent(node: Node, path: str, problems: _Problems) -> Any:
    if node.required:
        if isinstance(node, Section):
            what, header = "table", f"[{path}]"
        elif isinstance(node, Table):
            what, header = "table of named entries", f"[{path}.{node.placeholder}]"
        else:
            what, header = "array of tables", f"[[{path}]]"
        problems.append((path, f"missing required {what} {header}: {_description(node)}"))
        return None
    if isinstance(node, Table):
        return {}
    if isinstance(node, ArrayOf):
        return []
    return None if _has_required(node) else _section({}, node, path, problems)


def _description(node: Node) -> str:
    if isinstance(node, Section):
        return node.description
    return node.description or node.entry.description


def _node(value: object, node: Node, path: str, problems: _Problems) -> Any:
    if isinstance(node, Section):
        return _section(value, node, path, problems)
    if isinstance(node, Table):
        if not isinstance(value, dict):
            problems.append((path, f"{toml_repr(value)} is not a table; write [{path}.<name>]"))
            return None
        if len(value) < node.min_entries:
            problems.append((path, f"{len(value)} entries; at least {node.min_entries} "
                                   f"required, each as [{path}.{node.placeholder}]"))
        return {key: _section(v, node.entry, _join(path, key), problems)
                for key, v in value.items()}
    if not isinstance(value, list):
        problems.append((path, f"{toml_repr(value)} is not an array of tables; "
                               f"write [[{path}]]"))
        return None
    if len(value) < node.min_items or (node.max_items is not None
                                       and len(value) > node.max_items):
        hi = "inf" if node.max_items is None else node.max_items
        problems.append((path, f"{len(value)} items; allowed {node.min_items} to {hi}"))
    return [_section(v, node.entry, f"{path}[{i}]", problems) for i, v in enumerate(value)]


def _section(data: object, section: Section, path: str, problems: _Problems) -> Any:
    if not isinstance(data, dict):
        problems.append((path, f"{toml_repr(data)} is not a table; "
                               f"write [{path}] and its keys"))
        return None
    valid = section.keys
    for key in data:
        if key not in valid:
            close = difflib.get_close_matches(key, valid, n=3)
            hint = f"did you mean {' or '.join(map(repr, close))}? Valid keys" if close else (
                "valid keys")
            problems.append((_join(path, key),
                             f"unknown key; {hint}: {', '.join(valid) or '(none)'}"))
    out: dict[str, Any] = {}
    for f in section.fields:
        key = _join(path, f.name)
        if f.name in data:
            before = len(problems)
            out[f.name] = _field(data[f.name], f, key, problems)
            if len(problems) > before:  # refused (out of range, bad unit, ...): no value for the later checks
                out[f.name] = None
        elif f.required:
            example = _example(f)
            hint = f"; e.g. {f.name} = {example}" if example else ""
            problems.append((key, f"missing required key: {f.description} "
                                  f"({_short_type(f)}){hint}"))
        elif f.required_if is not None and data.get(f.required_if[0]) in f.required_if[1] and not any(
                k in data for k in f.unless):
            example = _example(f)
            hint = f"; e.g. {f.name} = {example}" if example else ""
            instead = f" (or {' or '.join(f.unless)})" if f.unless else ""
            problems.append((key, f"missing key{instead}, required with {f.required_if[0]} = "
                                  f"{toml_repr(data[f.required_if[0]])}: {f.description} ({_short_type(f)}){hint}"))
            out[f.name] = None
        else:
            out[f.name] = _default(f, key)
    for sub in section.subsections:
        key = _join(path, sub.name)
        out[sub.name] = (_node(data[sub.name], sub, key, problems) if sub.name in data
                         else _absent(sub, key, problems))
    return out


def validate(data: dict[str, Any], schema: Section, *, file: str | None = None) -> dict[str, Any]:
    """Check ``data`` (a loaded TOML document) against ``schema`` and convert it to SI.

    Parameters
    ----------
    data
        The document, e.g. from :func:`load_toml`.
    schema
        The root section; its own ``name`` is not part of the key paths.
    file
        Name of the file ``data`` came from, for error messages.

    Returns
    -------
    dict
        Nested plain dicts (lists for :class:`ArrayOf`) in schema order: quantities as SI
        floats, vectors as tuples, defaults filled, absent optional values ``None``.

    Raises
    ------
    ScenarioValidationError
        Listing every problem (unknown key with suggestions, missing key, wrong unit or
        type, out of range, bad choice), each with its dotted key path and value.
    """
    result, problems = validate_collect(data, schema)
    if problems:
        raise ScenarioValidationError(problems, file=file)
    return result  # type: ignore[no-any-return]


def validate_collect(data: dict[str, Any], schema: Section) -> tuple[Any, list[tuple[str, str]]]:
    """:func:`validate` without raising: the converted document and every problem found.

    Returns
    -------
    (dict, list of (str, str))
        The document as :func:`validate` returns it, with ``None`` where a value (or a whole
        table) was bad, and the problems as ``(key path, message)`` pairs; an empty list for a
        valid document. The loader uses it to go on checking the parts that are valid, so
        that the errors found after the schema come in the same run as the schema's.
    """
    problems: _Problems = []
    result = _section(data, schema, "", problems)
    return result, problems


# ------------------------------------------------------------------------------- TOML input

_WHERE = re.compile(r"\s*\(at line (\d+), column (\d+)\)\s*$")


def load_toml(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read a TOML file; a syntax error becomes a :class:`ScenarioError` with line and column.

    Raises
    ------
    ScenarioError
        If the file cannot be read, is not UTF-8 or is not valid TOML (the message names
        the line and column, ``file`` the path).
    """
    name = os.fspath(path)
    try:
        with open(name, "rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        text = str(exc)
        where = _WHERE.search(text)
        at = f"line {where[1]}, column {where[2]}" if where else "the end of the file"
        reason = _WHERE.sub("", text).replace(" (at end of document)", "")
        raise ScenarioError(f"invalid TOML at {at}: {reason}", file=name) from None
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"not UTF-8 text (byte {exc.start})", file=name) from None
    except OSError as exc:
        raise ScenarioError(f"cannot read the file: {exc.strerror}", file=name) from None


# ---------------------------------------------------------------------------- documentation

def _type_text(f: Field) -> str:
    if not isinstance(f.kind, Kind):
        return _short_type(f)
    text = units.describe(f.kind)
    if f.points:
        return f"list of >= {f.min_points} points, each a list of {f.n} x {text}"
    if f.counts:
        return f"list of {_counts(f)} x {text}"
    return f"list of {f.n} x {text}" if f.n else text


def _field_row(f: Field, path: str) -> tuple[str, str, str, str, str]:
    """(key path, type, required/default, allowed range, description) of one field."""
    if f.required:
        need = "required"
    elif f.required_if is not None:
        values = " or ".join(f"'{v}'" for v in f.required_if[1])
        instead = f" (or {' or '.join(f.unless)})" if f.unless else ""
        need = f"required if {f.required_if[0]} = {values}{instead}"
    elif f.default is MISSING or f.default is None:
        need = "optional"
    else:
        need = f"optional, default {toml_repr(f.default)}"
    ranged = f.minimum is not None or f.maximum is not None
    allowed = interval_text(f) if ranged else ""
    desc = f.description + (f" (example: {_example(f)})" if f.example is not None else "")
    return _join(path, f.name), _type_text(f), need, allowed, desc


def _walk(section: Section, header: str, path: str, desc: str, required: bool
          ) -> list[tuple[str, str, bool, list[tuple[str, str, str, str, str]]]]:
    """(TOML header, description, required, field rows) for a section and those below it."""
    rows = [_field_row(f, path) for f in section.fields]
    out = [(header, desc, required, rows)] if rows or not section.subsections else []
    for sub in section.subsections:
        sub_path = _join(path, sub.name)
        if isinstance(sub, Section):
            out += _walk(sub, f"[{sub_path}]", sub_path, sub.description, sub.required)
        elif isinstance(sub, Table):
            entry_path = _join(sub_path, sub.placeholder)
            out += _walk(sub.entry, f"[{entry_path}]", entry_path, _description(sub),
                         sub.required)
        else:
            out += _walk(sub.entry, f"[[{sub_path}]]", f"{sub_path}[]", _description(sub),
                         sub.required)
    return out


def document(schema: Section, fmt: Literal["text", "markdown"] = "text") -> str:
    """Reference documentation of ``schema``, generated from the objects that validate.

    Lists every key path with its type (unit kind with SI unit, accepted units and an
    example), whether it is required or its default, its allowed range or choices and
    its description.

    Parameters
    ----------
    schema
        The root section.
    fmt
        ``"text"`` (plain, indented) or ``"markdown"`` (a heading and a table per section).
    """
    if fmt not in ("text", "markdown"):
        raise ValueError(f"unknown format {fmt!r}; use 'text' or 'markdown'")
    lines: list[str] = []
    if fmt == "markdown":
        lines += [f"# {schema.description}", ""]
    else:
        lines += [schema.description, "=" * len(schema.description), ""]
    for header, desc, required, rows in _walk(schema, "(top level)", "", "", True):
        note = "" if required else " (optional)"
        if fmt == "markdown":
            lines += [f"## `{header}`{note}", ""] + ([desc, ""] if desc else [])
            if rows:
                lines += ["| Key | Type | Required | Allowed | Description |",
                          "|---|---|---|---|---|"]
                for key, *cells in rows:
                    cells = [c.replace("|", "\\|") for c in cells]
                    lines.append(f"| `{key}` | " + " | ".join(cells) + " |")
                lines.append("")
        else:
            lines += [f"{header}{note}"] + ([f"  {desc}"] if desc else [])
            for key, type_text, need, allowed, text in rows:
                lines += [f"  {key}", f"      {type_text}", f"      {need}"]
                lines += [f"      allowed {allowed}"] if allowed else []
                lines += [f"      {text}"]
            lines.append("")
    return "\n".join(lines).rstrip() + "\n"
