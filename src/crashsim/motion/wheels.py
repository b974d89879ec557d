"""Per-wheel settings of a run-out: state, brake, steer, tyre data, and their schedule.

Wheels (tyre contacts)
----------------------
Every :class:`~crashsim.vehicles.Axle` of every body has two contacts, ``left``
(``+track/2``, body y) and ``right`` (``-track/2``), at the axle's ``x``.  A dual-tyre axle
has one contact per side that stands for both tyres (summed load, twice the per-tyre
cornering stiffness; note sec. 2.4 [5]).  A contact is named by its *key*
``"<body>/<axle index>/<side>"``, e.g. ``"tractor/0/left"``.

Selectors
---------
Settings and scheduled changes address wheels by a selector string:

=======================  ===============================================
``"*"``                  every wheel of the vehicle
``"tractor"``            every wheel of body ``tractor``
``"tractor/1"``          both wheels of axle 1 (index from the front of
                         ``Body.axles``) -- or ``"tractor/drive 1"`` by axle name
``"tractor/1/left"``     one wheel
=======================  ===============================================

More specific selectors override less specific ones; two different selectors of equal
specificity that both match one wheel are an error.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field, fields, replace
from types import MappingProxyType
from typing import Any, Mapping, Sequence

import numpy as np

from ..errors import ScenarioError
from ..vehicles import Vehicle
from .brakes import AirBrakes

__all__ = [
    "WHEEL_STATES",
    "axle_label",
    "wheel_labels",
    "SIDES",
    "WheelSetting",
    "ScheduledChange",
    "WheelSettings",
    "WheelSpec",
    "enumerate_wheels",
]

#: Allowed wheel states.
WHEEL_STATES = ("rolling", "braked", "locked", "jammed")
#: Wheel sides, in the order wheels are enumerated.
SIDES = ("left", "right")

_MAX_MU_FACTOR = 2.0
_MAX_ROLLING_RESISTANCE = 0.5


def _suggest(value: str, allowed: Sequence[str]) -> str:
    close = difflib.get_close_matches(str(value), [str(a) for a in allowed], n=3)
    return f"; best matches are {close}" if close else ""


@dataclass(frozen=True)
class WheelSetting:
    """State and tyre data of one wheel (contact).

    Parameters
    ----------
    state : {"rolling", "braked", "locked", "jammed"}
        ``rolling``: free rolling (rolling resistance plus lateral force from the slip
        angle); ``braked``: rolling with a brake force ``brake * mu * N``; ``locked``: the
        wheel does not turn and slides (Coulomb friction opposite the contact velocity);
        ``jammed``: damaged, slides like a locked wheel, typically with its own
        ``mu_factor`` (rim gouging, deflated tyre).
    brake : float
        Brake fraction b in [0, 1] of the friction capacity mu N; only for ``"braked"``
        (must be 0 otherwise).
    steer : float
        Fixed steer angle [rad] of the wheel heading relative to the body x axis,
        counter-clockwise positive, |steer| <= pi/2.
    cornering_stiffness : float, optional
        Cornering stiffness **per tyre** [N/rad]; a dual contact uses twice this value.
    cornering_coefficient : float, optional
        Alternatively, cornering stiffness per unit load [1/rad] (N/rad per N), applied to
        the contact's current load (so it also covers dual tyres).  Typical 8.6 /rad
        (15 %/deg) for car tyres.  Give exactly one of the two for a rolling or braked wheel.
    rolling_resistance : float, optional
        Rolling-resistance coefficient f_r in [0, 0.5]; required for a rolling or braked wheel.
    mu_factor : float
        Multiplier (0, 2] on the road or zone friction coefficient at this wheel.
    self_steer_limit : float, optional
        A self-steering (castor) wheel with this steer-angle limit [rad] in [0, pi/2]: the wheel
        turns to follow its contact point's path (no slip angle, so no lateral force) while the
        angle that needs lies within +-limit, and sits at the limit beyond it (a fixed wheel steered
        by the limit).  ``steer`` is then not used.  0 is the axle locked straight (drivers lock a
        self-steering axle to reverse); None (default) a wheel that does not steer by itself.
        Model: :func:`crashsim.motion.tyres.castor_angle`.
    """

    state: str
    brake: float = 0.0
    steer: float = 0.0
    cornering_stiffness: float | None = None
    cornering_coefficient: float | None = None
    rolling_resistance: float | None = None
    mu_factor: float = 1.0
    self_steer_limit: float | None = None

    def __post_init__(self):
        if self.state not in WHEEL_STATES:
            raise ScenarioError(
                f"must be one of {WHEEL_STATES}, got {self.state!r}{_suggest(self.state, WHEEL_STATES)}",
                field="state",
            )
        brake = float(self.brake)
        if not (0.0 <= brake <= 1.0):
            raise ScenarioError(f"brake fraction must lie in [0, 1], got {self.brake!r}", field="brake")
        if self.state != "braked" and brake != 0.0:
            raise ScenarioError(
                f"a brake fraction ({brake}) is only meaningful for state 'braked', got state {self.state!r}",
                field="brake",
            )
        object.__setattr__(self, "brake", brake)
        steer = float(self.steer)
        if not (math.isfinite(steer) and abs(steer) <= math.pi / 2):
            shown = f"{math.degrees(steer):.4g} deg" if math.isfinite(steer) else repr(self.steer)
            raise ScenarioError(f"must lie in [-90, 90] deg, got {shown}", field="steer")
        object.__setattr__(self, "steer", steer)
        for name in ("cornering_stiffness", "cornering_coefficient"):
            value = getattr(self, name)
            if value is not None:
                v = float(value)
                if not (math.isfinite(v) and v > 0):
                    raise ScenarioError(f"must be a positive finite number, got {value!r}", field=name)
                object.__setattr__(self, name, v)
        if self.cornering_stiffness is not None and self.cornering_coefficient is not None:
            raise ScenarioError(
                "give either cornering_stiffness [N/rad] or cornering_coefficient [1/rad], not both",
                field="cornering_stiffness",
            )
        if self.rolling_resistance is not None:
            fr = float(self.rolling_resistance)
            if not (0.0 <= fr <= _MAX_ROLLING_RESISTANCE):
                raise ScenarioError(
                    f"must lie in [0, {_MAX_ROLLING_RESISTANCE}], got {self.rolling_resistance!r}",
                    field="rolling_resistance",
                )
            object.__setattr__(self, "rolling_resistance", fr)
        muf = float(self.mu_factor)
        if not (0.0 < muf <= _MAX_MU_FACTOR):
            raise ScenarioError(f"must lie in (0, {_MAX_MU_FACTOR}], got {self.mu_factor!r}", field="mu_factor")
        object.__setattr__(self, "mu_factor", muf)
        if self.self_steer_limit is not None:
            lim = float(self.self_steer_limit)
            if not (math.isfinite(lim) and 0.0 <= lim <= math.pi / 2):
                shown = f"{math.degrees(lim):.4g} deg" if math.isfinite(lim) else repr(self.self_steer_limit)
                raise ScenarioError(f"must lie in [0, 90] deg, got {shown}", field="self_steer_limit")
            object.__setattr__(self, "self_steer_limit", lim)

    @property
    def is_sliding(self) -> bool:
        """True for a locked or jammed wheel (pure Coulomb sliding)."""
        return self.state in ("locked", "jammed")

    def check_tyre_data(self, where: str) -> None:
        """Raise ScenarioError if a rolling or braked wheel lacks its tyre data."""
        if self.is_sliding:
            return
        if self.cornering_stiffness is None and self.cornering_coefficient is None:
            raise ScenarioError(
                f"a {self.state} wheel needs cornering_stiffness [N/rad, > 0] or cornering_coefficient [1/rad, > 0]",
                field=f"{where}.cornering_stiffness",
            )
        if self.rolling_resistance is None:
            raise ScenarioError(
                f"a {self.state} wheel needs rolling_resistance in [0, {_MAX_ROLLING_RESISTANCE}]",
                field=f"{where}.rolling_resistance",
            )


_SETTING_FIELDS = tuple(f.name for f in fields(WheelSetting))


@dataclass(frozen=True)
class ScheduledChange:
    """A change of wheel settings from a given time on (e.g. brakes released at 0.5 s).

    Parameters
    ----------
    time : float
        Time after separation [s], > 0.  The run-out is integrated piecewise so that the
        change falls exactly on a segment boundary.
    wheels : str
        Selector of the wheels concerned (see the module docstring).
    changes : mapping
        New values of :class:`WheelSetting` fields, e.g. ``{"state": "rolling"}``.  When the
        new state is not ``"braked"`` and ``brake`` is not given, the brake fraction is reset
        to 0; setting one of ``cornering_stiffness``/``cornering_coefficient`` clears the other.
    """

    time: float
    wheels: str
    changes: Mapping[str, Any]

    def __post_init__(self):
        t = float(self.time)
        if not (math.isfinite(t) and t > 0):
            raise ScenarioError(f"must be a finite time > 0 s, got {self.time!r}", field="schedule.time")
        object.__setattr__(self, "time", t)
        if not isinstance(self.wheels, str) or not self.wheels:
            raise ScenarioError(f"must be a selector string, got {self.wheels!r}", field="schedule.wheels")
        changes = dict(self.changes)
        if not changes:
            raise ScenarioError("a scheduled change must change at least one field", field="schedule.changes")
        for key in changes:
            if key not in _SETTING_FIELDS:
                raise ScenarioError(
                    f"unknown wheel setting {key!r}; allowed {_SETTING_FIELDS}{_suggest(key, _SETTING_FIELDS)}",
                    field="schedule.changes",
                )
        object.__setattr__(self, "changes", MappingProxyType(changes))

    def apply(self, setting: WheelSetting) -> WheelSetting:
        """The setting after this change."""
        changes = dict(self.changes)
        if changes.get("state", setting.state) != "braked" and "brake" not in changes:
            changes["brake"] = 0.0
        if "cornering_stiffness" in changes and "cornering_coefficient" not in changes:
            changes["cornering_coefficient"] = None
        if "cornering_coefficient" in changes and "cornering_stiffness" not in changes:
            changes["cornering_stiffness"] = None
        try:
            return replace(setting, **changes)
        except ScenarioError as err:
            raise ScenarioError(str(err), field=f"schedule[t={self.time}, {self.wheels!r}]") from None


@dataclass(frozen=True)
class WheelSpec:
    """Geometry of one tyre contact (derived from the vehicle; not user input).

    Attributes
    ----------
    key : str
        ``"<body>/<axle index>/<side>"``.
    body, body_index : str, int
        Body name and its index in ``Vehicle.bodies``.
    axle_index, axle_name : int, str
        Axle index in ``Body.axles`` and its name.
    side : {"left", "right"}
    position : (float, float)
        Contact centre in body axes [m].
    tyres : int
        Tyres in the contact: 2 for a dual axle, else 1.
    """

    key: str
    body: str
    body_index: int
    axle_index: int
    axle_name: str
    side: str
    position: tuple[float, float]
    tyres: int
    label: str = ""

    def __post_init__(self) -> None:
        if not self.label:
            object.__setattr__(self, "label", self.key)


def axle_label(body, index: int) -> str:
    """How reports name an axle of ``body``: its name from the file where it has one that is unique in the
    body and not a number (so that ``<body>/<label>`` still selects it, see :func:`select_wheels`), else
    its index."""
    names = [a.name for a in body.axles]
    name = names[index]
    if name and names.count(name) == 1 and not name.strip().isdigit() and "/" not in name:
        return name
    return str(index)


def wheel_labels(vehicles) -> dict[str, str]:
    """Wheel key (``"trailer/1/right"``) -> the name reports and CSV files give it (``"trailer/axle 2/right"``,
    the axle's name from the file), for every wheel of ``vehicles``."""
    return {w.key: w.label for v in vehicles for w in enumerate_wheels(v)}


def enumerate_wheels(vehicle: Vehicle) -> tuple[WheelSpec, ...]:
    """All tyre contacts of a vehicle, body by body, axle by axle, left then right; each with its
    ``key`` (``<body>/<axle index>/<side>``) and the ``label`` reports show (the axle's name)."""
    out = []
    for bi, body in enumerate(vehicle.bodies):
        for ai, axle in enumerate(body.axles):
            label = axle_label(body, ai)
            for side in SIDES:
                y = axle.track / 2 if side == "left" else -axle.track / 2
                out.append(
                    WheelSpec(
                        key=f"{body.name}/{ai}/{side}",
                        body=body.name,
                        body_index=bi,
                        axle_index=ai,
                        axle_name=axle.name,
                        side=side,
                        position=(float(axle.x), float(y)),
                        tyres=2 if axle.dual else 1,
                        label=f"{body.name}/{label}/{side}",
                    )
                )
    return tuple(out)


def select_wheels(vehicle: Vehicle, specs: Sequence[WheelSpec], selector: str, where: str) -> tuple[list[int], int]:
    """Indices of the wheels a selector matches and the selector's specificity (0..3)."""
    if selector == "*":
        return list(range(len(specs))), 0
    parts = selector.split("/")
    if len(parts) > 3:
        raise ScenarioError(
            f"selector {selector!r} has more than 3 parts; use 'body', 'body/axle' or 'body/axle/side'", field=where
        )
    body_names = [b.name for b in vehicle.bodies]
    if parts[0] not in body_names:
        raise ScenarioError(
            f"no body {parts[0]!r} in vehicle {vehicle.name!r}; bodies are {body_names}{_suggest(parts[0], body_names)}",
            field=where,
        )
    body = vehicle.body(parts[0])
    axle_index = None
    if len(parts) >= 2:
        token = parts[1]
        names = [a.name for a in body.axles]
        if token.isdigit() and int(token) < len(body.axles):
            axle_index = int(token)
        elif token in names:
            if names.count(token) > 1:
                raise ScenarioError(f"axle name {token!r} is not unique in body {body.name!r}; use the index", field=where)
            axle_index = names.index(token)
        else:
            allowed = [str(i) for i in range(len(body.axles))] + [n for n in names if n]
            raise ScenarioError(
                f"no axle {token!r} on body {body.name!r}; allowed {allowed}{_suggest(token, allowed)}", field=where
            )
    side = None
    if len(parts) == 3:
        side = parts[2]
        if side not in SIDES:
            raise ScenarioError(f"side must be one of {SIDES}, got {side!r}", field=where)
    idx = [
        i
        for i, s in enumerate(specs)
        if s.body == body.name
        and (axle_index is None or s.axle_index == axle_index)
        and (side is None or s.side == side)
    ]
    if not idx:
        raise ScenarioError(f"selector {selector!r} matches no wheel (does the body have axles?)", field=where)
    return idx, len(parts)


def _resolve_map(vehicle, specs, default, overrides, where) -> list[WheelSetting | None]:
    settings: list[WheelSetting | None] = [default] * len(specs)
    claimed: dict[tuple[int, int], str] = {}
    ranked = []
    for selector, setting in overrides.items():
        if not isinstance(setting, WheelSetting):
            raise ScenarioError(f"must be a WheelSetting, got {type(setting).__name__}", field=f"{where}[{selector!r}]")
        idx, spec = select_wheels(vehicle, specs, selector, f"{where}[{selector!r}]")
        ranked.append((spec, selector, idx, setting))
    for spec, selector, idx, setting in sorted(ranked, key=lambda r: r[0]):
        for i in idx:
            other = claimed.get((spec, i))
            if other is not None:
                raise ScenarioError(
                    f"selectors {other!r} and {selector!r} both set wheel {specs[i].key!r}", field=f"{where}[{selector!r}]"
                )
            claimed[(spec, i)] = selector
            settings[i] = setting
    return settings


@dataclass(frozen=True)
class WheelSettings:
    """Wheel settings of one vehicle for its run-out.

    Parameters
    ----------
    default : WheelSetting, optional
        Setting of every wheel not matched by ``wheels``.  If omitted, every wheel must
        be matched.
    wheels : mapping of str to WheelSetting
        Settings by selector (see the module docstring), overriding ``default``.
    schedule : sequence of ScheduledChange
        Changes from given times on, applied in time order (changes at equal times in the
        order given).
    brakes : AirBrakes, optional
        Air brakes (:mod:`crashsim.motion.brakes`): the brake force of the rolling wheels of
        the braked units as a ramp in time; None (the default) leaves the wheels as set.

    Examples
    --------
    >>> tyre = dict(cornering_coefficient=8.6, rolling_resistance=0.012)
    >>> ws = WheelSettings(
    ...     default=WheelSetting("locked"),
    ...     wheels={"car/0": WheelSetting("rolling", **tyre)},
    ...     schedule=[ScheduledChange(0.5, "car", {"state": "rolling", **tyre})],
    ... )
    """

    default: WheelSetting | None = None
    wheels: Mapping[str, WheelSetting] = field(default_factory=dict)
    schedule: Sequence[ScheduledChange] = ()
    brakes: AirBrakes | None = None

    def __post_init__(self):
        if self.brakes is not None and not isinstance(self.brakes, AirBrakes):
            raise ScenarioError(f"must be AirBrakes, got {type(self.brakes).__name__}", field="brakes")
        if self.default is not None and not isinstance(self.default, WheelSetting):
            raise ScenarioError(f"must be a WheelSetting, got {type(self.default).__name__}", field="wheels.default")
        object.__setattr__(self, "wheels", MappingProxyType(dict(self.wheels)))
        sched = tuple(self.schedule)
        for c in sched:
            if not isinstance(c, ScheduledChange):
                raise ScenarioError(f"must be a ScheduledChange, got {type(c).__name__}", field="wheels.schedule")
        object.__setattr__(self, "schedule", tuple(sorted(sched, key=lambda c: c.time)))

    @classmethod
    def all_locked(cls) -> "WheelSettings":
        """Every wheel locked (the settings used when ``wheels=None``)."""
        return cls(default=WheelSetting("locked"))

    def resolve(self, vehicle: Vehicle) -> "ResolvedWheels":
        """Settings of every wheel of ``vehicle`` over time; validates everything once."""
        specs = enumerate_wheels(vehicle)
        where = f"wheels[{vehicle.name!r}]"
        base = _resolve_map(vehicle, specs, self.default, self.wheels, where)
        for s, setting in zip(specs, base):
            if setting is None:
                raise ScenarioError(
                    f"wheel {s.key!r} has no setting; give WheelSettings.default or a selector matching it",
                    field=where,
                )
        phases = [(0.0, tuple(base))]
        current = list(base)
        for change in self.schedule:
            idx, _ = select_wheels(vehicle, specs, change.wheels, f"{where}.schedule[t={change.time}]")
            for i in idx:
                current[i] = change.apply(current[i])
            if phases[-1][0] == change.time:
                phases[-1] = (change.time, tuple(current))
            else:
                phases.append((change.time, tuple(current)))
        for t, settings in phases:
            for s, setting in zip(specs, settings):
                setting.check_tyre_data(f"{where}[{s.key!r}] (t >= {t} s)")
        if self.brakes is not None:
            check_brakes(vehicle, specs, phases, self.brakes)
        return ResolvedWheels(specs=specs, phases=tuple(phases), brakes=self.brakes)


def check_brakes(vehicle: Vehicle, specs, phases, brakes: AirBrakes) -> None:
    """Raise ScenarioError where the air brakes do not fit the vehicle or its wheel states: a unit that is
    not a body, capacities that do not match its axles, a braked wheel (fraction) on a braked unit, or a
    wheel of an ABS unit locked by its settings while the brakes act."""
    names = [b.name for b in vehicle.bodies]
    for name, unit in brakes.units.items():
        if name not in names:
            raise ScenarioError(f"no body {name!r} in vehicle {vehicle.name!r}; bodies are {names}"
                                f"{_suggest(name, names)}", field="units.body")
        n_axles = len(vehicle.body(name).axles)
        if len(unit.capacity) not in (1, n_axles):
            raise ScenarioError(f"body {name!r} has {n_axles} axles, got {len(unit.capacity)} capacities (give one "
                                f"per axle, or one for every axle)", field=f"units[{name!r}].capacity")
    ends = [t for t, _ in phases[1:]] + [math.inf]
    for (t0, settings), t1 in zip(phases, ends):
        for s, setting in zip(specs, settings):
            unit = brakes.units.get(s.body)
            if unit is None:
                continue
            if setting.state == "braked":
                raise ScenarioError(f"wheel {s.label!r} is 'braked' with a brake fraction ({setting.brake:g}) from "
                                    f"{t0:g} s while body {s.body!r} has air brakes; give state = \"rolling\" (the air "
                                    "brakes give its brake force) or remove the body from the brakes' units",
                                    field=f"units[{s.body!r}]")
            if unit.abs and setting.state == "locked":
                on, _, off, fall = brakes.times(s.body)
                if t1 > on and t0 < off + fall:
                    flag = "tractor_abs" if s.body_index == 0 else "trailer_abs"
                    span = f"from {t0:g} s on" if math.isinf(t1) else f"from {t0:g} s to {t1:g} s"
                    raise ScenarioError(f"is true, but wheel {s.label!r} is locked by its wheel settings {span} while its unit's brakes act (from {on:g} s); ABS keeps its wheels "
                                        f"rolling: allowed is {flag} = false or state = \"rolling\" there",
                                        field=flag)


@dataclass(frozen=True)
class ResolvedWheels:
    """Per-wheel settings of a vehicle as a step function of time.

    Attributes
    ----------
    specs : tuple of WheelSpec
        The contacts, in the order of :func:`enumerate_wheels`.
    phases : tuple of (float, tuple of WheelSetting)
        ``(start time [s], settings per wheel)``; the first phase starts at 0.
    """

    specs: tuple[WheelSpec, ...]
    phases: tuple[tuple[float, tuple[WheelSetting, ...]], ...]
    brakes: AirBrakes | None = None

    def brake_rows(self, vehicle: Vehicle) -> np.ndarray:
        """Per wheel ``(has air brakes, t_on, rise, t_off, fall, brake force at full application [N],
        ABS efficiency (0: none))``, shape (nw, 7); all zero without air brakes."""
        if self.brakes is None:
            return np.zeros((len(self.specs), 7))
        units = self.brakes.units
        timing = {name: self.brakes.times(name) for name in units}
        none = (0.0,) * 7
        rows = []
        for s in self.specs:
            unit = units.get(s.body)
            if unit is None:
                rows.append(none)
                continue
            cap = unit.capacity[0] if len(unit.capacity) == 1 else unit.capacity[s.axle_index]
            rows.append((1.0, *timing[s.body], 0.5 * cap * (1.0 - unit.out_of_adjustment),
                         self.brakes.abs_efficiency if unit.abs else 0.0))
        return np.array(rows, dtype=float).reshape(-1, 7)

    @property
    def change_times(self) -> tuple[float, ...]:
        """Times [s] at which settings change (segment boundaries of the integration)."""
        return tuple(t for t, _ in self.phases[1:])

    def at(self, t: float) -> tuple[WheelSetting, ...]:
        """Settings in force at time ``t`` [s] (a change at ``t`` is already in force)."""
        times = np.array([p[0] for p in self.phases])
        return self.phases[int(np.searchsorted(times, t, side="right")) - 1][1]
