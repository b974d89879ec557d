"""Parameter sweeps on a batch of impacts, and the paper's barrier sweep (Figures 4 and 5).

Pure numpy: a sweep is one :class:`~crashsim.impact.solve.ImpactBatch` built from a template
:class:`~crashsim.impact.problem.ImpactProblem`, with one field of its
:class:`~crashsim.impact.core.ImpactArrays` set along the batch axis. Everything is SI and
radians; degrees appear only in labels.

Two layers:

* :func:`parameter_sweep` is general: any template, any batch field, optionally crossed with
  a list of Coulomb friction coefficients (the paper's rule, Eq. 8), optionally with an
  ``update`` callback for fields that depend on the swept value.
* :func:`barrier_problem` and :func:`barrier_angle_sweep` are a thin wrapper for the paper's
  "RIGID BARRIER COLLISIONS" section (Table 2, Figures 4 and 5), with the dimensions the
  paper omits taken from ``docs/paper-geometry.md``.

Paper frame of the barrier examples
-----------------------------------
The tractor CG is at the origin with heading pi (travelling -x at the Table 2 speed), as in
the paper's printed results (docs/paper-geometry.md: the paper's frame is the "vehicle travels
+x" frame turned by 180 deg). The crush-surface normal, from the barrier into the tractor,
then points at the barrier angle G: ``normal_angle = G`` with ``tangent_sign = +1``.
G = 0 is a head-on impact; at G = 90 deg the tractor's contact point moves along the wall
and there is no impact (closing velocity 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Callable, Sequence, Union

import numpy as np

from ..errors import ScenarioError
from ..vehicles import Body, BodyState, Hitch, Vehicle, chain_states
from .core import ImpactArrays
from .problem import CrushSurface, ImpactProblem, TangentialLaw
from .solve import ImpactBatch

__all__ = [
    "parameter_sweep",
    "crossings",
    "sliding_onset",
    "Table2Truck",
    "TABLE2",
    "CONTACT_15",
    "CONTACT_75",
    "CONTACT_ANCHOR_ANGLES",
    "contact_points",
    "barrier_problem",
    "barrier_angle_sweep",
]

#: Relative size of the closing velocity below which an item counts as "no impact"
#: (the contact points do not approach; e.g. a barrier angle of exactly 90 deg).
APPROACH_TOL = 1e-9


# --------------------------------------------------------------------------------------------
# General sweep
# --------------------------------------------------------------------------------------------

def parameter_sweep(
    template: ImpactProblem,
    parameter: str,
    values,
    *,
    friction: Sequence[float] | None = None,
    update: Callable[[ImpactArrays, np.ndarray], None] | None = None,
) -> dict[str, np.ndarray]:
    """Solve ``template`` for every value of one :class:`ImpactArrays` field.

    Parameters
    ----------
    template : ImpactProblem
        The impact; every number not swept is taken from it.
    parameter : str
        Name of an :class:`~crashsim.impact.core.ImpactArrays` field, e.g. ``"normal_angle"``
        [rad], ``"restitution"``, ``"law_value"``, ``"point"`` [m, world] or ``"velocity"``.
    values : array_like, shape (N,) + the field's per-impact shape (or broadcastable to it)
        The swept values, SI units.
    friction : sequence of float, optional
        Coulomb coefficients f >= 0. If given, the template's tangential law is replaced by the
        paper's friction rule (Eq. 8: keep mu = mu_max if |mu_max| <= f, else slide throughout
        with |mu| = f) and every value is solved for every f, all in one batch.
    update : callable(arrays, values), optional
        Called after the swept field is set, with the batch's ``ImpactArrays`` (batch size N,
        or F*N with ``friction``: f-major, i.e. item ``i * N + j`` has ``friction[i]`` and
        ``values[j]``) and the values repeated the same way. Use it for fields that depend on
        the swept value (a contact point that moves with the barrier angle).

    Returns
    -------
    dict
        ``"parameter"`` (str), ``"values"`` (N, ...), ``"body_names"``, ``"vehicle_names"``
        (tuples), ``"friction"`` (F,) if given, and every array of
        :meth:`ImpactBatch.solve` (``"energy_loss.system"``, ``"mu_max"``, ``"mu"``,
        ``"sliding"``, ``"yaw_rate"`` (..., n), ``"velocity"`` (..., n, 2), ...) reshaped to
        a leading (N,) or, with ``friction``, (F, N). Also ``"approaching"`` (bool): False where
        the contact points do not approach (closing velocity ~ 0 or > 0); there the ratios
        ``"mu"`` and ``"mu_max"`` are 0/0 and are set to NaN.

    Raises
    ------
    ScenarioError
        Unknown field, values of the wrong shape, or a negative friction coefficient.

    Examples
    --------
    >>> out = parameter_sweep(problem, "restitution", np.linspace(0, 1, 11))   # doctest: +SKIP
    >>> out["energy_loss.system"].shape                                        # doctest: +SKIP
    (11,)
    """
    names = [f.name for f in fields(ImpactArrays)]
    if parameter not in names:
        raise ScenarioError(f"unknown field {parameter!r}; allowed {names}", field="sweep.parameter")
    values = np.asarray(values, dtype=float)
    if values.ndim == 0:
        values = values[None]
    nv = values.shape[0]
    if nv < 1:
        raise ScenarioError("needs at least one value", field="sweep.values")

    if friction is not None:
        fr = np.atleast_1d(np.asarray(friction, dtype=float))
        if fr.ndim != 1 or fr.size < 1 or not np.all(np.isfinite(fr)) or np.any(fr < 0):
            raise ScenarioError(f"must be a non-empty sequence of finite f >= 0, got {friction!r}",
                                field="sweep.friction")
        surf = template.surface
        template = ImpactProblem(
            template.vehicles, template.states, template.body1, template.body2,
            CrushSurface(surf.point, surf.normal_angle, surf.restitution, TangentialLaw("friction", float(fr[0])),
                         surf.moment_restitution, surf.tangent_sign),
            template.constraints, template.external,
        )
        lead = (fr.size, nv)
    else:
        fr = None
        lead = (nv,)
    total = int(np.prod(lead))

    batch = ImpactBatch.from_problem(template, total)
    A = batch.arrays
    target = getattr(A, parameter)
    tiled = np.broadcast_to(values, (lead[0],) + values.shape) if fr is not None else values
    tiled = tiled.reshape((total,) + values.shape[1:])
    try:
        target[...] = np.broadcast_to(tiled, target.shape) if tiled.shape != target.shape else tiled
    except ValueError:
        raise ScenarioError(
            f"values of shape {values.shape} do not fit field {parameter!r} of per-impact shape {target.shape[1:]}",
            field="sweep.values",
        ) from None
    if fr is not None:
        A.law_value[:] = np.repeat(fr, nv)
    if update is not None:
        update(A, tiled)

    out = batch.solve()
    speed = np.max(np.hypot(A.velocity[..., 0], A.velocity[..., 1]), axis=1) + np.abs(A.yaw_rate).max(axis=1)
    approaching = out["closing_velocity"] < -APPROACH_TOL * np.maximum(speed, 1.0)
    out["approaching"] = approaching
    for key in ("mu", "mu_max"):
        out[key] = np.where(approaching, out[key], np.nan)

    res: dict = {
        "parameter": parameter,
        "values": values,
        "body_names": batch.structure.body_names,
        "vehicle_names": batch.structure.vehicle_names,
    }
    if fr is not None:
        res["friction"] = fr
    for k, v in out.items():
        v = np.asarray(v)
        res[k] = v.reshape(lead + v.shape[1:]) if v.ndim >= 1 and v.shape[0] == total else v
    return res


def crossings(x, y, level: float = 0.0) -> np.ndarray:
    """Every x where the sampled curve y(x) crosses ``level`` (linear interpolation).

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Abscissae (increasing) and ordinates; NaN samples break the curve.
    level : float

    Returns
    -------
    ndarray
        Crossing abscissae in increasing order (a sample exactly on ``level`` counts once).
    """
    x = np.asarray(x, dtype=float)
    d = np.asarray(y, dtype=float) - level
    out = []
    for i in range(len(x) - 1):
        a, b = d[i], d[i + 1]
        if not (np.isfinite(a) and np.isfinite(b)):
            continue
        if a == 0.0:
            out.append(x[i])
        elif a * b < 0:
            out.append(x[i] + (x[i + 1] - x[i]) * a / (a - b))
    if len(x) and d[-1] == 0.0:
        out.append(x[-1])
    return np.asarray(out)


def sliding_onset(angles, mu_max, f: float) -> float:
    """Smallest angle beyond which |mu_max| > f on the rest of the sampled range.

    This is the paper's "for f = 0.2 the vehicle will continue sliding along the barrier
    surface throughout the collision for barrier angles of about 14 degrees or greater".
    The last crossing of |mu_max| = f is returned (|mu_max| may dip below f near G = 0 first).

    Returns
    -------
    float
        The angle (same unit as ``angles``); NaN if |mu_max| <= f at the last finite sample;
        ``angles[0]`` if |mu_max| > f everywhere.
    """
    angles = np.asarray(angles, dtype=float)
    m = np.abs(np.asarray(mu_max, dtype=float))
    ok = np.isfinite(m)
    a, m = angles[ok], m[ok]
    if m.size == 0 or not m[-1] > f:
        return float("nan")
    c = crossings(a, m, f)
    return float(c[-1]) if c.size else float(a[0])


# --------------------------------------------------------------------------------------------
# The paper's barrier examples (Table 2; Figures 4, 5; Tables 3, 4)
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Table2Truck:
    """The hypothetical tractor-semitrailer of the paper's Table 2.

    Masses [kg], yaw inertias [kg m^2] and speed [m/s] are the paper's; the pin offsets [m]
    are from ``docs/paper-geometry.md`` (tractor CG to fifth wheel 3.100 m rearward, fifth
    wheel to trailer CG 3.991 m rearward).
    """

    name: str
    trailer_mass: float
    trailer_yaw_inertia: float
    tractor_mass: float = 9500.0
    tractor_yaw_inertia: float = 21000.0
    fifth_wheel: float = 3.100
    kingpin: float = 3.991
    speed: float = 13.41

    def vehicle(self) -> Vehicle:
        return Vehicle(
            "A",
            (Body("A_tractor", self.tractor_mass, self.tractor_yaw_inertia),
             Body("A_trailer", self.trailer_mass, self.trailer_yaw_inertia)),
            (Hitch((-self.fifth_wheel, 0.0), (self.kingpin, 0.0)),),
        )


#: Table 2: a. loaded (Figure 4), b. empty (Figure 5).
TABLE2 = {
    "loaded": Table2Truck("loaded", 20000.0, 150000.0),
    "empty": Table2Truck("empty", 6000.0, 48000.0),
}

#: Contact point from the tractor CG in tractor axes (x forward, y left) [m] recovered from
#: Table 3 (barrier angle 15 deg) and Table 4 (75 deg, the front corner).
CONTACT_15 = (3.924, 0.240)
CONTACT_75 = (3.884, 1.205)
CONTACT_ANCHOR_ANGLES = (math.radians(15.0), math.radians(75.0))

ContactSpec = Union[str, tuple, Callable[[np.ndarray], np.ndarray]]


def contact_points(angles, contact: ContactSpec = "fixed") -> np.ndarray:
    """Contact point in tractor axes [m] for each barrier angle [rad], shape (N, 2).

    ``contact`` is one of

    ``"fixed"``
        The Table 3 point (3.924, 0.240) at every angle.
    ``"corner"``
        The Table 4 front-corner point (3.884, 1.205) at every angle.
    ``"interpolate"``
        Moves linearly with G from the Table 3 point at 15 deg to the corner at 75 deg, and
        stays at the nearer one outside that range. Only the two ends come from the paper
        (Tables 3, 4); the path between them is an assumption: the paper's figures are lost
        and it does not say how its contact point moved.
    a point ``(x, y)``
        That point at every angle.
    a callable
        ``contact(angles) -> (N, 2)`` points in tractor axes.
    """
    g = np.atleast_1d(np.asarray(angles, dtype=float))
    if callable(contact):
        pts = np.asarray(contact(g), dtype=float)
    elif isinstance(contact, str):
        if contact == "fixed":
            pts = np.broadcast_to(np.asarray(CONTACT_15), (g.size, 2))
        elif contact == "corner":
            pts = np.broadcast_to(np.asarray(CONTACT_75), (g.size, 2))
        elif contact == "interpolate":
            g0, g1 = CONTACT_ANCHOR_ANGLES
            s = np.clip((g - g0) / (g1 - g0), 0.0, 1.0)[:, None]
            pts = (1.0 - s) * np.asarray(CONTACT_15) + s * np.asarray(CONTACT_75)
        else:
            raise ScenarioError(
                f"unknown contact {contact!r}; allowed 'fixed', 'corner', 'interpolate', a point or a callable",
                field="sweep.contact",
            )
    else:
        pts = np.broadcast_to(np.asarray(contact, dtype=float), (g.size, 2))
    if pts.shape != (g.size, 2) or not np.all(np.isfinite(pts)):
        raise ScenarioError(f"contact points must be finite with shape ({g.size}, 2), got {pts.shape}",
                            field="sweep.contact")
    return np.array(pts, dtype=float)


def _truck(truck) -> Table2Truck:
    if isinstance(truck, Table2Truck):
        return truck
    try:
        return TABLE2[truck]
    except (KeyError, TypeError):
        raise ScenarioError(f"unknown truck {truck!r}; allowed {sorted(TABLE2)} or a Table2Truck",
                            field="sweep.truck") from None


def barrier_problem(
    truck: str | Table2Truck = "loaded",
    angle: float = math.radians(15.0),
    contact=CONTACT_15,
    *,
    friction: float = 0.6,
    restitution: float = 0.05,
    moment_restitution: float = -1.0,
) -> ImpactProblem:
    """The paper's barrier impact (Fig. 3, Tables 3 and 4) in the paper's frame.

    Parameters
    ----------
    truck : "loaded", "empty" or Table2Truck
    angle : float
        Barrier angle G [rad] (0 = head on).
    contact : (float, float)
        Contact point from the tractor CG in tractor axes [m].
    friction, restitution, moment_restitution : float
        f, e and e' (Table 2: f = 0.2 or 0.6, e = 0.05, e' = -1).

    Returns
    -------
    ImpactProblem
        Tractor ``"A_tractor"`` (body 1) against the barrier ``"wall"`` (body 2); the tractor
        CG at the origin with heading pi, moving at ``truck.speed`` along -x.
    """
    t = _truck(truck)
    veh = t.vehicle()
    wall = Vehicle("barrier", (Body("wall", math.inf, math.inf),))
    states = chain_states(veh, (0.0, 0.0), math.pi, (-t.speed, 0.0))
    cx, cy = (float(c) for c in contact)
    pt = (-cx, -cy)  # tractor axes -> world for heading pi
    states["wall"] = BodyState(pt, 0.0, (0.0, 0.0), 0.0)
    return ImpactProblem(
        (veh, wall), states, "A_tractor", "wall",
        CrushSurface(pt, float(angle), restitution, TangentialLaw("friction", friction), moment_restitution, 1),
    )


def barrier_angle_sweep(
    truck: str | Table2Truck = "loaded",
    angles=None,
    friction: Sequence[float] = (0.2, 0.6),
    contact: ContactSpec = "fixed",
    *,
    n: int = 181,
    restitution: float = 0.05,
) -> dict:
    """Energy loss, mu_max, mu and tractor yaw rate against barrier angle (Figs. 4 and 5).

    The figures of the paper are lost and its contact point moved with the barrier angle in a
    way it does not state (docs/paper-geometry.md: the 15 deg point reproduces "mu_max reaches
    0.2 at about 14 deg", only the front corner reproduces "f = 1.2 needed at 60 deg"). The
    figures can therefore be reproduced in shape, not line for line; ``contact`` chooses
    the assumption (see :func:`contact_points`).

    Parameters
    ----------
    truck : "loaded" (Figure 4), "empty" (Figure 5) or Table2Truck
    angles : array_like, optional
        Barrier angles G [rad], increasing; default ``n`` points from 0 to 90 deg.
    friction : sequence of float
        Coulomb coefficients f (paper: 0.2 and 0.6).
    contact : str, (x, y) or callable
        Contact-point rule, see :func:`contact_points`.
    n : int
        Number of angles when ``angles`` is not given.
    restitution : float
        e (paper: 0.05).

    Returns
    -------
    dict
        Everything :func:`parameter_sweep` returns, with leading axes (F, N), plus

        ``"angle"`` (N,) [rad]; ``"friction"`` (F,); ``"truck"`` (name); ``"contact"`` (N, 2)
        contact points in tractor axes [m]; ``"contact_rule"`` (str);
        ``"energy_loss"`` (F, N) system kinetic-energy loss fraction; ``"mu_max"`` (F, N)
        no-sliding impulse ratio P_t/P_n (the same for every f); ``"mu"`` (F, N) ratio used;
        ``"sliding"`` (F, N) bool, sliding throughout (|mu_max| > f);
        ``"tractor_yaw_rate"`` (F, N) [rad/s] after the impact (counter-clockwise positive,
        in the paper's frame as in the paper).
    """
    t = _truck(truck)
    if angles is None:
        if not (isinstance(n, int) and n >= 2):
            raise ScenarioError(f"n must be an integer >= 2, got {n!r}", field="sweep.n")
        angles = np.linspace(0.0, math.pi / 2, n)
    angles = np.atleast_1d(np.asarray(angles, dtype=float))
    if angles.ndim != 1 or not np.all(np.isfinite(angles)):
        raise ScenarioError("angles must be a 1-D sequence of finite angles [rad]", field="sweep.angles")
    pts = contact_points(angles, contact)
    template = barrier_problem(t, float(angles[0]), tuple(pts[0]), friction=float(np.max(friction)),
                               restitution=restitution)

    wall = [b.name for b in template.bodies].index("wall")

    def move_contact(A: ImpactArrays, g: np.ndarray) -> None:
        # tractor at the origin with heading pi: world point = -(tractor-axes point)
        p = -contact_points(g, contact)
        A.point[:] = p
        A.position[:, wall] = p  # the wall's reference point (its mass is infinite)

    res = parameter_sweep(template, "normal_angle", angles, friction=friction, update=move_contact)
    tractor = res["body_names"].index("A_tractor")
    res.update(
        angle=angles,
        truck=t.name,
        contact=pts,
        contact_rule=contact if isinstance(contact, str) else "custom",
        energy_loss=res["energy_loss.system"],
        tractor_yaw_rate=res["yaw_rate"][..., tractor],
        restitution=restitution,
    )
    return res
