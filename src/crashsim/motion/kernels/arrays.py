"""The named arrays the run-out kernels take, and the layouts of their columns.

The kernels read three bundles, each a namedtuple of arrays (numba compiles namedtuples:
attribute access costs what a tuple index does):

* :class:`KernelModel` ``M``: the scene (built once by :class:`crashsim.motion.scene_model.SceneModel`);
* :class:`Mode` ``D``: the discrete state, changed only at events (:func:`mode_arrays`);
* :class:`Work` ``W``: scratch arrays of one evaluation (:func:`make_work`).

Columns inside the arrays have named indices: ``C_*`` (``cfg``), ``I_*`` (``icfg``), ``P_*``
(``phase_wheels``), ``S_*`` (segment wheel inputs ``sw``), ``W_*`` (``Work.wheel_out``), ``R_*``
(``pair_par``), ``A_*`` (``Mode.pref``); states ``PS_*``, event kinds ``EV_*``, log records
``LOG_*`` and run statuses ``ST_*``.
"""

from __future__ import annotations

from collections import OrderedDict, namedtuple

import numpy as np
from numba import njit

from .jit import JIT

#: The model bundle ``M`` of a scene (SI units; nb bodies, nw wheels, nh hitches, np pairs).
#:
#: * ``body`` (nb, 3): mass [kg], yaw inertia [kg m^2], rest reference length L_ref [m];
#: * ``wheel`` (nw, 3): contact x, y in body axes [m], static load [N]; ``wheel_body`` (nw,) its body;
#: * ``hitch`` (nh, 6): front pin x, y (front body axes), rear pin x, y (rear body axes) [m],
#:   articulation limit [rad] (NaN: none), yaw lock (1.0: the joint is locked in yaw at zero
#:   articulation, a C-dolly; read only when ``icfg[I_YAWLOCK]`` is set); ``hitch_body`` (nh, 2)
#:   front and rear body index;
#: * ``load_transfer`` (nw, 2 nb): load-transfer matrix [N per m/s^2] on the filtered
#:   body-axes accelerations; ``inv_mass`` (3 nb,): inverse masses [1/kg] and inertias
#:   [1/(kg m^2)] in z order (x.., y.., psi..);
#: * ``phase_times`` (P,) [s], ``phase_wheels`` (P, nw, N_P): wheel-setting phases (``P_*`` columns): a
#:   phase starts at each scheduled change and at each kink of the air brakes' ramps (a kink's phase
#:   keeps the settings; only the piece of the ramp changes), so that no phase holds a kink;
#: * ``zone_mu`` (nz,), ``zone_ptr`` (nz + 1,), ``zone_edges`` (ne, 5: start x, y, edge x, y,
#:   1/|edge|^2 [m, 1/m^2]), ``zone_box`` (nz, 4: xmin, ymin, xmax, ymax [m]): friction zones
#:   (:func:`crashsim.motion.road._edges`);
#: * ``cfg`` (N_CFG,) float options (``C_*``), ``icfg`` (N_ICFG,) int options (``I_*``);
#: * ``tab_a, tab_b, tab_c, tab_e, tab_p``: the explicit RK scheme's tableau (solve_ivp's A, B, C, E, P);
#: * ``body_vehicle`` (nb,): the vehicle of each body;
#: * contact pieces (convex): ``piece_body`` (npc,) the body, -1 for a fixed obstacle in world
#:   coordinates; vertices ``piece_verts[piece_ptr[i]:piece_ptr[i+1]]`` [m] counter-clockwise,
#:   with the outward unit normal ``piece_normals`` of the edge from each vertex to the next;
#:   ``piece_info`` (npc, 4): centre x, y and radius of a bounding circle, thickness [m];
#: * pairs: ``pair_body`` (np, 2) bodies A and B (B = -1: an obstacle); piece pairs
#:   ``piece_pairs[pair_ptr[p]:pair_ptr[p+1]]`` (rows: piece of A, piece of B);
#:   ``pair_par`` (np, N_R) parameters (``R_*`` columns);
#: * slope (read only when ``icfg[I_SLOPE]`` is set): ``zone_slope`` (nz, 3) the in-plane gravity
#:   x, y [m/s^2] and the normal factor inside each zone (the road's in ``cfg[C_GX, C_GY, C_GN]``;
#:   :func:`crashsim.motion.road.slope_gravity`); ``wheel_mass`` (nw,) the mass [kg] of its body
#:   that a wheel carries in the in-plane gravity (its share of the body's static wheel loads);
#: * air brakes (read only when ``icfg[I_BRAKE]`` is set): ``wheel_brake`` (nw, N_B) per wheel
#:   (``B_*`` columns: has air brakes, t_on, rise, t_off, fall [s], brake force at full application
#:   [N], ABS efficiency; :meth:`crashsim.motion.wheels.ResolvedWheels.brake_rows`); the clock
#:   (time [s]) is then the state's entry ``icfg[I_CLOCK]``;
#: * contact height (read only with load transfer, ``icfg[I_LT]``, in scenes with contact pairs):
#:   ``contact_lever`` (nb,) the height of the body's contact forces over its CG height, ``h_c / h``
#:   [-] (1: at the CG, the default; :func:`crashsim.motion.kernels.equations.specific_force`).
KernelModel = namedtuple("KernelModel", [
    "body", "wheel", "wheel_body", "hitch", "load_transfer", "inv_mass", "phase_times", "phase_wheels",
    "zone_mu", "zone_ptr", "zone_edges", "cfg", "icfg", "tab_a", "tab_b", "tab_c", "tab_e", "tab_p",
    "zone_box", "body_vehicle", "hitch_body", "piece_body", "piece_ptr", "piece_verts", "piece_normals",
    "piece_info", "pair_body", "pair_ptr", "piece_pairs", "pair_par", "zone_slope", "wheel_mass", "wheel_brake",
    "contact_lever"])

#: The mode ``D`` (the discrete state of a segment, changed in place at events):
#:
#: * ``memb`` (nw, nz) bool: zone membership of every wheel;
#: * ``lk_j`` (max(nh, 1),) int, ``lk_th`` (max(nh, 1),) [rad], ``lk_n`` (1,) int: the closed
#:   articulation stops (hitch, locked angle) and their count;
#: * ``shift`` (max(nh, 1),) [rad]: raised thresholds of stops that were left;
#: * ``pstate`` (np,) int: contact state of every pair (``PS_*``); ``pref`` (np, N_A): its
#:   crush allowance (``A_*``: a flag and the poses of its bodies when the run-out started);
#: * ``parked`` (nv,) int: 1 for a vehicle at rest (its bodies frozen).
Mode = namedtuple("Mode", ["memb", "lk_j", "lk_th", "lk_n", "shift", "pstate", "pref", "parked"])

#: Work arrays ``W`` of one evaluation (:func:`crashsim.motion.kernels.equations.evaluate` fills them):
#:
#: * ``wheel_out`` (nw, N_W): per-wheel wheel-axes velocity [m/s], force [N], sliding flag, load [N], and
#:   the margins of its switches [N] (``W_MSAT`` ..: where the force law's slope jumps; written only by
#:   ``tyre_eval(..., margins=True)``, for a rejected step);
#: * ``body_force`` (3 nb,): world-frame force and moment sums per body (z order) [N, N m];
#: * ``jacobian`` (m_max, 3 nb), ``gram`` (m_max, m_max): constraint Jacobian G and G M^-1 G^T;
#: * ``multipliers`` (m_max,): hitch forces on the front body [N], then stop moments [N m];
#: * ``trig`` (2, nb): cos and sin of the body headings;
#: * ``pair_power`` (np,): power of each pair's contact forces on the bodies [W];
#: * ``contact_pts`` (2 x the most vertices of a piece, N_Q): scratch for the contact points of two pieces
#:   (:func:`crashsim.motion.kernels.contacts.piece_points`, ``Q_*`` columns);
#: * ``contact_force`` (2 nb,): the contacts' share of ``body_force``, world-frame x.., y.. [N]
#:   (written only in scenes with contact pairs; the load transfer reads it).
Work = namedtuple("Work", ["wheel_out", "body_force", "jacobian", "gram", "multipliers", "trig", "pair_power",
                           "contact_pts", "contact_force"])

#: The modes of a run's stored segments, stacked (segment first), for the post-processing
#: kernels: ``phase`` (ns,) wheel-setting phase, ``nlk`` (ns,) the number of closed stops, and
#: the :class:`Mode` fields ``memb, lk_j, lk_th, pstate, pref, parked`` with a leading segment axis.
Segments = namedtuple("Segments", ["phase", "memb", "nlk", "lk_j", "lk_th", "pstate", "pref", "parked"])

#: The events of a segment (:func:`crashsim.motion.kernels.events.build_events`), one entry
#: per event: ``kind`` (``EV_*``), ``idx`` (the vehicle, zone, hitch, closed stop or pair it
#: belongs to), ``val`` (its threshold: a stop angle [rad], a release side, a press depth [m])
#: and ``dir`` (the direction of the zero crossing that fires it: +1 rising, -1 falling).
Events = namedtuple("Events", ["kind", "idx", "val", "dir"])

#: Values and rate bounds of a segment's events at the start (``g_old``, ``r_old``) and the end
#: (``g_new``, ``r_new``) of a step (units of each event's value, and per second).
EventValues = namedtuple("EventValues", ["g_old", "g_new", "r_old", "r_new"])

#: One accepted step of the compiled engine as its dense output sees it: start time ``t_old``
#: [s], size ``h`` [s], start state ``y_old`` (n,), dense-output matrix ``Q`` (n, degree), and
#: ``ytmp`` (n,) scratch for interpolated states (:func:`crashsim.motion.kernels.events.interpolate`).
Step = namedtuple("Step", ["t_old", "h", "y_old", "Q", "ytmp"])

# ----------------------------------------------------------------------------- array layouts
# cfg (float options)
(C_EPS, C_ALPHA2, C_BETA2, C_TAU, C_VSTOP, C_RTOL, C_ATOL, C_MAXSTEP, C_FIRST, C_TMAX, C_SDT, C_ROADMU,
 C_ZRES, C_GX, C_GY, C_GN) = range(16)
N_CFG = 16
# icfg (int options); I_SLOPE: 1 where any part of the road is not level; I_CASTOR: 1 where any
# wheel is self-steering in any phase; I_YAWLOCK: the number of yaw-locked hitches (C-dollies);
# I_BRAKE: 1 where any wheel has air brakes, and I_CLOCK the index of the clock (time [s]) in the state then
I_FIALA, I_LT, I_MAXSEG, I_ORDER, I_NSTAGES, I_MAXEVAL, I_SLOPE, I_CASTOR, I_YAWLOCK, I_BRAKE, I_CLOCK = range(11)
N_ICFG = 11
# phase_wheels columns (per phase and wheel); P_CASTOR: the steer-angle limit of a self-steering
# wheel [rad], -1 for a wheel that does not steer by itself
P_MUF, P_BRAKE, P_FROLL, P_CFIX, P_CCOEF, P_CD, P_SD, P_LOCKED, P_CASTOR = range(9)
N_P = 9
# segment wheel columns (sw); S_N0: the static load on the road's slope [N]; S_GX, S_GY: the
# in-plane gravity force the wheel's share of its body's mass carries, world frame [N]; S_CASTOR as P_CASTOR;
# S_AIR: 1 where the wheel's brake force comes from the air brakes in this segment (a rolling wheel of a
# braked unit); S_BREF, S_BBASE, S_BSLOPE: the piece of the brake's ramp in force in the segment, its
# application level ``S_BBASE + S_BSLOPE (clock - S_BREF)`` (reference time [s], level, level per second;
# :func:`crashsim.motion.kernels.tyres.brake_piece`)
(S_MU, S_MULOAD, S_DEMAND, S_CALPHA, S_DCOEF, S_CFIX, S_CCOEF, S_CD, S_SD, S_LOCKED, S_N0, S_GX, S_GY, S_CASTOR, S_AIR,
 S_BREF, S_BBASE, S_BSLOPE) = range(18)
N_S = 18
# air-brake columns (wheel_brake): has air brakes (1/0), brakes start building [s], rise time [s],
# release starts [s] (inf: held), fall time [s], brake force at full application [N], ABS efficiency (0: none)
B_HAS, B_ON, B_RISE, B_OFF, B_FALL, B_FORCE, B_ABS = range(7)
N_B = 7
# per-wheel outputs of an evaluation (Work.wheel_out); then the margins of the wheel's switches [N], each
# >= 0 on its far side, NaN where the switch does not apply (crashsim.motion.kernels.tyres.tyre_eval): the
# lateral demand's saturation, the lock-up of a braked rolling wheel, the ABS limit, the wheel's lift
W_U, W_V, W_FX, W_FY, W_SLIDE, W_LOAD, W_MSAT, W_MLOCK, W_MABS, W_MLIFT = range(10)
N_W = 10
#: The margin columns of ``Work.wheel_out`` (first and end).
W_M0, W_M1 = W_MSAT, W_MLIFT + 1
# pair parameters (pair_par columns): contact stiffness [N/m], damping [N s/m], contact friction,
# arming distance [m], impulse threshold [m/s], event resolution [m], and the contact's natural
# frequency sqrt(k / m_eff) [1/s] (m_eff the pair's reduced mass: the closing speed a point pressed e
# deep is held at, omega e, counts against its strike, crashsim.motion.kernels.contacts.strike_scan)
R_K, R_C, R_MU, R_ARM, R_VTHR, R_RES, R_OMEGA = range(7)
N_R = 7
# pair states
PS_DISARMED, PS_ARMED, PS_CONTACT = 0, 1, 2
# pair allowance columns (D.pref, one row per pair): whether the pair has a crush allowance (1.0: its
# outlines overlapped or lay within the arming distance at the start of the run-out, the crush of the first
# impact), and the poses of its
# bodies A and B at that start (x, y [m], heading [rad]; B's unused for an obstacle): a point of one body
# that lay inside the other then is crushed material, allowed as deep as it lay
# (:func:`crashsim.motion.kernels.contacts.crush_allowance`)
A_CRUSH, A_XA, A_YA, A_PA, A_XB, A_YB, A_PB = range(7)
N_A = 7
# A_CRUSH of a pair pressed on beyond its crush at this instant (its allowance just set there): an impact
# solved now is the first impact's crush going on, e = 0 at its points (crashsim.motion.impacts)
PRESSED = 2.0
# contact point columns (Work.contact_pts rows, crashsim.motion.kernels.contacts.piece_points): world x, y [m],
# the normal from B into A, the depth beyond the allowance [m], the allowance [m], and 1.0 for a point of the
# crush of the first impact (its material point lay inside the other piece at the start, or within
# CRUSH_REACH of it)
Q_X, Q_Y, Q_NX, Q_NY, Q_DEPTH, Q_ALLOW, Q_CRUSH = range(7)
N_Q = 7
# Reach of the crush of the first impact [m]: a point of a disarmed pair whose material point lay inside the
# other body at the start of the run-out, or within this distance of it, is the first impact's crush (pressing
# on is sustained contact, not a new impact); points farther away meet the other body anew (a strike counts
# from the surface)
CRUSH_REACH = 0.5
# Depth [m] over which the damper of a sustained contact takes hold: its force is
# c x rate x min(1, depth / DAMPER_DEPTH), so a slow touch starts from zero force (no jump of c x rate at
# the surface, as a Hunt-Crossley damper proportional to the depth gives) and bodies resting a few
# millimetres deep are damped at the pair's ratio
DAMPER_DEPTH = 2e-3
# Points of every pair within this distance of touching [m] take part in a simultaneous impact
# (:func:`crashsim.motion.kernels.contacts.contact_rows`): the touching points the event is located on
# lie within round-off of the surface, and pressed points within the depth sustained contact allows
ROW_MARGIN = 1e-3
# event kinds of a segment
EV_REST, EV_ZONE, EV_STOP, EV_RELEASE, EV_GAP, EV_ARM, EV_PRESS, EV_STRIKE = range(8)
# log record kinds
(LOG_ZONE_ENTER, LOG_ZONE_EXIT, LOG_SCHEDULE, LOG_STOP_CLOSED, LOG_STOP_IMPACT, LOG_STOP_OPEN, LOG_REST,
 LOG_ARMED, LOG_CONTACT, LOG_PRESS, LOG_CONTACT_END) = range(11)
# run status
(ST_REST, ST_TIME_LIMIT, ST_MAX_SEGMENTS, ST_STEP_TOO_SMALL, ST_NONFINITE, ST_MAX_EVAL, ST_WALL_TIME,
 ST_NO_PROGRESS, ST_IMPACT) = range(9)
# zone-crossing tolerances: identical in both engines (they run this code)
ZONE_TOL = 1e-9
ZONE_OVERSHOOT = 1e-10
# The wall clock is read every this many solver steps.
WALL_CHECK_STEPS = 256
# Largest number of points at which one step's dense output is searched for a feature the
# step could have passed through (zones, contact gaps).
MAX_SUBSAMPLES = 512
# solve_ivp's step-size controller constants (scipy.integrate._ivp.rk)
SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
EPS = np.finfo(float).eps



def mode_arrays(nw, nz, nh, npairs, nv):
    """A fresh mode ``D`` (:class:`Mode`; Python helper)."""
    return Mode(np.zeros((nw, nz), np.bool_), np.zeros(max(nh, 1), np.int64), np.zeros(max(nh, 1)),
                np.zeros(1, np.int64), np.zeros(max(nh, 1)), np.zeros(npairs, np.int64), np.zeros((npairs, N_A)),
                np.zeros(nv, np.int64))


@njit(**JIT)
def make_work(M):
    """Work arrays of one evaluation (:class:`Work`)."""
    nb = M.body.shape[0]
    nw = M.wheel.shape[0]
    nh = M.hitch.shape[0]
    mmax = max(3 * nh, 1)
    nv = 1
    for i in range(M.piece_ptr.shape[0] - 1):
        nv = max(nv, M.piece_ptr[i + 1] - M.piece_ptr[i])
    return Work(
        np.zeros((nw, N_W)),
        np.zeros(3 * nb),
        np.zeros((mmax, 3 * nb)),
        np.zeros((mmax, mmax)),
        np.zeros(mmax),
        np.zeros((2, nb)),
        np.zeros(M.pair_body.shape[0]),
        np.zeros((2 * nv, N_Q)),
        np.zeros(2 * nb),
    )


# ----------------------------------------------------------------------------- fast dispatch
def _remember_types(*classes, size=64):
    """Type the bundles passed from Python once per bundle object, not at every call.

    numba types a namedtuple argument in Python, array by array, at every call (a plain tuple
    it types in C): about 2 us per call for the 30 arrays of a :class:`KernelModel`, which the
    SciPy engine pays at every right-hand-side evaluation.  A bundle is immutable and its
    arrays keep their dtype, dimensions, layout and flags, so its numba type is remembered
    for the last ``size`` bundle objects (held, so an id is not reused while remembered).
    Uses numba's typeof registry; without it numba's own typing stays in force.
    """
    try:
        from numba.core import types
        from numba.core.typing.typeof import typeof_impl
    except ImportError:  # pragma: no cover - numba internals moved
        return
    known = OrderedDict()

    def typeof_bundle(val, c):
        key = (id(val), c.purpose)
        hit = known.get(key)
        if hit is not None and hit[0] is val:
            return hit[1]
        tys = [typeof_impl(v, c) for v in val]
        if any(t is None for t in tys):
            return None
        ty = types.BaseTuple.from_types(tys, type(val))
        known[key] = (val, ty)
        if len(known) > size:
            known.popitem(last=False)
        return ty

    for cls in classes:
        typeof_impl.register(cls)(typeof_bundle)


_remember_types(KernelModel, Mode, Segments)
