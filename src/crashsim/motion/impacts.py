"""The impacts of the run-out: every point touching at the instant of a strike, solved at once.

When a point of two bodies (or a body and an obstacle) closes at the impulse threshold or faster
(a touch at speed, a strike of a pair in contact, a point left striking by an articulation stop
closing), the integration stops and this module solves the impact of the whole instant:

1. **The points.**  Every contact point within :data:`~crashsim.motion.kernels.ROW_MARGIN` of
   touching, beyond its allowance, of every pair in contact or disarmed, and of every armed pair that
   touches (:func:`crashsim.motion.kernels.contact_rows`): a car pinned between a prime mover and a
   parked van is two pairs, both in the solve.  A point of the first impact's crush going on takes
   part with e = 0 (plastic: a point of the crush of a pair still disarmed, or one pressed in when
   its pair was pressed on beyond the crush at this very instant); every other point with its pair's
   e and f.
2. **The bodies**: every body of the vehicles those points belong to, with their hitches as pins
   that hold and their closed articulation stops as one-sided rows (a plastic stop).
3. **The solve**: :func:`crashsim.impact.multicontact.solve_contacts` (a complementarity problem,
   Lemke's method; with one point it is Brach's impact with the friction law and no moment impulse),
   in rounds: the points that strike (closing at their pair's threshold or faster, plus ``omega e``
   for a point already pressed ``e`` deep, the kernels' strike measure), then the points those drove
   in that fast, then every point at once.
4. **After it**: the velocities jump; every pair that took an impulse, or touched, is in sustained
   contact (a disarmed pair struck at fresh material too; its crush allowance is kept); a closed stop
   whose bodies now turn away from it opens; the vehicles move again.

No point then closes at the threshold (each leaves at e times its approach speed or more), so an
instant is solved once: the sequential impulses that chattered through a tangle one pair after
another (43 impacts in one scene) are one event.  And a point driven in slowly while in contact
deepens its contact force instead of striking again (the strike measure), so a car pinned between
two vehicles and forced along a turning side is pressed, not struck every few milliseconds.
"""

from __future__ import annotations

import math

import numpy as np

from ..impact.multicontact import solve_contacts
from ..impact.result import BodyImpact, pdof_from_force
from .layout import SV_X, SV_Y, SV_HEADING, SV_VX, SV_VY, SV_YAW_RATE
from .result import RunoutEvent
from .scene_result import PairImpulse, SecondaryImpact
from .scene_model import SceneModel, kernels

__all__ = ["IMPACT_EVENT_WINDOW", "impact_instant", "event_number"]

#: An impulse below this [N s] counts as none (round-off of the pivoting).
_NO_IMPULSE = 1e-9
#: Instants within this time [s] of an event's first instant that involve one of its pairs belong to that
#: event (the bounces of one collision: a crash pulse lasts some 0.1 s); reports and figures number events.
IMPACT_EVENT_WINDOW = 0.05


def event_number(previous, t: float, pairs) -> int:
    """The event number of an instant at ``t`` whose pairs (names ``"a|b"``) took impulses, after the
    records ``previous``: the last event's if it began at most :data:`IMPACT_EVENT_WINDOW` before and
    shares a pair, else the next (2 for the first after the first impact)."""
    if not previous:
        return 2
    last = previous[-1].event
    mine = [r for r in previous if r.event == last]
    if t - mine[0].t <= IMPACT_EVENT_WINDOW and set(pairs) & {f"{r.body1}|{r.body2}" for r in mine}:
        return last
    return last + 1


def _rows(model: SceneModel, y: np.ndarray, D) -> np.ndarray:
    k = kernels()
    M = model.M
    most = int(np.max(np.diff(M.piece_ptr))) if len(M.piece_ptr) > 1 else 1
    out = np.zeros((2 * most * max(len(M.piece_pairs), 1), 1 + k.N_Q))
    n = int(k.contact_rows(y, model.M, D, out))
    return out[:n]


def _body_impacts(model: SceneModel, y: np.ndarray, pair, bodies: list, cols: list, nd: int, dz: np.ndarray,
                  v_before: dict, force: np.ndarray, ia: int, ib: int) -> tuple[dict, dict]:
    """The velocity change and the :class:`~crashsim.impact.result.BodyImpact` of each body of a pair's
    vehicles (``bodies``, their columns ``cols`` of the instant's ``nd`` bodies; ``dz`` the pair's share of
    the velocity change, ``force`` its impulse on body ``ia``), and of the obstacle struck, if one is:
    ``(delta_v, impacts)`` by body name."""
    names = model.layout.bodies
    nb = model.n_bodies
    delta_v, impacts = {}, {}
    for b, j in zip(bodies, cols):
        dv = (float(dz[j]), float(dz[nd + j]))
        delta_v[names[b]] = dv
        vb = v_before[names[b]]
        crush = force if b == ia else (-force if b == ib else None)
        heading = float(y[SV_HEADING * nb + b])
        mass = float(model.mass[b])
        va, vz = np.array(vb[:2]), np.array([y[SV_VX * nb + b], y[SV_VY * nb + b]])
        impacts[names[b]] = BodyImpact(
            name=names[b], vehicle=model.vehicle_of_body(b).name, heading=heading, velocity_before=va,
            velocity=vz, yaw_rate_before=vb[2], yaw_rate=float(y[SV_YAW_RATE * nb + b]), delta_v=np.array(dv),
            crush_impulse=crush, pdof=None if crush is None else pdof_from_force(crush, heading),
            ke_before=0.5 * mass * float(va @ va) + 0.5 * float(model.inertia[b]) * vb[2] ** 2,
            ke_after=0.5 * mass * float(vz @ vz) + 0.5 * float(model.inertia[b]) * float(y[SV_YAW_RATE * nb + b]) ** 2,
            mass=mass)
    if pair.obstacle:
        impacts[pair.b] = BodyImpact(name=pair.b, vehicle=pair.b, heading=0.0, velocity_before=np.zeros(2),
                                     velocity=np.zeros(2), yaw_rate_before=0.0, yaw_rate=0.0,
                                     delta_v=np.zeros(2), crush_impulse=-force,
                                     pdof=pdof_from_force(-force, 0.0), ke_before=0.0, ke_after=0.0,
                                     mass=math.inf, fixed=True)
    return delta_v, impacts


def _point_rows(model: SceneModel, rows: np.ndarray, pair_of: np.ndarray, y: np.ndarray, D, col: dict):
    """The complementarity problem's rows of an instant's touching points: the normal and tangential
    Jacobians over the velocities of the bodies in ``col`` (a body's column), and each point's restitution,
    friction and strike threshold. Returns ``(Jn, Jt, e, f, strike)``."""
    k = kernels()
    M = model.M
    nb = model.n_bodies
    nd = len(col)
    nc = rows.shape[0]
    Jn, Jt = np.zeros((nc, 3 * nd)), np.zeros((nc, 3 * nd))
    e, f, strike = np.zeros(nc), np.zeros(nc), np.zeros(nc)
    for r in range(nc):
        p = pair_of[r]
        px, py, nx, ny = rows[r, 1:5]
        tx, ty = -ny, nx
        for b, sign in ((M.pair_body[p, 0], 1.0), (M.pair_body[p, 1], -1.0)):
            if b < 0:
                continue
            j = col[int(b)]
            rx, ry = px - y[SV_X * nb + b], py - y[SV_Y * nb + b]
            Jn[r, j], Jn[r, nd + j], Jn[r, 2 * nd + j] = sign * nx, sign * ny, sign * (rx * ny - ry * nx)
            Jt[r, j], Jt[r, nd + j], Jt[r, 2 * nd + j] = sign * tx, sign * ty, sign * (rx * ty - ry * tx)
        c = model.pairs[p].contact
        # the crush of the first impact going on is plastic: the points of its crush while the pair is
        # disarmed, and those pressed in when it was pressed on beyond the crush at this instant
        crush = ((D.pstate[p] == k.PS_DISARMED and rows[r, 1 + k.Q_CRUSH] != 0.0)
                 or (D.pref[p, k.A_CRUSH] == k.PRESSED and rows[r, 1 + k.Q_ALLOW] > 0.0))
        e[r] = 0.0 if crush else c.restitution
        f[r] = c.friction
        # a point pressed in strikes faster by the speed its depth holds (kernels' strike_scan)
        strike[r] = c.velocity_threshold + M.pair_par[p, k.R_OMEGA] * max(rows[r, 1 + k.Q_DEPTH], 0.0)
    return Jn, Jt, e, f, strike


def impact_instant(model: SceneModel, t: float, y: np.ndarray, trigger: np.ndarray, D, offsets: np.ndarray,
                   log: list, previous=()) -> list[SecondaryImpact]:
    """Solve the impact of the instant ``t`` (module docstring); update ``y`` and the mode ``D`` in place.

    ``trigger`` is the kernels' strike geometry ``(pair, x, y, nx, ny, u_n)`` of the point that
    stopped the integration.  Appends the run-out events (one ``impact`` per pair that took an impulse,
    then ``stop_open`` for each stop it opened) to ``log``; returns the pairs' records, numbered by
    :func:`event_number` after the run's ``previous`` records.
    """
    k = kernels()
    M = model.M
    L = model.layout
    names = L.bodies
    nb = model.n_bodies
    rows = _rows(model, y, D)
    if rows.shape[0] == 0:  # pragma: no cover - the trigger's own point is within the margin
        p = int(trigger[0])
        rows = np.zeros((1, 1 + k.N_Q))
        rows[0, :5] = p, trigger[1], trigger[2], trigger[3], trigger[4]
    pair_of = rows[:, 0].astype(np.int64)
    # the vehicles of the points, and every body of them
    veh = sorted({int(M.body_vehicle[b]) for p in set(pair_of.tolist()) for b in M.pair_body[p] if b >= 0})
    bodies = [i for i in range(nb) if int(M.body_vehicle[i]) in veh]
    col = {b: j for j, b in enumerate(bodies)}
    nd = len(bodies)
    dof = np.concatenate([np.array(bodies) + c * nb for c in range(3)])  # z order: vx.., vy.., w..
    minv = M.inv_mass[dof]
    u = y[SV_VX * nb:(SV_YAW_RATE + 1) * nb][dof].copy()
    G_all = k.hitch_jacobian(np.ascontiguousarray(y), M)
    keep = np.any(G_all[:, dof] != 0.0, axis=1)
    G = G_all[keep][:, dof]
    Jn, Jt, e, f, strike = _point_rows(model, rows, pair_of, y, D, col)
    # closed stops of these vehicles: the relative yaw rate may not go further past them
    stops = [q for q in range(int(D.lk_n[0])) if int(M.body_vehicle[M.hitch_body[D.lk_j[q], 0]]) in veh]
    Js = np.zeros((len(stops), 3 * nd))
    for r, q in enumerate(stops):
        j = int(D.lk_j[q])
        side = 1.0 if D.lk_th[q] - offsets[j] > 0.0 else -1.0
        Js[r, 2 * nd + col[int(M.hitch_body[j, 0])]] = -side
        Js[r, 2 * nd + col[int(M.hitch_body[j, 1])]] = side
    sol = solve_contacts(minv, G, Jn, Jt, Js, u, e, f, strike)
    for p in set(pair_of.tolist()):  # the press is behind these pairs now
        if D.pref[p, k.A_CRUSH] == k.PRESSED:
            D.pref[p, k.A_CRUSH] = 1.0
    ke_before = model.kinetic_energy(y)
    v_before = {names[b]: (float(y[SV_VX * nb + b]), float(y[SV_VY * nb + b]), float(y[SV_YAW_RATE * nb + b])) for b in bodies}
    y[SV_VX * nb:(SV_YAW_RATE + 1) * nb][dof] = sol.velocity
    loss_total = ke_before - model.kinetic_energy(y)
    # closed stops the impact turns away from open (from the last, so the indices hold)
    opened = []
    ws = Js @ sol.velocity
    for r in reversed(range(len(stops))):
        if sol.stop[r] <= _NO_IMPULSE and ws[r] > 0.0:
            opened.append(int(k.release_stop(y, M, D, offsets, stops[r])))
    # the pairs: contact from now on; their records
    P = sol.inverse_mass  # the constrained inverse the impulses acted through
    records = []
    warning = ""
    if sol.law != "friction":
        why = "; ".join(f"{law}: {what}" for law, what in sol.attempts)
        warning = (f"Newton's restitution with the pairs' e and f would have made energy for this geometry ({why}); "
                   f"solved {'with e = 0' if sol.law == 'plastic' else 'frictionless with e = 0'} instead")
    shares = {}
    for p in sorted(set(pair_of.tolist())):
        mine = pair_of == p
        ln, lt = sol.normal[mine], sol.tangential[mine]
        if D.pstate[p] == k.PS_ARMED:
            D.pstate[p] = k.PS_CONTACT
            D.pref[p, :] = 0.0
        elif D.pstate[p] == k.PS_DISARMED and np.any((ln > _NO_IMPULSE) & (rows[mine, 1 + k.Q_CRUSH] == 0.0)):
            D.pstate[p] = k.PS_CONTACT  # struck at fresh material: a strike anywhere from now on (crush kept)
        if float(np.sum(ln)) <= _NO_IMPULSE:
            continue
        shares[p] = float(np.sum(sol.work[mine]))
    if shares:  # what no point booked (a closed stop's reaction, the hitch-consistency projection, round-off)
        top = max(shares, key=lambda p: float(np.sum(sol.normal[pair_of == p])))
        shares[top] += loss_total - sum(shares.values())
    event = event_number(previous, t, [model.pairs[p].name for p in shares])
    for p in shares:
        mine = pair_of == p
        ln, lt = sol.normal[mine], sol.tangential[mine]
        pair = model.pairs[p]
        pts, nrm = rows[mine, 1:3], rows[mine, 3:5]
        wgt = ln / float(np.sum(ln))
        point = wgt @ pts
        normal = wgt @ nrm
        normal = normal / max(float(np.hypot(*normal)), 1e-300)
        dz = P @ (Jn[mine].T @ ln + Jt[mine].T @ lt)
        ia = int(M.pair_body[p, 0])
        ib = int(M.pair_body[p, 1])
        vehs = {int(M.body_vehicle[ia])} | ({int(M.body_vehicle[ib])} if ib >= 0 else set())
        force = np.array([float(ln @ nrm[:, 0] + lt @ -nrm[:, 1]), float(ln @ nrm[:, 1] + lt @ nrm[:, 0])])
        theirs = [b for b in bodies if int(M.body_vehicle[b]) in vehs]  # the bodies of the pair's vehicles
        delta_v, impacts = _body_impacts(model, y, pair, theirs, [col[b] for b in theirs], nd, dz, v_before, force,
                                         ia, ib)
        closing = float(np.max(-(Jn[mine] @ u)))
        loss = shares[p]
        slip = Jt[mine] @ sol.velocity
        result = PairImpulse(pair.a, pair.b, float(np.sum(ln)), float(np.sum(lt)), impacts,
                             float(np.sum(sol.work_normal[mine])), float(np.sum(sol.work_tangential[mine])),
                             {"system": {"before": ke_before, "after": ke_before - loss}},
                             sliding=bool(np.any(np.abs(slip[ln > _NO_IMPULSE]) > 1e-9 * (1.0 + np.max(np.abs(u))))),
                             closing_velocity=float(wgt @ (Jn[mine] @ u)),
                             separation_normal_velocity=float(wgt @ (Jn[mine] @ sol.velocity)),
                             separation_tangential_velocity=float(wgt @ slip))
        c = pair.contact
        # the e its points took: 0 at points of the crush of the first impact (all of the pair's: 0)
        law_e = c.restitution if sol.law == "friction" and np.any(e[mine] > 0.0) else 0.0
        law_f = 0.0 if sol.law == "frictionless" else c.friction
        rec = SecondaryImpact(t=t, body1=pair.a, body2=pair.b, point=np.asarray(point, float),
                              normal=np.asarray(normal, float), closing_speed=closing,
                              normal_impulse=result.normal_impulse, tangential_impulse=result.tangential_impulse,
                              energy_loss=float(loss), delta_v=delta_v, law=sol.law, restitution=law_e,
                              friction=law_f, result=result, warning=warning, event=event, points=int(np.sum(mine)))
        records.append(rec)
        dv = ", ".join(f"{n} {math.hypot(*d):.3g} m/s" for n, d in delta_v.items() if n in (pair.a, pair.b))
        how = (f"{pair.a} strikes {pair.b} at {closing:.3g} m/s" if closing >= 0.0 else
               f"{pair.a} is pushed against {pair.b} (parting at {-closing:.3g} m/s before)")
        # with several pairs at once a pair's share of the loss can be of either sign: the instant's is given
        lost = (f"impact {event}: {loss:.4g} J lost" if len(shares) == 1 else
                f"impact {event}: {len(shares)} pairs at once, {loss_total:.4g} J lost in all")
        log.append(RunoutEvent(
            t, "impact", f"{how}: normal impulse {rec.normal_impulse:.4g} N s, delta-v {dv}, {lost}"
                         + (f" ({warning})" if warning else ""),
            float(loss), tuple(model.vehicles[v].name for v in sorted(vehs)),
            {"pair": pair.name, "speed_m_s": closing, "normal_impulse_N_s": rec.normal_impulse,
             "delta_v_m_s": {n: math.hypot(*d) for n, d in delta_v.items() if n in (pair.a, pair.b)},
             "energy_J": float(loss), "bodies": [pair.a, pair.b], "event": event, "pairs_at_once": len(shares),
             "instant_energy_J": float(loss_total)},
            place=(float(point[0]), float(point[1]))))
    for v in veh:
        D.parked[v] = 0
    for j in opened:
        front, rear = model.hitch_names[j]
        log.append(RunoutEvent(t, "stop_open", f"articulation stop of hitch {front}-{rear} opens", 0.0,
                               (model.vehicle_of_body(int(M.hitch_body[j, 0])).name,), {"hitch": f"{front}-{rear}"}))
    return records

