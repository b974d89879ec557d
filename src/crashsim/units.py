"""Units at the edge: the only module of crashsim that knows mph, ft, lbf and deg.

Everything inside crashsim is SI (m, kg, s, N, rad). Values written by people, in
scenario files or on the command line, are strings carrying their unit (``"30 mph"``,
``"20945 lbf"``, ``"75 deg"``); :func:`parse` turns one into an SI float, once, at the
boundary. :func:`to_unit` goes the other way for reports, in SI or US customary units,
from the single display table :data:`DISPLAY_UNITS`.

Conventions (decided here, and only here)
-----------------------------------------
* **Standard gravity** ``G0 = 9.80665 m/s^2`` exactly: the "standard acceleration of
  gravity" declared by the 3rd CGPM (1901) and listed in NIST SP 811 (2008), Appendix B;
  the value pint uses in ``lbf`` and ``kgf``.
* **lb is a mass.** ``lb``/``pound`` is the avoirdupois pound, 0.45359237 kg exactly.
* **A weight is accepted for a mass.** A force given for a :attr:`Kind.MASS`
  (``"20945 lbf"``, ``"93.2 kN"``) is a weight and is converted to mass by dividing by
  ``G0``. Since ``1 lbf = 1 lb * G0``, ``"W lbf"`` and ``"W lb"`` give the same mass.
* **lb for lbf in US practice.** Where reading ``lb`` as a mass gives the wrong dimension
  and reading it as ``lbf`` gives the expected one, ``lbf`` is meant: ``"90639 lb-s"`` is
  an impulse in lbf s, ``"1.95e6 ft-lb"`` an energy in ft lbf, ``"15489 ft-lb-s^2"`` a yaw
  inertia in lbf ft s^2 (= slug ft^2), ``"8143 lb"`` a force in lbf, ``"285.5 lb/in"`` a
  CRASH3 stiffness A in lbf/in and ``"87 lb/in^2"`` a stiffness B in lbf/in^2. Where the literal
  reading already fits it wins (``"lb ft^2"`` is a yaw inertia in pound-mass ft^2).
* **g is standard gravity for an acceleration.** A unit written exactly ``g`` for an
  :attr:`Kind.ACCELERATION` means ``G0`` (``"0.7 g"``); anywhere else pint's ``g`` (gram).
* **Angles are checked.** pint treats radians as dimensionless; here an angle unit counts
  as a dimension of its own, so ``"75"`` or ``"75 %"`` is not an angle, ``"10 Hz"`` is not
  an angular velocity and ``"5 m deg"`` is not a length.
* **Spelling.** A hyphen between unit names is a product (``"N-s"``, ``"kg-m^2"``,
  ``"ft-lb-s^2"``); ``²``/``³`` are powers; ``·`` is a product.
* **Dimensionless** values are plain numbers (``0.6``, ``"0.6"``) or percentages
  (``"5 %"`` -> 0.05).

pint is imported on first use (:func:`registry`), so ``import crashsim.units`` is cheap;
unit expressions are parsed once and cached, and the documented spellings are read from a shipped
table of pint's factors (:func:`factor_table`) without importing pint at all.

Examples
--------
>>> parse("30 mph", Kind.SPEED, field="vehicles.A.speed")
13.4112
>>> round(parse("20945 lbf", "mass", field="vehicles.A.mass"), 3)  # a weight, as mass
9500.492
>>> to_unit(13.4112, Kind.SPEED, "US")
(30.0, 'mph')
"""

from __future__ import annotations

import difflib
import enum
import functools
import json
import math
import os
import re
import threading
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

from crashsim.errors import ScenarioError

if TYPE_CHECKING:  # pragma: no cover
    import pint

__all__ = ["G0", "Kind", "System", "DisplaySystem", "SPEED_UNITS", "speed_unit_of", "system_label", "DISPLAY_UNITS",
           "registry", "parse", "parse_vector", "to_unit", "write_like", "convert", "describe", "example", "si_unit",
           "resolve_system", "toml_repr", "factor_table"]

G0: float = 9.80665
"""Standard acceleration of gravity [m/s^2], exact by definition (3rd CGPM, 1901)."""

System = Literal["SI", "US"]

#: Units a speed of an SI output may be shown in (``[scenario] speed_unit``); US outputs show mph.
SPEED_UNITS = ("m/s", "km/h", "mph")


class DisplaySystem(str):
    """A unit system (``"SI"`` or ``"US"``; equal to, and usable as, that string) whose SI outputs
    show speeds in ``speed_unit`` (one of :data:`SPEED_UNITS`) instead of m/s.

    :func:`to_unit` (and so every report, table and figure) reads ``speed_unit`` off the system it is
    given; :func:`resolve_system` keeps it when a system is chosen by name over a scenario's
    (``--units SI`` on a file with ``speed_unit = "km/h"``: km/h). A US system shows mph whatever
    ``speed_unit`` says.

    Examples
    --------
    >>> si = DisplaySystem("SI", "km/h")
    >>> si == "SI", format_value(13.4112, Kind.SPEED, si), format_value(5.0, Kind.LENGTH, si)
    (True, '48.28 km/h', '5 m')
    """

    speed_unit: str | None

    def __new__(cls, system: str, speed_unit: str | None = None):
        if system not in ("SI", "US"):
            raise ValueError(f"unknown unit system {system!r}; use 'SI' or 'US'")
        if speed_unit is not None and speed_unit not in SPEED_UNITS:
            raise ValueError(f"unknown speed unit {speed_unit!r}; allowed {', '.join(SPEED_UNITS)}")
        self = super().__new__(cls, system)
        self.speed_unit = speed_unit
        return self

    def __getnewargs__(self):  # pickled whole (worker processes)
        return str(self), self.speed_unit

    def __repr__(self) -> str:
        return f"DisplaySystem({str(self)!r}, {self.speed_unit!r})"


def system_label(system) -> str:
    """How a report names its unit system: ``"SI"``, ``"US"``, ``"SI, speeds in km/h"``."""
    speed = speed_unit_of(system)
    return str(system) if speed == DISPLAY_UNITS[Kind.SPEED][str(system)] else f"{system}, speeds in {speed}"


def speed_unit_of(system) -> str:
    """The speed unit of a system's outputs: ``speed_unit`` of an SI :class:`DisplaySystem`, else the
    system's own (m/s, mph)."""
    own = getattr(system, "speed_unit", None)
    return own if own is not None and system == "SI" else DISPLAY_UNITS[Kind.SPEED][str(system)]


class Kind(str, enum.Enum):
    """Physical kind of a quantity; each has one SI unit, used everywhere inside crashsim."""

    LENGTH = "length"
    SPEED = "speed"
    MASS = "mass"
    YAW_INERTIA = "yaw_inertia"
    ANGLE = "angle"
    ANGULAR_VELOCITY = "angular_velocity"
    TIME = "time"
    FORCE = "force"
    IMPULSE = "impulse"
    MOMENT_IMPULSE = "moment_impulse"
    ACCELERATION = "acceleration"
    ENERGY = "energy"
    FORCE_PER_LENGTH = "force_per_length"
    FORCE_PER_AREA = "force_per_area"
    DIMENSIONLESS = "dimensionless"
    SLOPE = "slope"
    CORNERING_STIFFNESS = "cornering_stiffness"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class _Spec:
    noun: str  # "a speed"
    expect: str  # accepted units, for messages and documentation
    examples: tuple[str, str]  # two example values
    spellings: tuple[str, ...]  # unit spellings offered as "did you mean"
    angle_power: int = 0  # power of the angle pseudo-dimension


_SPECS: dict[Kind, _Spec] = {
    Kind.LENGTH: _Spec("a length", "m, mm, km, ft, in, yd, mi", ("12.5 m", "41 ft"),
                       ("m", "mm", "cm", "km", "ft", "in", "yd", "mi")),
    Kind.SPEED: _Spec("a speed", "m/s, km/h, mph, ft/s", ("30 mph", "13.41 m/s"),
                      ("m/s", "km/h", "kph", "mph", "ft/s", "fps")),
    Kind.MASS: _Spec("a mass", "kg, t, lb, slug (= lbf s^2/ft, lb-s^2/ft); or a weight in N, kN, lbf, kip",
                     ("9500 kg", "20945 lbf"),
                     ("kg", "t", "lb", "lbs", "slug", "lb-s^2/ft", "N", "kN", "lbf", "kip")),
    Kind.YAW_INERTIA: _Spec("a yaw inertia", "kg m^2, slug ft^2, lbf ft s^2 (ft-lb-s^2)",
                            ("21000 kg m^2", "15489 ft-lb-s^2"),
                            ("kg m^2", "kg*m^2", "slug ft^2", "lbf ft s^2", "ft-lb-s^2")),
    Kind.ANGLE: _Spec("an angle", "deg, rad", ("75 deg", "1.309 rad"),
                      ("deg", "rad", "degree", "radian"), angle_power=1),
    Kind.ANGULAR_VELOCITY: _Spec("an angular velocity", "deg/s, rad/s, rpm",
                                 ("10.3 deg/s", "0.18 rad/s"), ("deg/s", "rad/s", "rpm"),
                                 angle_power=1),
    Kind.TIME: _Spec("a time", "s, ms, min, h", ("0.15 s", "150 ms"), ("s", "ms", "min", "h")),
    Kind.FORCE: _Spec("a force", "N, kN, lbf, kip", ("36222 N", "8143 lbf"),
                      ("N", "kN", "lbf", "kip")),
    Kind.IMPULSE: _Spec("an impulse", "N s, kN s, lbf s (lb-s)",
                        ("403164 N s", "90639 lb-s"), ("N s", "N*s", "kN s", "lbf s", "lb-s")),
    Kind.MOMENT_IMPULSE: _Spec("a moment impulse", "N m s, lbf ft s (ft-lb-s)",
                               ("1200 N m s", "885 ft-lb-s"), ("N m s", "lbf ft s", "ft-lb-s")),
    Kind.ACCELERATION: _Spec("an acceleration", "m/s^2, ft/s^2, g (standard gravity)",
                             ("9.81 m/s^2", "0.7 g"), ("m/s^2", "ft/s^2", "g")),
    Kind.ENERGY: _Spec("an energy", "J, kJ, N m, ft lbf (ft-lb)",
                       ("2.65e6 J", "1.95e6 ft-lb"), ("J", "kJ", "MJ", "N m", "ft lbf", "ft-lb")),
    Kind.FORCE_PER_LENGTH: _Spec("a force per length", "N/m, kN/m, lbf/in (lb/in: the pound-force of CRASH3 practice)",
                                 ("50000 N/m", "285.5 lb/in"), ("N/m", "kN/m", "lbf/in", "lb/in")),
    Kind.FORCE_PER_AREA: _Spec("a force per area", "N/m^2, kN/m^2, MN/m^2, lbf/in^2 (lb/in^2: pound-force)",
                               ("600000 N/m^2", "87.0 lb/in^2"), ("N/m^2", "kN/m^2", "MN/m^2", "lbf/in^2", "lb/in^2")),
    Kind.DIMENSIONLESS: _Spec("a plain number", "a number, or a percentage", ("0.6", "5 %"),
                              ("%",)),
    Kind.CORNERING_STIFFNESS: _Spec("a cornering stiffness",
                                    "force per angle of slip: N/rad, kN/rad, N/deg, lbf/deg; or a force, read per radian",
                                    ("40000 N/rad", "155 lbf/deg"), ("N/rad", "kN/rad", "N/deg", "lbf/deg", "lbf/rad"),
                                    angle_power=-1),
    Kind.SLOPE: _Spec("a slope", "rise over run as a number or a percentage, or the angle of the surface (deg, rad)",
                      ("-6 %", "-3.43 deg"), ("%", "deg", "rad")),
}

DISPLAY_UNITS: dict[Kind, dict[str, str]] = {
    Kind.LENGTH: {"SI": "m", "US": "ft"},
    Kind.SPEED: {"SI": "m/s", "US": "mph"},
    Kind.MASS: {"SI": "kg", "US": "lb"},  # lb (mass) is numerically the weight in lbf
    Kind.YAW_INERTIA: {"SI": "kg m^2", "US": "lbf ft s^2"},
    Kind.ANGLE: {"SI": "rad", "US": "deg"},
    Kind.ANGULAR_VELOCITY: {"SI": "rad/s", "US": "deg/s"},
    Kind.TIME: {"SI": "s", "US": "s"},
    Kind.FORCE: {"SI": "N", "US": "lbf"},
    Kind.IMPULSE: {"SI": "N s", "US": "lbf s"},
    Kind.MOMENT_IMPULSE: {"SI": "N m s", "US": "lbf ft s"},
    Kind.ACCELERATION: {"SI": "m/s^2", "US": "ft/s^2"},
    Kind.ENERGY: {"SI": "J", "US": "ft lbf"},
    Kind.FORCE_PER_LENGTH: {"SI": "N/m", "US": "lbf/in"},
    Kind.FORCE_PER_AREA: {"SI": "N/m^2", "US": "lbf/in^2"},
    Kind.DIMENSIONLESS: {"SI": "", "US": ""},
    Kind.SLOPE: {"SI": "", "US": ""},
    Kind.CORNERING_STIFFNESS: {"SI": "N/rad", "US": "lbf/deg"},
}
"""Display unit of each kind in each system: the one table behind :func:`to_unit`.

Every label is also accepted by :func:`parse`, so ``f"{value!r} {label}"`` reads back."""

#: Kinds written as plain numbers (or percentages): no SI unit label.
_PLAIN = frozenset({Kind.DIMENSIONLESS, Kind.SLOPE})

# Aliases defined in the registry if this pint version lacks them.
_ALIASES = (("kph", "kilometer_per_hour"), ("fps", "foot_per_second"),
            ("lbs", "pound"), ("rev", "revolution"))
_ANGLE_ALIASES = ("rad", "deg", "arcmin", "arcsec", "turn", "rpm", "grad")

_registry: pint.UnitRegistry | None = None
_angle_names: frozenset[str] = frozenset()
_lock = threading.Lock()


def registry() -> pint.UnitRegistry:
    """Return crashsim's single pint registry, creating it (and importing pint) on first use."""
    global _registry, _angle_names
    if _registry is None:
        with _lock:
            if _registry is None:
                import pint

                ureg = pint.UnitRegistry()
                for alias, target in _ALIASES:
                    if alias not in ureg:
                        ureg.define(f"@alias {target} = {alias}")
                _angle_names = frozenset(ureg.get_name(a) for a in _ANGLE_ALIASES)
                _registry = ureg
    return _registry


class _Invalid(Exception):
    """A value cannot be read; the message says why (without the field name)."""


_NUMBER = re.compile(
    r"\s*(?P<num>[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|(?:inf(?:inity)?|nan)\b))"
    r"\s*(?P<unit>.*?)\s*",
    re.IGNORECASE,
)
_HYPHEN = re.compile(r"(?<=[A-Za-z_²³)])-(?=[A-Za-z(])")
_POUND = re.compile(r"\b(?:lb|lbs|pound|pounds)\b")


def _kind(kind: Kind | str) -> Kind:
    try:
        return Kind(kind)
    except ValueError:
        raise ValueError(f"unknown quantity kind {kind!r}; use one of {', '.join(k.value for k in Kind)}") from None


def toml_repr(value: object) -> str:
    """A value as written in TOML (``"30 mph"``, ``true``, ``["1 m", "2 m"]``), for messages."""
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_repr(v) for v in value) + "]"
    if isinstance(value, dict):
        return "a table"
    return repr(value)


def _type_noun(value: object) -> str:
    """How a TOML user would call the type of ``value``."""
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, (list, tuple)):
        return "a list"
    return f"a {type(value).__name__}"


def _such_as(spec: _Spec) -> str:
    return f'write {spec.noun} such as "{spec.examples[0]}" or "{spec.examples[1]}"'


def _pint_unit(text: str) -> pint.Unit:
    """Parse a normalised unit expression; raise _Invalid on unknown or malformed units."""
    ureg = registry()
    import pint

    try:
        return ureg.parse_units(text)
    except pint.UndefinedUnitError as exc:
        names = exc.unit_names if isinstance(exc.unit_names, str) else ", ".join(exc.unit_names)
        raise _Invalid(f"has an unknown unit '{names}'") from None
    except Exception:  # pint's parser raises assorted types for malformed input
        raise _Invalid(f"has a malformed unit '{text}'") from None


def _angle_power(unit: pint.Unit) -> float:
    """Power of the angle pseudo-dimension in ``unit`` (pint keeps angles dimensionless)."""
    return sum(p for name, p in unit._units.items() if name in _angle_names)


def _dims_noun(unit: pint.Unit) -> str:
    """What a unit measures, in words (``"a mass"``), for error messages."""
    power = _angle_power(unit)
    for kind, spec in _SPECS.items():
        if kind not in _PLAIN and power == spec.angle_power:
            if unit.dimensionality == registry().parse_units(si_unit(kind)).dimensionality:
                return spec.noun
    if power == 0 and unit.dimensionless:
        return _SPECS[Kind.DIMENSIONLESS].noun
    if power == 0 and unit.dimensionality == registry().parse_units("1/s").dimensionality:
        return "a frequency (no angle unit)"
    if power == 0:
        for si, noun in (("W", "a power"), ("Pa", "a pressure"), ("m^2", "an area"), ("m^3", "a volume"),
                         ("kg/m^3", "a density"), ("A", "an electric current"), ("K", "a temperature")):
            if unit.dimensionality == registry().parse_units(si).dimensionality:
                return noun
    angle = "" if not power else " * [angle]" if power == 1 else f" * [angle] ** {power:g}"
    return f"of dimension {unit.dimensionality}{angle}"


@functools.cache
def _factors() -> dict[str, float]:
    """The shipped table (``data/unit_factors.json``, :func:`factor_table`), read once, found beside this module."""
    with open(os.path.join(os.path.dirname(__file__), "data", "unit_factors.json"), encoding="utf-8") as fh:
        return json.load(fh)


def _shipped_factor(unit: str, kind: Kind) -> float | None:
    """The shipped SI factor of ``unit`` read as ``kind`` (None if the table does not hold it)."""
    return _factors().get(f"{kind.value}|{unit}")


def factor_table() -> dict[str, float]:
    """Pint's SI factor (``"kind|unit"``) of every documented spelling and display label of every kind,
    and of the US survey foot: shipped as ``data/unit_factors.json`` (``benchmarks/unit_factors.py``),
    so that a file in those units is read without importing pint (0.5 s of CPU)."""
    pairs = [(k, sp) for k, spec in _SPECS.items() if k not in _PLAIN for sp in spec.spellings]
    pairs += [(k, label) for k, labels in DISPLAY_UNITS.items() if k not in _PLAIN for label in labels.values()]
    pairs += [(Kind.SPEED, sp) for sp in SPEED_UNITS] + [(Kind.LENGTH, "survey_foot")]
    return dict(sorted({f"{kind.value}|{unit}": _pint_factor(unit, kind) for kind, unit in pairs}.items()))


@functools.lru_cache(maxsize=4096)
def _si_factor(unit: str, kind: Kind) -> float:
    """SI value of one ``unit`` read as ``kind``; raise _Invalid with the reason if impossible."""
    shipped = _shipped_factor(unit, kind)
    return _pint_factor(unit, kind) if shipped is None else shipped


def _pint_factor(unit: str, kind: Kind) -> float:
    """:func:`_si_factor` computed by pint."""
    spec = _SPECS[kind]
    text = _HYPHEN.sub("*", unit.strip().replace("·", "*"))
    if kind is Kind.ACCELERATION and text in ("g", "G"):
        text = "standard_gravity"
    ureg = registry()
    si = ureg.parse_units(si_unit(kind))

    def fits(u: pint.Unit) -> bool:
        return u.dimensionality == si.dimensionality and _angle_power(u) == spec.angle_power

    try:
        literal = _pint_unit(text)
    except _Invalid:
        literal = None
    if literal is None or not fits(literal):  # "Mph", "DEG": a symbol whose case carries no meaning
        same = [sp for sp in spec.spellings if sp in _CASELESS and sp.lower() == text.lower()]
        if same:
            literal = _pint_unit(_HYPHEN.sub("*", same[0]))
    if literal is None:
        literal = _pint_unit(text)  # raises: the unknown unit named
    if fits(literal):
        return float(ureg.Quantity(1.0, literal).to(si).magnitude)
    newton = ureg.parse_units("N")
    if (kind is Kind.CORNERING_STIFFNESS and literal.dimensionality == newton.dimensionality
            and _angle_power(literal) == 0):
        return float(ureg.Quantity(1.0, literal).to(newton).magnitude)  # a force, read per radian
    if kind is Kind.MASS and literal.dimensionality == newton.dimensionality:
        return float(ureg.Quantity(1.0, literal).to(newton).magnitude) / G0  # weight
    if _POUND.search(text):
        as_force = _pint_unit(_POUND.sub("lbf", text))
        if fits(as_force):
            return float(ureg.Quantity(1.0, as_force).to(si).magnitude)
    noun = _dims_noun(literal)
    if re.fullmatch(r"[A-Za-z]+", unit.strip()) and _suggest(unit, spec):  # a typo that is another unit
        # ("mhp": milli-horsepower): say how it was read
        name = str(literal).replace("_", " ")
        raise _Invalid(f"reads {unit.strip()!r} as {name}, {noun.removeprefix('of dimension ')}, not {spec.noun}")
    raise _Invalid(f"is {noun}")


#: Unit spellings whose case carries no meaning (accepted as "MPH", "Mph", "Deg"); SI symbols are
#: not among them, since their case does ("mm" and "Mm", "t" and "T", "s" and "S").
_CASELESS = frozenset({"mph", "kph", "fps", "ft/s", "deg", "degree", "rad", "radian", "rpm", "deg/s", "rad/s",
                       "ft", "in", "yd", "mi", "lb", "lbs", "lbf", "kip", "slug", "lb-s^2/ft", "slug ft^2",
                       "lbf ft s^2", "ft-lb-s^2", "lbf s", "lb-s", "lbf ft s", "ft-lb-s", "ft/s^2", "ft lbf", "ft-lb",
                       "lbf/in", "lb/in", "lbf/in^2", "lb/in^2", "min"})


#: Characters that look like a minus sign but are not the ASCII hyphen-minus (pasted from a word
#: processor or a PDF), with their Unicode names.
_LOOKALIKE_MINUS = {"\u2212": "minus sign", "\u2013": "en dash", "\u2014": "em dash", "\u2010": "hyphen",
                    "\u2011": "non-breaking hyphen", "\u2012": "figure dash", "\ufe63": "small hyphen-minus",
                    "\uff0d": "fullwidth hyphen-minus"}


def _case_hint(unit: str, spec: _Spec) -> str:
    """A unit that differs from one of the expected spellings only in case ("T" for "t"): say what the
    symbol is (SI symbols keep their case: "T is tesla; a tonne is t")."""
    same = [sp for sp in spec.spellings if sp.lower() == unit.strip().lower() and sp != unit.strip()]
    if not same:
        return ""
    try:
        name = str(_pint_unit(unit.strip())).replace("_", " ")
    except _Invalid:
        return f"; did you mean '{same[0]}'? (SI symbols keep their case)"
    return f"; {unit.strip()} is the {name} (SI symbols keep their case): did you mean '{same[0]}'?"


def _suggest(unit: str, spec: _Spec) -> str:
    close = difflib.get_close_matches(unit, spec.spellings, n=1, cutoff=0.6)
    return f"; did you mean '{close[0]}'?" if close else ""


def _to_si(value: object, kind: Kind) -> float:
    """Read one value as ``kind`` and return it in SI; raise _Invalid naming the value."""
    spec = _SPECS[kind]
    shown = toml_repr(value)
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise _Invalid(f"{shown} is {_type_noun(value)}, not {spec.noun}; {_such_as(spec)}")
    if isinstance(value, (int, float)):
        number, unit = float(value), None
    else:
        match = _NUMBER.fullmatch(value)
        if not value.strip():
            raise _Invalid(f"{shown} is empty; {_such_as(spec)}")
        if match is None:
            odd = next((c for c in value if c in _LOOKALIKE_MINUS), None)
            if odd is not None:
                raise _Invalid(f"{shown} contains the character U+{ord(odd):04X} ({_LOOKALIKE_MINUS[odd]}) where a "
                               f"minus is meant; write the ASCII hyphen-minus '-' ({_such_as(spec)})")
            raise _Invalid(f"{shown} is not a number followed by a unit; {_such_as(spec)}")
        number, unit = float(match["num"]), match["unit"]
    if not math.isfinite(number):
        raise _Invalid(f"{shown} is not a finite number")
    if kind is Kind.SLOPE and unit and unit not in ("%", "percent"):
        try:
            angle = number * _si_factor(unit, Kind.ANGLE)
        except _Invalid:
            angle = None
        if angle is not None:
            if not abs(angle) < 0.5 * math.pi:
                raise _Invalid(f"{shown} is not the angle of a road surface: it must lie strictly between -90 and 90 deg")
            return math.tan(angle)  # rise over run of a surface at that angle
    if kind in _PLAIN:
        if not unit:
            return number
        if unit in ("%", "percent"):
            return number / 100.0
        try:
            what = f"is {_dims_noun(_pint_unit(_HYPHEN.sub('*', unit)))}"
        except _Invalid as exc:
            what = str(exc)
        if kind is Kind.SLOPE:
            raise _Invalid(f'{shown} {what}; expected a slope such as "-6 %", "-0.06" or "-3.43 deg"')
        raise _Invalid(f'{shown} {what}; expected a plain number such as "0.6" or "5 %"')
    if not unit:
        raise _Invalid(f"{shown} has no unit; {_such_as(spec)}")
    try:
        factor = _si_factor(unit, kind)
    except _Invalid as exc:
        raise _Invalid(f"{shown} {exc}; expected {spec.noun} ({spec.expect})"
                       f"{_suggest(unit, spec) or _case_hint(unit, spec)}") from None
    result = number * factor
    if not math.isfinite(result):
        raise _Invalid(f"{shown} is too large: not a finite number in SI")
    return result


def parse(value: str | int | float, kind: Kind | str, *, field: str,
          file: str | None = None) -> float:
    """Read one value with its unit and return it in the SI unit of ``kind``.

    Parameters
    ----------
    value
        A number followed by its unit, e.g. ``"30 mph"``, ``"-3260 N s"``, ``"2.5e3 N*s"``,
        ``"20945 lbf"`` (a weight, accepted for a mass). For :attr:`Kind.DIMENSIONLESS`
        also an ``int``/``float``, a bare number string or a percentage (``"5 %"``).
    kind
        The physical kind expected (:class:`Kind` or its string value).
    field
        Dotted path of the value (``"vehicles.A.speed"``), used in error messages.
    file
        File the value came from, if any, used in error messages.

    Returns
    -------
    float
        The value in the SI unit of ``kind`` (see :func:`si_unit`).

    Raises
    ------
    ScenarioError
        If the value has no unit where one is needed, has an unknown unit or the wrong
        dimension, is malformed or is not finite. The message names the value and what
        is expected.

    Examples
    --------
    >>> parse("75 deg", "angle", field="impact.angle")  # doctest: +ELLIPSIS
    1.308996938995...
    >>> parse("30", "speed", field="vehicles.A.speed")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    crashsim.errors.ScenarioError: vehicles.A.speed: "30" has no unit; write a speed such as ...
    """
    try:
        return _to_si(value, _kind(kind))
    except _Invalid as exc:
        raise ScenarioError(str(exc), field=field, file=file) from None


def parse_vector(value: Sequence[str | int | float], kind: Kind | str, n: int | None = 2, *,
                 field: str, file: str | None = None) -> tuple[float, ...]:
    """Read a list of values, each with its own unit, e.g. ``["1 m", "2 ft"]``.

    Parameters
    ----------
    value
        A list (or tuple) of values as accepted by :func:`parse`.
    kind
        The physical kind of every component.
    n
        Required number of components, or ``None`` for any length.
    field, file
        As for :func:`parse`; a component's error names ``field[i]``.

    Returns
    -------
    tuple of float
        The components in SI.

    Raises
    ------
    ScenarioError
        If ``value`` is not a list of length ``n`` or a component is invalid.
    """
    kind = _kind(kind)
    spec = _SPECS[kind]
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence):
        raise ScenarioError(
            f'{toml_repr(value)} is not a list; write {n or "several"} values each with its unit, '
            f'e.g. ["{spec.examples[0]}", "{spec.examples[1]}"]', field=field, file=file)
    if n is not None and len(value) != n:
        count = f"{len(value)} component{'' if len(value) == 1 else 's'}"
        raise ScenarioError(f"{toml_repr(value)} has {count}; expected {n}",
                            field=field, file=file)
    return tuple(parse(v, kind, field=f"{field}[{i}]", file=file) for i, v in enumerate(value))


def resolve_system(value: object, default: str = "SI", *, field: str = "units") -> System:
    """A unit system written by a user (``"SI"``, ``"us"``, any case; None: ``default``).

    A ``default`` that is a :class:`DisplaySystem` (a scenario's ``units`` with its ``speed_unit``)
    lends its speed unit to the system chosen (shown in SI outputs only).

    Raises
    ------
    ScenarioError
        Naming ``field`` and the value, for anything but SI or US.
    """
    value = default if value is None else value
    if isinstance(value, DisplaySystem):
        return value  # type: ignore[return-value]
    if not isinstance(value, str) or value.strip().upper() not in ("SI", "US"):
        raise ScenarioError(f"unknown unit system {value!r}; allowed \"SI\" or \"US\" (any case)", field=field)
    name = value.strip().upper()
    speed = getattr(default, "speed_unit", None)  # the scenario's speed unit of SI outputs, kept
    return DisplaySystem(name, speed) if speed is not None else name  # type: ignore[return-value]


def number_and_unit(text: object) -> tuple[float, str] | None:
    """A value as a file writes it split into its number and its unit text (``"30 mph"`` ->
    ``(30.0, "mph")``, ``"0.05"`` -> ``(0.05, "")``); None for anything that is not a number with an
    optional unit (a plain number in a file is a float, not text: None)."""
    m = _NUMBER.fullmatch(text) if isinstance(text, str) else None
    return (float(m["num"]), m["unit"]) if m is not None else None


def si_unit(kind: Kind | str) -> str:
    """SI unit label of ``kind`` (``"m/s"`` for a speed, ``""`` for dimensionless)."""
    return DISPLAY_UNITS[_kind(kind)]["SI"]


def to_unit(si_value: float, kind: Kind | str, system: System = "SI") -> tuple[float, str]:
    """Express an SI value in the display unit of ``system`` (from :data:`DISPLAY_UNITS`).

    Parameters
    ----------
    si_value
        Value in the SI unit of ``kind``.
    kind
        Its physical kind.
    system
        ``"SI"`` or ``"US"`` (US customary: ft, mph, lb, lbf, lbf s, ft lbf, lbf ft s^2,
        deg, deg/s, ft/s^2); an SI :class:`DisplaySystem` shows speeds in its ``speed_unit``.

    Returns
    -------
    (float, str)
        The value and its unit label; the label is accepted by :func:`parse`.

    Examples
    --------
    >>> to_unit(9500.0, "mass", "US")  # doctest: +ELLIPSIS
    (20943.914..., 'lb')
    """
    kind = _kind(kind)
    if system not in ("SI", "US"):
        raise ValueError(f"unknown unit system {system!r}; use 'SI' or 'US'")
    label = speed_unit_of(system) if kind is Kind.SPEED else DISPLAY_UNITS[kind][str(system)]
    if kind in _PLAIN:
        return float(si_value), label
    return float(si_value) / _si_factor(label, kind), label


def write_like(si_value: float, kind: Kind | str, like: object = None) -> str | float:
    """An SI value written as a file value in the unit of another file value ``like``.

    The number is exact (Python's shortest ``repr`` of the value in that unit), so that
    :func:`parse` reads back the same SI value to within a rounding of the unit factor.

    Parameters
    ----------
    si_value
        The value in the SI unit of ``kind``.
    kind
        Its physical kind.
    like
        A value as written in a file (``"25 mph"``, ``"5 %"``, ``0.6``) whose unit to use;
        ``None`` or a value without a readable unit: the SI unit of ``kind``.

    Returns
    -------
    str or float
        ``"30.2 mph"``, ``"13.5 m/s"``; a plain number for a dimensionless value (a percentage
        if ``like`` is one).

    Examples
    --------
    >>> write_like(13.4112, "speed", "25 mph")
    '30.0 mph'
    >>> write_like(0.05, "dimensionless", "2 %"), write_like(0.05, "dimensionless", "0.1")
    ('5.0 %', 0.05)
    """
    kind = _kind(kind)
    x = float(si_value)
    unit = None
    if isinstance(like, str):
        m = _NUMBER.fullmatch(like)
        unit = m["unit"] if m is not None and m["unit"] else None
    if kind is Kind.SLOPE and unit not in (None, "%", "percent"):
        try:
            return f"{math.atan(x) / _si_factor(unit, Kind.ANGLE)!r} {unit}"
        except _Invalid:  # not an angle unit: a plain number below
            pass
    if kind in _PLAIN:
        return f"{100.0 * x!r} %" if unit in ("%", "percent") else x
    if unit is not None:
        try:
            return f"{x / _si_factor(unit, kind)!r} {unit}"
        except _Invalid:  # not a unit of this kind: SI below
            pass
    return f"{x!r} {si_unit(kind)}"


def format_value(value: float, kind: Kind | str, system: System = "SI", digits: int = 4) -> str:
    """An SI value as text in the display unit of ``system``, e.g. ``format_value(13.41, "speed", "US")``.

    Angles are always shown in degrees; NaN and None as ``"n/a"``.

    Examples
    --------
    >>> format_value(13.41, "speed", "US")
    '30 mph'
    >>> format_value(0.5, "length", "US")
    '1.64 ft'
    """
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    if _kind(kind) is Kind.ANGLE:
        return f"{math.degrees(value):.{max(digits - 3, 1)}f} deg"
    v, label = to_unit(value, kind, system)
    text = f"{v:.{digits}g}" if abs(v) >= 1e-9 else "0"
    return f"{text} {label}".rstrip()


def convert(value: float, from_unit: str, to_unit: str, kind: Kind | str | None = None) -> float:
    """Convert a number between two units, with the conventions of this module.

    Parameters
    ----------
    value
        The number, in ``from_unit``.
    from_unit, to_unit
        Unit expressions (``"kg m^2"``, ``"ft-lb-s^2"``, ``"mph"``).
    kind
        Read both units as this kind (so ``"lbf"`` -> ``"kg"`` is weight to mass). If
        ``None``, every kind that can read both units is tried; they must agree.

    Returns
    -------
    float
        The value in ``to_unit``.

    Raises
    ------
    ScenarioError
        If no kind reads both units, or two kinds give different answers.

    Examples
    --------
    >>> round(convert(21000, "kg m^2", "ft-lb-s^2"), 1)
    15488.8
    """
    if kind is not None and _kind(kind) is Kind.SLOPE:  # rise over run is not a multiple of an angle
        return _slope_in(_to_si(f"{value!r} {from_unit}".strip(), Kind.SLOPE), to_unit)
    kinds = [k for k in Kind if k is not Kind.SLOPE] if kind is None else [_kind(kind)]
    results: dict[Kind, float] = {}
    reasons: list[str] = []
    for k in kinds:
        unit = from_unit
        try:
            factor = _si_factor(unit, k)
            unit = to_unit
            results[k] = value * factor / _si_factor(unit, k)
        except _Invalid as exc:
            reasons.append(f"'{unit}' {exc}, not {_SPECS[k].noun}")
    if not results:
        detail = f": {reasons[0]}" if kind is not None else ": no quantity kind reads both"
        raise ScenarioError(f"cannot convert '{from_unit}' to '{to_unit}'{detail}")
    first = next(iter(results.values()))
    if any(not math.isclose(r, first, rel_tol=1e-12) for r in results.values()):
        raise ScenarioError(f"converting '{from_unit}' to '{to_unit}' is ambiguous between "
                            f"{', '.join(k.value for k in results)}; pass kind=")
    return first


def _slope_in(rise_over_run: float, unit: str) -> float:
    """A slope (rise over run) as a number in ``unit``: none, a percentage or an angle unit."""
    if not unit:
        return rise_over_run
    if unit in ("%", "percent"):
        return 100.0 * rise_over_run
    try:
        return math.atan(rise_over_run) / _si_factor(unit, Kind.ANGLE)
    except _Invalid as exc:
        raise ScenarioError(f"cannot convert a slope to '{unit}': '{unit}' {exc}, not a percentage or an angle") from None


def example(kind: Kind | str) -> str:
    """An example value of ``kind`` as written in a file (``"30 mph"`` for a speed)."""
    return _SPECS[_kind(kind)].examples[0]


def describe(kind: Kind | str) -> str:
    """Short text for documentation: the SI unit and accepted examples of ``kind``.

    Examples
    --------
    >>> describe("speed")
    'speed [m/s]; accepts m/s, km/h, mph, ft/s; e.g. "30 mph", "13.41 m/s"'
    """
    kind = _kind(kind)
    spec = _SPECS[kind]
    unit = f" [{si_unit(kind)}]" if si_unit(kind) else ""
    return (f'{kind.value.replace("_", " ")}{unit}; accepts {spec.expect}; '
            f'e.g. "{spec.examples[0]}", "{spec.examples[1]}"')
