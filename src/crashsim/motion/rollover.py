"""Wheel lift and rollover: each body's load transfer ratio and lateral acceleration against its threshold.

What is computed (``RunoutOptions(rollover=True)``, level ``load_transfer`` only)
-------------------------------------------------------------------------------
The ``load_transfer`` level gives every contact the load ``N = N_static g_n + T a_f``
(:mod:`crashsim.motion.loads`; ``g_n`` the slope's normal factor, ``a_f`` the filtered body-axes
accelerations of the state).  From the *unclamped* loads (the tyre forces use ``max(N, 0)``):

* per axle, ``LTR_axle = (N_right - N_left) / (N_right + N_left)``; its inner wheel lifts when
  ``|LTR_axle|`` reaches 1 (the inner load reaches 0): event ``"wheel_lift"`` (the body's first
  axle to lift);
* per body (unit), ``LTR = (sum N_right - sum N_left) / (sum N_right + sum N_left)`` over its
  axles; all its inner wheels are off the ground when ``|LTR|`` reaches 1: event
  ``"unit_lift"``.  For a rigid body on one track width this happens at the lateral acceleration
  ``a_y = g t / (2 h)`` (the static stability factor);
* the body's lateral acceleration ``|a_y| / (g g_n)`` (the filtered body-axes specific force that
  transfers load: tyre and hitch forces at the ground, contact forces by their height over the
  CG's, :func:`crashsim.motion.kernels.equations.specific_force`; in units of the normal gravity)
  reaching its rollover threshold (an input in g, default :func:`default_rollover_threshold`):
  event ``"rollover_threshold"``.  A side push at the CG's height (a contact at the default
  height) accelerates the body without counting here.

Each is recorded once per body, at its first occurrence, with the body's CG place and speed.
From the earliest of them the planar result of that vehicle is outside its validity (a unit
whose wheels lift is rolling, which three planar degrees of freedom do not describe).

How the events are located
--------------------------
The three indicators are functions of the state alone (the filtered accelerations), so they
are found after the run, on the engine's own solution, by one routine for both engines: a
scan of the result's samples (every ``sample_dt``, default 10 ms, and every segment boundary),
then Brent's method on the dense solution inside the first sampled interval where an indicator
changes sign (to :data:`ROOT_XTOL`).  A scan can step over an exceedance shorter than
``sample_dt``; the filtered accelerations follow the forces with the lag ``tau`` (0.2 s by
default), twenty times the sampling interval, so such an exceedance is a graze of the threshold
by a tiny fraction of it.  Root finding in the integration itself (a terminal-free event of the
kernels) would catch those too, at the price of a kernel change and of work in every step of
every run; the post-run search costs nothing when the check is off and a few array products
when it is on.

Roll coupling between units
---------------------------
By default the load model puts each body's roll moment ``m a_y h`` on that body's own axles and
the hitch forces at ground level: the coupling passes no roll moment (a ball, a drawbar eye, an
A-dolly's ring).  A fifth wheel is stiff in roll; a towed body with ``roll_coupled`` shares its
roll moment with the towing body in proportion to the hitch's static load
(:func:`crashsim.motion.loads.load_transfer_matrix`), so its own axles transfer the rigid body's
``2 h a_y / (g t)``.  Free in roll, a semitrailer's axles carry all its roll moment on less than
all its weight, and its wheels lift at about ``(W - N_kp)/W`` of its ``t/(2h)``: early.  The
threshold check compares each body with its own threshold, which for a coupled unit is best the
combination's tilt-table value (SAE J2180 tests the combination).
"""

from __future__ import annotations

import math
from bisect import bisect_left, bisect_right
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ..errors import ScenarioError
from ..units import G0 as STANDARD_GRAVITY
from ..vehicles import MAX_ROLLOVER_THRESHOLD, Body
from .layout import SV_AX_F, SV_AY_F
from .scene_model import kernels
from .result import RunoutEvent

__all__ = ["DEFAULT_THRESHOLD_FACTOR", "MAX_ROLLOVER_THRESHOLD", "ROLL_EVENT_KINDS", "ROOT_XTOL", "RollMonitor",
           "default_rollover_threshold", "rollover_threshold", "static_stability_factor", "roll_summary",
           "with_events"]

#: Rigid-body threshold t/(2h) times this is the default rollover threshold: suspension and tyre
#: compliance (and payload shift) move the CG outboard as the body rolls.  Gertsch and Eichelhard
#: (SAE 2003-01-3385) found tractor-semitrailer rollover thresholds about 25 % below t/(2h).
DEFAULT_THRESHOLD_FACTOR = 0.75
#: Event kinds recorded by the check, in the order they are searched for each body.
ROLL_EVENT_KINDS = ("wheel_lift", "unit_lift", "rollover_threshold")
#: Time tolerance [s] of the root search on the dense solution.
ROOT_XTOL = 1e-9


def static_stability_factor(body: Body) -> float:
    """Rigid-body rollover threshold ``t / (2 h)`` [g] of a body (mean track of its axles).

    Raises
    ------
    ScenarioError
        Without ``cg_height`` or without axles.
    """
    if body.cg_height is None:
        raise ScenarioError("the default rollover threshold 0.75 t / (2 h) needs the CG height h of the body "
                            "(give cg_height, or rollover_threshold in g)", field=f"{body.name}.cg_height")
    if not body.axles:
        raise ScenarioError("the default rollover threshold 0.75 t / (2 h) needs the track t of the body's axles",
                            field=f"{body.name}.axles")
    track = sum(a.track for a in body.axles) / len(body.axles)  # the mean (summed in order, as np.mean for < 8)
    return track / (2.0 * body.cg_height)


def default_rollover_threshold(body: Body) -> float:
    """Default rollover threshold [g]: :data:`DEFAULT_THRESHOLD_FACTOR` times ``t / (2 h)``, at most
    :data:`~crashsim.vehicles.MAX_ROLLOVER_THRESHOLD`."""
    return min(DEFAULT_THRESHOLD_FACTOR * static_stability_factor(body), MAX_ROLLOVER_THRESHOLD)


def rollover_threshold(body: Body) -> float:
    """The body's rollover threshold [g]: its ``rollover_threshold`` input, else the default."""
    return body.rollover_threshold if body.rollover_threshold is not None else default_rollover_threshold(body)


@dataclass(frozen=True)
class _Axle:
    body: int
    name: str
    left: int
    right: int


class RollMonitor:
    """The roll indicators of a scene model, and the search for their first crossings.

    Parameters
    ----------
    model : SceneModel
        Built with ``options.load_transfer`` (the load-transfer matrix is read from it).
    """

    def __init__(self, model):
        if not model.options.load_transfer:
            raise ScenarioError("the wheel-lift and rollover check needs the load_transfer level", field="rollover")
        self.model = model
        M = model.M
        self.nb = model.n_bodies
        self.transfer = np.asarray(M.load_transfer)
        self.n0 = np.asarray(M.wheel[:, 2], dtype=float)
        self.thresholds = np.array([rollover_threshold(b) for b in model.bodies])
        specs = model.specs
        nb, nw = self.nb, len(specs)
        axles: dict[tuple[int, int], dict] = {}
        for k, s in enumerate(specs):
            d = axles.setdefault((s.body_index, s.axle_index), {"name": s.axle_name})
            d[s.side] = k
        # sorted by body, then axle: each body's axles are one run of rows, ax_span[i] = (first, end) of body i's
        self.axles = tuple(_Axle(bi, d["name"], d["left"], d["right"]) for (bi, _), d in sorted(axles.items())
                           if "left" in d and "right" in d)
        body_of = [a.body for a in self.axles]
        self.ax_span = [(bisect_left(body_of, i), bisect_right(body_of, i)) for i in range(nb)]
        self.ax_left = np.array([a.left for a in self.axles], dtype=np.int64)
        self.ax_right = np.array([a.right for a in self.axles], dtype=np.int64)
        self.ax_body = np.array(body_of, dtype=np.int64)
        #: the bodies with axles, and the first of each one's run of axle rows (for np.maximum.reduceat)
        self.ax_bodies = np.array([i for i, (a, b) in enumerate(self.ax_span) if b > a], dtype=np.int64)
        self.ax_first = np.array([a for a, b in self.ax_span if b > a], dtype=np.int64)
        self.wheel_body = np.array([s.body_index for s in specs], dtype=np.int64)
        self.side = np.array([1.0 if s.side == "right" else -1.0 for s in specs])
        #: (nb, nw): which contacts are the body's, and the same with the side's sign (right +)
        self.member = np.zeros((nb, nw))
        self.member[self.wheel_body, np.arange(nw)] = 1.0
        self.signed = self.member * self.side[None, :]
        self.weight = self.member @ self.n0  # each body's static load on a level road [N]
        self._gn_statics: dict[bytes, tuple] = {}

    @classmethod
    def of(cls, model) -> "RollMonitor":
        """The monitor of ``model``, built once per model (a model reused across the runs of a fit or
        Monte Carlo study keeps it)."""
        monitor = model.__dict__.get("_roll_monitor")
        if monitor is None:
            monitor = model.__dict__["_roll_monitor"] = cls(model)
        return monitor

    # ---------------------------------------------------------------- indicators
    def normal_factor(self, memb) -> np.ndarray:
        """The slope's normal factor under every wheel (nw,) for a zone membership (nw, nz)."""
        M = self.model.M
        if not self.model.road.sloped:
            return np.ones(self.n0.shape[0])
        gn = np.full(self.n0.shape[0], float(M.cfg[kernels().C_GN]))
        memb = np.asarray(memb, dtype=bool)
        for z in range(memb.shape[1]):  # the last zone a wheel is in counts, as in the kernels
            gn[memb[:, z]] = M.zone_slope[z, 2]
        return gn

    def loads(self, Y: np.ndarray, gn: np.ndarray) -> np.ndarray:
        """Unclamped contact loads (nw, K) [N] of states ``Y`` (n, K)."""
        acc = Y[SV_AX_F * self.nb: (SV_AY_F + 1) * self.nb]
        return (self.n0 * gn)[:, None] + self.transfer @ acc

    def values(self, Y: np.ndarray, gn: np.ndarray):
        """``(ind, ltr, ay, N, g)``: per kind the indicator (nb, K), >= 0 where the condition holds; the
        unit LTR (nb, K), the lateral acceleration [g] (nb, K), the unclamped loads (nw, K) and each
        axle's lift indicator (n_axles, K) (None without axles)."""
        nb = self.nb
        n0, static, g_body = self._statics(gn)
        N = n0[:, None] + self.transfer @ Y[SV_AX_F * nb: (SV_AY_F + 1) * nb]  # the loads (as loads())
        K = N.shape[1]
        lift = np.full((nb, K), -np.inf)
        g = None
        if self.axles:
            g = -np.minimum(N[self.ax_left], N[self.ax_right]) / static  # (n_axles, K)
            lift[self.ax_bodies] = np.maximum.reduceat(g, self.ax_first, axis=0)  # each body's largest
        tot = self.member @ N
        ltr = np.divide(self.signed @ N, tot, out=np.zeros((nb, K)), where=tot > 0)
        ay = Y[SV_AY_F * nb: (SV_AY_F + 1) * nb] / g_body
        ind = {"wheel_lift": lift, "unit_lift": np.abs(ltr) - 1.0,
               "rollover_threshold": np.abs(ay) - self.thresholds[:, None]}
        return ind, ltr, ay, N, g

    def _statics(self, gn: np.ndarray):
        """``(n0 gn (nw,), each axle's static load (n_axles, 1), each body's normal gravity (nb, 1))`` under
        the normal factors ``gn``: what :meth:`values` divides by, kept per value of ``gn`` (a run has one
        or a few)."""
        key = gn.tobytes()
        got = self._gn_statics.get(key)
        if got is None:
            n0 = self.n0 * gn
            static = np.maximum(n0[self.ax_left] + n0[self.ax_right], 1e-12)[:, None] if self.axles else None
            w = self.weight
            gn_body = np.divide(self.member @ n0, w, out=np.ones(self.nb), where=w > 0)
            if len(self._gn_statics) >= 64:  # many zones' slopes in a long study: keep the memory bounded
                self._gn_statics.clear()
            got = self._gn_statics[key] = (n0, static, (STANDARD_GRAVITY * gn_body)[:, None])
        return got

    def indicators(self, Y: np.ndarray, gn: np.ndarray):
        """``(ind, ltr, ay_g, axle_of)``: per kind the indicator (nb, K), >= 0 where the condition holds;
        the unit LTR (nb, K), the lateral acceleration [g] (nb, K), the lifting axle (nb, K)."""
        ind, ltr, ay, _, g = self.values(Y, gn)
        K = ltr.shape[1]
        axle_of = np.full((self.nb, K), -1, dtype=np.int64)
        if g is not None:
            for i in self.ax_bodies.tolist():
                first, end = self.ax_span[i]
                axle_of[i] = first + np.argmax(g[first:end], axis=0)
        return ind, ltr, ay, axle_of

    def indicator(self, y: np.ndarray, gn: np.ndarray, i: int, kind: str) -> float:
        """One indicator of body ``i`` at one state ``y`` (n,): the value :meth:`indicators` gives, for the
        root search (only the body's own contacts are evaluated)."""
        nb = self.nb
        if kind == "rollover_threshold":
            on = self.member[i] > 0
            w = float(self.n0[on].sum())
            gn_i = float(np.dot(self.n0[on], gn[on]) / w) if w > 0 else 1.0
            return abs(float(y[SV_AY_F * nb + i])) / (STANDARD_GRAVITY * gn_i) - float(self.thresholds[i])
        acc = y[SV_AX_F * nb: (SV_AY_F + 1) * nb]
        if kind == "wheel_lift":
            rows = np.flatnonzero(self.ax_body == i)
            if not rows.size:
                return -np.inf
            lf, rt = self.ax_left[rows], self.ax_right[rows]
            n_l = self.n0[lf] * gn[lf] + self.transfer[lf] @ acc
            n_r = self.n0[rt] * gn[rt] + self.transfer[rt] @ acc
            static = np.maximum(self.n0[lf] * gn[lf] + self.n0[rt] * gn[rt], 1e-12)
            return float(np.max(-np.minimum(n_l, n_r) / static))
        on = np.flatnonzero(self.member[i] > 0)
        n = self.n0[on] * gn[on] + self.transfer[on] @ acc
        tot = float(n.sum())
        return (abs(float(np.dot(self.side[on], n)) / tot) if tot > 0 else 0.0) - 1.0

    # ---------------------------------------------------------------- events
    def series(self, T: np.ndarray, seg_of: np.ndarray, Y: np.ndarray, memb) -> tuple[np.ndarray, np.ndarray]:
        """Every body's unit load transfer ratio and lateral acceleration [g] at the samples, (nb, K) each
        (the values the events are found on; ``memb`` the zone membership of every segment)."""
        ltr = np.zeros((self.nb, len(T)))
        ay = np.zeros((self.nb, len(T)))
        if not len(T):
            return ltr, ay
        for s in np.unique(seg_of).tolist():  # the normal factor is constant in a segment
            cols = seg_of == s
            gn = self.normal_factor(memb[s]) if len(memb) else np.ones(self.n0.shape[0])
            _, ltr[:, cols], ay[:, cols], _, _ = self.values(Y[:, cols], gn)
        return ltr, ay

    def events(self, T: np.ndarray, seg_of: np.ndarray, Y: np.ndarray, memb, starts: np.ndarray, sol) -> list:
        """The first crossing of every indicator of every body, as :class:`RunoutEvent` (sorted by time).

        Parameters
        ----------
        T, seg_of, Y
            Sample times (K,), their segments (K,) and states (n, K).
        memb
            Zone membership of every segment (nseg, nw, nz).
        starts
            Start time of every segment (nseg,).
        sol
            Dense solution of the run, ``sol(t)`` -> state.
        """
        model, nb = self.model, self.nb
        if not len(T):
            return []
        gns = {}

        def gn_of(s):
            if s not in gns:
                gns[s] = self.normal_factor(memb[s]) if len(memb) else np.ones(self.n0.shape[0])
            return gns[s]

        # the normal factor is constant in a segment: evaluate the samples of segments of one normal factor
        # together (on a road without zones, all at once: segments also end at the wheel changes and the air
        # brakes' kinks, which change no load)
        groups: dict[bytes, list[int]] = {}
        if len(memb) and memb.shape[2]:
            for s in np.unique(seg_of).tolist():
                groups.setdefault(gn_of(s).tobytes(), []).append(s)
        if len(groups) <= 1:
            ind = self.values(Y, gn_of(int(seg_of[0])))[0]
        else:
            ind = {k: np.empty((nb, len(T))) for k in ROLL_EVENT_KINDS}
            for segs in groups.values():
                cols = np.isin(seg_of, segs)
                part = self.values(Y[:, cols], gn_of(segs[0]))[0]
                for k in ROLL_EVENT_KINDS:
                    ind[k][:, cols] = part[k]
        # each body's first sample of each kind at or past its threshold, in body order, then kind order
        first = []
        for n, kind in enumerate(ROLL_EVENT_KINDS):
            over = ind[kind] >= 0.0
            first += [(i, n, int(np.argmax(over[i]))) for i in np.flatnonzero(over.any(axis=1)).tolist()]
        if not first:
            return []
        first.sort()
        out = []
        names = [b.name for b in model.bodies]
        vehicles = [model.vehicle_of_body(i).name for i in range(nb)]
        for i, n, j in first:
            kind = ROLL_EVENT_KINDS[n]
            t = float(T[j])
            if j > 0:
                t = self._root(i, kind, float(T[j - 1]), t, starts, gn_of, sol)
            out.append(self._event(i, kind, t, starts, gn_of, sol, names, vehicles))
        out.sort(key=lambda e: e.t)
        return out

    def _at(self, t, starts, gn_of, sol):
        s = max(int(np.searchsorted(starts, t, side="right")) - 1, 0)
        y = np.asarray(sol(np.array([t])), dtype=float).reshape(-1, 1)
        return y, gn_of(s)

    def _root(self, i, kind, a, b, starts, gn_of, sol) -> float:
        def f(t):
            y, gn = self._at(t, starts, gn_of, sol)
            return self.indicator(y[:, 0], gn, i, kind)

        fa, fb = f(a), f(b)
        if not (fa < 0.0 <= fb):  # a segment boundary between: the sampled time stands
            return b
        if fb == 0.0:
            return b
        return float(brentq(f, a, b, xtol=ROOT_XTOL))

    def _event(self, i, kind, t, starts, gn_of, sol, names, vehicles) -> RunoutEvent:
        L = self.model.layout
        y, gn = self._at(t, starts, gn_of, sol)
        _, ltr, ay, axle_of = self.indicators(y, gn)
        col = y[:, 0]
        x, yy = float(col[L.x][i]), float(col[L.y][i])
        speed = math.hypot(float(col[L.vx][i]), float(col[L.vy][i]))
        lifting = "left" if ltr[i, 0] > 0 else "right"
        data = {"body": names[i], "ltr": float(ltr[i, 0]), "lateral_acceleration_g": float(ay[i, 0]),
                "threshold_g": float(self.thresholds[i]), "speed_m_s": speed, "x_m": x, "y_m": yy,
                "lifting_side": lifting}
        if kind == "wheel_lift":
            ax = self.axles[int(axle_of[i, 0])] if axle_of[i, 0] >= 0 else None
            data["axle"] = ax.name if ax is not None else ""
            what = f"{lifting} wheel of axle {data['axle']!r} of {names[i]} lifts (axle load transfer ratio 1)"
        elif kind == "unit_lift":
            what = f"all {lifting} wheels of {names[i]} lift (load transfer ratio {ltr[i, 0]:+.3f})"
        else:
            what = (f"{names[i]} passes its rollover threshold {self.thresholds[i]:.3g} g "
                    f"(lateral acceleration {abs(ay[i, 0]):.3g} g)")
        detail = f"{what} at ({x:.2f}, {yy:.2f}) m, {speed:.2f} m/s"
        return RunoutEvent(t, kind, detail, vehicles=(vehicles[i],), data=data, place=(x, yy))


def roll_summary(events, bodies, thresholds) -> dict:
    """A vehicle's rollover verdict from its events: ``{"thresholds_g", "rolled", "rolled_bodies",
    "wheel_lift", "valid_until_s"}`` (``valid_until_s`` None when no wheel lifted and no threshold
    was passed: the planar result is within this check's validity throughout)."""
    roll = [e for e in events if e.kind in ROLL_EVENT_KINDS]
    rolled = sorted({e.data["body"] for e in roll if e.kind in ("unit_lift", "rollover_threshold")})
    lifted = sorted({e.data["body"] for e in roll if e.kind == "wheel_lift"})
    return {"thresholds_g": dict(zip(bodies, [float(t) for t in thresholds])), "rolled": bool(rolled),
            "rolled_bodies": rolled, "wheel_lift_bodies": lifted,
            "valid_until_s": min((e.t for e in roll), default=None)}


def with_events(events: list, extra: list) -> list:
    """``events`` with ``extra`` merged in by time, the run's last (end) event kept last."""
    if not extra:
        return events
    if not events:
        return list(extra)
    out = list(events[:-1])
    for e in extra:  # after every event at the same time or earlier; the others keep their order
        i = len(out)
        while i > 0 and out[i - 1].t > e.t:
            i -= 1
        out.insert(i, e)
    return out + [events[-1]]
