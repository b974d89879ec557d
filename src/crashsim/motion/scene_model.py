"""A scene compiled into the arrays the run-out kernels take (:mod:`crashsim.motion.kernels`).

:class:`SceneModel` holds every movable vehicle of a scene in one state vector (bodies in
vehicle order, :class:`~crashsim.motion.layout.StateLayout`), their wheels, hitches, static
loads and wheel-setting phases, the road, the options, and the contact geometry (the bodies'
outlines, fixed obstacles, and the pairs that can touch).  Both engines integrate the same
bundle; nothing here is engine-specific.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np
from scipy.integrate import RK23, RK45

from ..errors import ScenarioError
from ..vehicles import BodyState, Vehicle
from . import kernels as kernel_package
from .contact import ContactModel, Obstacle, convex_pieces, piece_thickness
from .layout import StateLayout
from .loads import StaticLoads, load_transfer_matrix, static_loads
from .options import RunoutOptions
from .road import Road, slope_gravity
from .wheels import ResolvedWheels, WheelSettings, WheelSpec

__all__ = ["SceneModel", "Pair", "contact_levers", "kernels", "reference_lengths"]

# Minimum rest reference length [m] (|yaw rate| * L_ref is compared with v_stop).
_MIN_L_REF = 0.5

#: Explicit RK schemes of the compiled engine: solve_ivp's tableaux (A, B, C, E, P).
SCHEMES = {"dopri5": RK45, "bs3": RK23}
#: Finest zone feature [m] a step is searched for (a corner clipped less deeply may be missed).
ZONE_RESOLUTION = 0.02
#: Finest contact feature [m]: at most this, and at most a quarter of the thinner piece.
CONTACT_RESOLUTION = 0.05


def reference_lengths(vehicle: Vehicle, specs) -> np.ndarray:
    """Rest reference length L_ref of every body [m]: half its length, else its farthest contact (>= 0.5 m).

    Parameters
    ----------
    vehicle : Vehicle
    specs : sequence of WheelSpec
        The vehicle's contacts (:func:`~crashsim.motion.wheels.enumerate_wheels`).

    Returns
    -------
    ndarray, shape (n_bodies,)
    """
    out = []
    for i, body in enumerate(vehicle.bodies):
        if body.length is not None:
            out.append(max(body.length / 2, _MIN_L_REF))
        else:
            reach = [math.hypot(*s.position) for s in specs if s.body_index == i]
            out.append(max(max(reach, default=0.0), _MIN_L_REF))
    return np.array(out, dtype=float)


def contact_levers(bodies, load_transfer: bool) -> np.ndarray:
    """Per body, the height of its contact forces over its CG height, ``h_c / h`` (nb,) [-].

    ``contact_height`` over ``cg_height`` where a body gives both, else 1 (contact forces at the CG's
    height, the default); all 1 without load transfer (not read then).  The load transfer takes a
    contact force's moment about the ground against the CG's
    (:func:`crashsim.motion.kernels.equations.specific_force`).
    """
    out = np.ones(len(bodies))
    if load_transfer:
        for i, b in enumerate(bodies):
            if b.contact_height is not None and b.cg_height is not None:
                out[i] = b.contact_height / b.cg_height
    return out


#: The ``phase_wheels`` columns :func:`phase_rows` fills, in the order of its values.
_PHASE_COLUMNS = (kernel_package.P_MUF, kernel_package.P_BRAKE, kernel_package.P_FROLL, kernel_package.P_CFIX,
                  kernel_package.P_CCOEF, kernel_package.P_CD, kernel_package.P_SD, kernel_package.P_LOCKED,
                  kernel_package.P_CASTOR)


def phase_rows(res: ResolvedWheels) -> np.ndarray:
    """The kernels' wheel rows (``P_*`` columns) of every phase of a vehicle's resolved wheel
    settings, shape (n_phases, n_wheels, N_P)."""
    values = [[(s.mu_factor, s.brake, s.rolling_resistance or 0.0, (s.cornering_stiffness or 0.0) * spec.tyres,
                s.cornering_coefficient or 0.0, math.cos(s.steer), math.sin(s.steer), 1.0 if s.is_sliding else 0.0,
                -1.0 if s.self_steer_limit is None else s.self_steer_limit)
               for s, spec in zip(settings, res.specs)] for _, settings in res.phases]
    out = np.zeros((len(res.phases), len(res.specs), kernel_package.N_P))
    out[:, :, _PHASE_COLUMNS] = np.array(values, dtype=float).reshape(len(res.phases), len(res.specs), -1)
    return out


def kernels():
    """The run-out kernel package (:mod:`crashsim.motion.kernels`)."""
    return kernel_package


@dataclass(frozen=True)
class Pair:
    """Two things that can touch: bodies ``a`` and ``b`` of different vehicles, or body ``a`` and obstacle ``b``."""

    a: str
    b: str
    obstacle: bool
    contact: ContactModel

    @property
    def name(self) -> str:
        return f"{self.a}|{self.b}"


def _zone_arrays(road: Road):
    """The friction zones as kernel arrays: ``(mu, edge pointer, edges (x0, y0, ex, ey, 1/len^2), boxes)``."""
    zone_mu = np.array([z.mu for z in road.zones], dtype=float)
    zone_ptr = np.zeros(len(road.zones) + 1, dtype=np.int64)
    edges = []
    for i, z in enumerate(road.zones):
        x0, y0, ex, ey, inv = z._edge_arrays
        edges.append(np.stack([x0, y0, ex, ey, inv], 1))
        zone_ptr[i + 1] = zone_ptr[i] + len(x0)
    edge_arr = np.ascontiguousarray(np.concatenate(edges, 0)) if edges else np.zeros((0, 5))
    zone_box = np.array([[*np.min(z.vertices, 0), *np.max(z.vertices, 0)] for z in road.zones],
                        dtype=float).reshape(-1, 4)
    return zone_mu, zone_ptr, edge_arr, zone_box


def _piece_arrays(pieces: list):
    """The convex pieces as kernel arrays: ``(vertices, outward edge normals, pointer, (cx, cy, radius,
    thickness) each)``."""
    verts, normals, ptr, info = [], [], [0], []
    for pc in pieces:
        d = np.roll(pc, -1, axis=0) - pc
        nrm = np.stack([d[:, 1], -d[:, 0]], 1) / np.hypot(d[:, 0], d[:, 1])[:, None]
        verts.append(pc)
        normals.append(nrm)
        ptr.append(ptr[-1] + len(pc))
        c = pc.mean(0)
        info.append([c[0], c[1], float(np.max(np.hypot(*(pc - c).T))), piece_thickness(pc)])
    pc_v = np.ascontiguousarray(np.concatenate(verts, 0)) if verts else np.zeros((0, 2))
    pc_n = np.ascontiguousarray(np.concatenate(normals, 0)) if normals else np.zeros((0, 2))
    return pc_v, pc_n, ptr, info


class SceneModel:
    """The run-out of a scene as arrays (see the module docstring).

    Parameters
    ----------
    vehicles : sequence of Vehicle
        The movable vehicles (barriers are skipped).
    wheels : mapping of vehicle name to WheelSettings or None
        None (or absent) means every wheel locked.
    road : Road
    options : RunoutOptions
    contact : ContactModel
        The scene's contact model (:mod:`crashsim.motion.contact`).
    pair_contact : mapping, optional
        Overrides for some pairs: ``{(name1, name2): ContactModel}`` where a name is a body, a
        vehicle or an obstacle; the most specific match wins (body-body over body-vehicle over
        vehicle-vehicle).
    obstacles : sequence of Obstacle
        Fixed obstacles (the barrier of an impact, guardrails, walls, poles).
    hitches : bool
        False: no hitch constraints (every body runs out alone; the static loads stay those
        of the coupled vehicles: the ``rigid`` level).
    """

    def __init__(self, vehicles: Sequence[Vehicle], wheels: Mapping[str, WheelSettings | None] | None, road: Road,
                 options: RunoutOptions, *, contact: ContactModel | None = None,
                 pair_contact: Mapping | None = None, obstacles: Sequence[Obstacle] = (), hitches: bool = True):
        k = kernels()
        self.options = options
        self.road = road
        self.contact = ContactModel() if contact is None else contact
        self.vehicles = tuple(v for v in vehicles if not v.is_barrier)
        if not self.vehicles:
            raise ScenarioError("the scene has no movable vehicle to run out", field="vehicles")
        self.obstacles = tuple(obstacles)
        wheels = dict(wheels or {})
        names = [v.name for v in self.vehicles]
        for key in wheels:
            if key not in names and key not in {v.name for v in vehicles}:
                raise ScenarioError(f"no vehicle named {key!r}; vehicles are {names}", field="wheels")
        self.bodies = tuple(b for v in self.vehicles for b in v.bodies)
        body_names = [b.name for b in self.bodies]
        if len(set(body_names)) != len(body_names):
            raise ScenarioError(f"body names must be unique in the scene, got {body_names}", field="vehicles")
        self.body_vehicle = np.array([i for i, v in enumerate(self.vehicles) for _ in v.bodies], dtype=np.int64)
        self.layout = None  # set once the wheels are known (the air brakes add the clock)

        # ---- wheels, loads and wheel-setting phases, vehicle by vehicle
        self.resolved = {}
        self.loads: dict[str, StaticLoads] = {}
        specs: list[WheelSpec] = []
        self.wheel_range, self.body_range, self.hitch_range = {}, {}, {}
        b0 = w0 = h0 = 0
        for v in self.vehicles:
            settings = wheels.get(v.name)
            settings = WheelSettings.all_locked() if settings is None else settings
            if isinstance(settings, ResolvedWheels):
                res = settings
            elif isinstance(settings, WheelSettings):
                res = settings.resolve(v)
            else:
                raise ScenarioError(f"must be WheelSettings or None, got {type(settings).__name__}",
                                    field=f"wheels[{v.name!r}]")
            if not res.specs:
                raise ScenarioError("a run-out needs at least one axle", field=f"{v.name}.bodies")
            self.resolved[v.name] = res
            self.loads[v.name] = static_loads(v)
            # body indices of the scene
            specs += [WheelSpec(s.key, s.body, s.body_index + b0, s.axle_index, s.axle_name, s.side, s.position,
                                s.tyres) for s in res.specs]
            self.body_range[v.name] = (b0, b0 + len(v.bodies))
            self.wheel_range[v.name] = (w0, w0 + len(res.specs))
            nh_v = len(v.hitches) if hitches else 0
            self.hitch_range[v.name] = (h0, h0 + nh_v)
            b0 += len(v.bodies)
            w0 += len(res.specs)
            h0 += nh_v
        self.specs = tuple(specs)
        nb, nw, nh = b0, w0, h0
        wheel_brake = np.zeros((nw, k.N_B))
        for v in self.vehicles:
            lo, hi = self.wheel_range[v.name]
            wheel_brake[lo:hi] = self.resolved[v.name].brake_rows(v)
        self.air_brakes = bool(np.any(wheel_brake[:, k.B_HAS] != 0.0))
        self.layout = StateLayout(tuple(body_names), accel_filter=options.load_transfer, clock=self.air_brakes)
        self.static_load = np.concatenate([self.loads[v.name].wheel for v in self.vehicles])
        changes = {t for r in self.resolved.values() for t in r.change_times} - {0.0}
        #: Times [s] at which wheel settings change (scheduled changes after 0).
        self.change_times = tuple(sorted(changes))
        # the kinks of the air brakes' ramps: where the brake force starts or stops changing
        rows = wheel_brake[wheel_brake[:, k.B_HAS] != 0.0]
        kinks = np.concatenate([rows[:, k.B_ON], rows[:, k.B_ON] + rows[:, k.B_RISE], rows[:, k.B_OFF],
                                rows[:, k.B_OFF] + rows[:, k.B_FALL]]) if len(rows) else np.zeros(0)
        #: Times at which the air brakes' force starts or stops changing (no wheel change).
        self.brake_kinks = tuple(sorted({x for x in kinks.tolist() if 0.0 < x < options.t_max}))
        # Phases: one from 0, from each scheduled change and from each kink of the ramps (a kink's phase keeps
        # the settings; its wheels take the next piece of their ramps, kernels.tyres.brake_piece), so that no
        # phase holds a kink or a step of a ramp.  Both engines end a segment at every phase boundary before
        # t_max: no step straddles one, and the brake force of a segment is one linear piece of the clock.
        times = sorted({0.0} | changes | set(self.brake_kinks))
        self.phase_times = np.array(times, dtype=float)
        #: Where the integration must stop and restart: the phase boundaries before t_max, then t_max.
        self.segment_stops = tuple(sorted({tc for tc in times[1:] if tc < options.t_max} | {options.t_max}))

        phase_w = self._phase_wheels(times, nw)

        # ---- bodies and hitches
        self.mass = np.array([b.mass for b in self.bodies], dtype=float)
        self.inertia = np.array([b.yaw_inertia for b in self.bodies], dtype=float)
        l_ref = np.concatenate([reference_lengths(v, self.resolved[v.name].specs) for v in self.vehicles])
        body = np.ascontiguousarray(np.stack([self.mass, self.inertia, l_ref], 1))
        wheel = np.array([[s.position[0], s.position[1], n] for s, n in zip(self.specs, self.static_load)],
                         dtype=float).reshape(-1, 3)
        wbody = np.array([s.body_index for s in self.specs], dtype=np.int64)
        hitch, hbody, self.hitch_names = self._hitch_arrays(hitches)
        self.minv = np.concatenate([1 / self.mass, 1 / self.mass, 1 / self.inertia])
        transfer = self._transfer_matrix(options, nb, nw)
        contact_lever = contact_levers(self.bodies, options.load_transfer)

        # ---- road and options
        zone_mu, zone_ptr, edge_arr, zone_box = _zone_arrays(road)
        cfg = np.zeros(k.N_CFG)
        cfg[k.C_EPS] = options.eps
        cfg[k.C_ALPHA2] = 2.0 * options.baumgarte_zeta * options.baumgarte_omega
        cfg[k.C_BETA2] = options.baumgarte_omega**2
        cfg[k.C_TAU] = options.load_transfer_tau
        cfg[k.C_VSTOP] = options.v_stop
        cfg[k.C_RTOL] = options.rtol
        cfg[k.C_ATOL] = options.atol
        cfg[k.C_MAXSTEP] = options.max_step
        cfg[k.C_FIRST] = 0.0 if options.first_step is None else options.first_step
        cfg[k.C_TMAX] = options.t_max
        cfg[k.C_SDT] = options.sample_dt
        cfg[k.C_ROADMU] = road.mu
        cfg[k.C_ZRES] = ZONE_RESOLUTION
        zone_slope, wheel_mass = self._slope_arrays(road, wbody, wheel, cfg)
        self._cfg = cfg
        scheme = SCHEMES[options.scheme]
        icfg = np.zeros(k.N_ICFG, dtype=np.int64)
        icfg[k.I_FIALA] = 1 if options.lateral_model == "fiala" else 0
        icfg[k.I_LT] = 1 if options.load_transfer else 0
        icfg[k.I_MAXSEG] = int(options.max_segments)
        icfg[k.I_ORDER] = scheme.error_estimator_order
        icfg[k.I_NSTAGES] = scheme.n_stages
        icfg[k.I_MAXEVAL] = int(options.max_evaluations)
        icfg[k.I_SLOPE] = 1 if road.sloped else 0
        icfg[k.I_CASTOR] = 1 if bool(np.any(phase_w[:, :, k.P_CASTOR] >= 0.0)) else 0
        icfg[k.I_YAWLOCK] = int(np.count_nonzero(hitch[:, 5])) if nh else 0
        icfg[k.I_BRAKE] = 1 if self.air_brakes else 0
        icfg[k.I_CLOCK] = self.layout.clock_index if self.air_brakes else 0
        tab_a, tab_b, tab_c, tab_e, tab_p = (np.ascontiguousarray(a, dtype=float)
                                             for a in (scheme.A, scheme.B, scheme.C, scheme.E, scheme.P))

        # ---- contact geometry
        pieces, pc_body, pr_body, pr_ptr, pp, pr_par = self._contact_pairs(pair_contact)
        pc_v, pc_n, ptr, info = _piece_arrays(pieces)
        self.M = k.KernelModel(
            body=body, wheel=wheel, wheel_body=wbody, hitch=np.ascontiguousarray(hitch), load_transfer=transfer,
            inv_mass=self.minv, phase_times=self.phase_times, phase_wheels=phase_w,
            zone_mu=zone_mu, zone_ptr=zone_ptr, zone_edges=edge_arr, cfg=cfg, icfg=icfg,
            tab_a=tab_a, tab_b=tab_b, tab_c=tab_c, tab_e=tab_e, tab_p=tab_p, zone_box=zone_box,
            body_vehicle=self.body_vehicle, hitch_body=hbody, piece_body=np.array(pc_body, dtype=np.int64),
            piece_ptr=np.array(ptr, dtype=np.int64), piece_verts=pc_v, piece_normals=pc_n,
            piece_info=np.array(info, dtype=float).reshape(-1, 4),
            pair_body=np.array(pr_body, dtype=np.int64).reshape(-1, 2), pair_ptr=np.array(pr_ptr, dtype=np.int64),
            piece_pairs=np.array(pp, dtype=np.int64).reshape(-1, 2),
            pair_par=np.array(pr_par, dtype=float).reshape(-1, k.N_R), zone_slope=zone_slope, wheel_mass=wheel_mass,
            wheel_brake=np.ascontiguousarray(wheel_brake), contact_lever=contact_lever)
        self.n_bodies, self.n_wheels, self.n_hitches = nb, nw, nh

    def _phase_wheels(self, times: list, nw: int) -> np.ndarray:
        """Every wheel's kernel row in each phase (phases from ``times``, nw wheels): (n_phases, nw, N_P)."""
        k = kernels()
        phase_w = np.zeros((len(times), nw, k.N_P))
        for v in self.vehicles:
            lo, hi = self.wheel_range[v.name]
            res = self.resolved[v.name]
            # each phase takes the rows of the settings in force at its start (a kink's phase repeats them)
            in_force = np.searchsorted([t for t, _ in res.phases], times, side="right") - 1
            phase_w[:, lo:hi] = phase_rows(res)[in_force]
        return phase_w

    def _hitch_arrays(self, hitches: bool):
        """The hitches' kernel rows (front point, rear point, articulation limit, yaw lock), their bodies'
        indices and their (front, rear) body names; none without ``hitches``."""
        hitch_rows, hbody, hitch_names = [], [], []
        for v in (self.vehicles if hitches else ()):
            lo, _ = self.body_range[v.name]
            for j, h in enumerate(v.hitches):
                hitch_rows.append([*h.front_point, *h.rear_point,
                                   math.nan if h.articulation_limit is None else h.articulation_limit,
                                   1.0 if h.yaw_locked else 0.0])
                hbody.append([lo + j, lo + j + 1])
                hitch_names.append((v.bodies[j].name, v.bodies[j + 1].name))
        hitch = np.array(hitch_rows, dtype=float).reshape(-1, 6)
        hbody = np.array(hbody, dtype=np.int64).reshape(-1, 2)
        return hitch, hbody, hitch_names

    def _transfer_matrix(self, options: RunoutOptions, nb: int, nw: int) -> np.ndarray:
        """Each wheel's load change per body acceleration (nw, 2 nb): (ax..., ay...); zero without load transfer."""
        transfer = np.zeros((nw, 2 * nb))
        if options.load_transfer:
            for v in self.vehicles:
                for i, b in enumerate(v.bodies):
                    if b.cg_height is None:
                        raise ScenarioError("load transfer needs the CG height of every body",
                                            field=f"{b.name}.cg_height")
                blo, bhi = self.body_range[v.name]
                wlo, whi = self.wheel_range[v.name]
                T = load_transfer_matrix(v, self.loads[v.name])  # (nw_v, 2 nb_v): (ax..., ay...)
                nbv = bhi - blo
                transfer[wlo:whi, blo:bhi] = T[:, :nbv]
                transfer[wlo:whi, nb + blo:nb + bhi] = T[:, nbv:]
        return transfer

    def _contact_pairs(self, pair_contact: Mapping | None):
        """The convex pieces of every body's outline and of the obstacles, and the pairs that can touch
        (bodies of different vehicles, a body and an obstacle; sets ``self.pairs``): ``(pieces, their bodies
        (-1: an obstacle), the pairs' bodies, piece-pair pointer, piece pairs, the pairs' kernel rows)``."""
        pieces, pc_body = [], []
        body_pieces: dict[int, list[int]] = {}
        for i, b in enumerate(self.bodies):
            outline = b.outline()
            if outline is None:
                continue
            for piece in convex_pieces(outline):
                body_pieces.setdefault(i, []).append(len(pieces))
                pieces.append(piece)
                pc_body.append(i)
        obstacle_pieces: dict[str, list[int]] = {}
        for ob in self.obstacles:
            for piece in ob.pieces():
                obstacle_pieces.setdefault(ob.name, []).append(len(pieces))
                pieces.append(piece)
                pc_body.append(-1)
        overrides = dict(pair_contact or {})
        self.pairs: list[Pair] = []
        pr_body, pr_ptr, pp, pr_par = [], [0], [], []
        thick = [piece_thickness(pc) for pc in pieces]

        def add_pair(ia, ib_pieces, ib, name_b, obstacle, model):
            if not model.enabled:
                return
            m_a = self.mass[ia]
            m_eff = m_a if ib < 0 else m_a * self.mass[ib] / (m_a + self.mass[ib])
            for pa in body_pieces[ia]:
                for pb in ib_pieces:
                    pp.append((pa, pb))
            pr_ptr.append(len(pp))
            pr_body.append((ia, ib))
            res = min(CONTACT_RESOLUTION, 0.25 * min([thick[q] for q in body_pieces[ia]] + [thick[q] for q in ib_pieces]))
            pr_par.append([model.stiffness, 2.0 * model.damping_ratio * math.sqrt(model.stiffness * m_eff),
                           model.friction, model.arm_distance, model.velocity_threshold, res,
                           math.sqrt(model.stiffness / m_eff)])
            self.pairs.append(Pair(self.bodies[ia].name, name_b, obstacle, model))

        for ia in sorted(body_pieces):
            for ib in sorted(body_pieces):
                if ib <= ia or self.body_vehicle[ia] == self.body_vehicle[ib]:
                    continue
                add_pair(ia, body_pieces[ib], ib, self.bodies[ib].name, False,
                         self._pair_model(ia, ib, None, overrides))
            for ob in self.obstacles:
                add_pair(ia, obstacle_pieces[ob.name], -1, ob.name, True, self._pair_model(ia, None, ob, overrides))
        return pieces, pc_body, pr_body, pr_ptr, pp, pr_par

    def with_road(self, road: Road) -> "SceneModel":
        """This model on another road with the same friction zones (objects): only its friction
        coefficient differs, which enters the arrays in one place (``cfg[C_ROADMU]``).  The same
        model as ``SceneModel(..., road, ...)`` built from scratch, without building it again."""
        if road.zones is not self.road.zones:
            raise ScenarioError("with_road keeps the friction zones; build a new SceneModel for other zones",
                                field="road.zones")
        new = copy.copy(self)
        new.road = road
        cfg = self._cfg.copy()
        cfg[kernels().C_ROADMU] = road.mu
        zone_slope, wheel_mass = new._slope_arrays(road, self.M.wheel_body, self.M.wheel, cfg)
        icfg = self.M.icfg.copy()
        icfg[kernels().I_SLOPE] = 1 if road.sloped else 0
        new._cfg = cfg
        new.M = self.M._replace(cfg=cfg, icfg=icfg, zone_slope=zone_slope, wheel_mass=wheel_mass)
        return new

    def _slope_arrays(self, road: Road, wbody: np.ndarray, wheel: np.ndarray, cfg: np.ndarray | None = None):
        """The kernel's slope inputs: the road's gravity in ``cfg`` (``C_GX, C_GY, C_GN``), and the
        zones' rows ``zone_slope`` (nz, 3) and the wheels' mass shares ``wheel_mass`` (nw,) [kg]."""
        k = kernels()
        cfg = self._cfg if cfg is None else cfg
        cfg[k.C_GX], cfg[k.C_GY], cfg[k.C_GN] = slope_gravity(road.grade, road.cross_slope)
        zone_slope = np.array([slope_gravity(*road.zone_slope(z)) for z in road.zones], dtype=float).reshape(-1, 3)
        wheel_mass = np.zeros(wheel.shape[0])
        if road.sloped:
            for i, b in enumerate(self.bodies):
                on = wbody == i
                total = float(np.sum(wheel[on, 2]))
                if total <= 0.0:
                    raise ScenarioError(f"body {b.name!r} has no wheel load to carry its weight on a sloped road; "
                                        "give it an axle", field=f"{b.name}.axles")
                wheel_mass[on] = self.mass[i] * wheel[on, 2] / total
        return zone_slope, wheel_mass

    # ------------------------------------------------------------------ pairs
    def _pair_model(self, ia: int, ib: int | None, obstacle: Obstacle | None, overrides: Mapping) -> ContactModel:
        body_a = self.bodies[ia].name
        veh_a = self.vehicles[self.body_vehicle[ia]].name
        if obstacle is not None:
            base = obstacle.contact or self.contact
            names_b = (obstacle.name,)
        else:
            base = self.contact
            names_b = (self.bodies[ib].name, self.vehicles[self.body_vehicle[ib]].name)
        best, rank = base, -1
        for key, model in overrides.items():
            x, y = key
            for r_a, na in enumerate((body_a, veh_a)):
                for r_b, nb_ in enumerate(names_b):
                    if {x, y} == {na, nb_} and x != y:
                        score = 2 - r_a + (1 - r_b)
                        if score > rank:
                            best, rank = model, score
        return best

    # ------------------------------------------------------------------ helpers
    def vehicle_of_body(self, i: int) -> Vehicle:
        return self.vehicles[int(self.body_vehicle[i])]

    def pack(self, states: Mapping[str, BodyState]) -> np.ndarray:
        """The scene state vector from body states (filtered accelerations zero)."""
        return self.layout.pack(states)

    def offsets(self, y: np.ndarray) -> np.ndarray:
        """``2 pi k`` offset of every hitch's articulation angle at ``y`` (stops are at offset +- limit)."""
        psi = y[self.layout.psi]
        hb = self.M.hitch_body
        out = np.zeros(max(self.n_hitches, 1))
        for j in range(self.n_hitches):
            raw = psi[hb[j, 0]] - psi[hb[j, 1]]
            out[j] = raw - (np.remainder(raw + math.pi, 2 * math.pi) - math.pi)
        return out

    def kinetic_energy(self, y) -> float:
        L = self.layout
        return 0.5 * float(np.dot(self.mass, y[L.vx] ** 2 + y[L.vy] ** 2) + np.dot(self.inertia, y[L.w] ** 2))

    def fresh_mode(self):
        return kernels().mode_arrays(self.n_wheels, len(self.road.zones), self.n_hitches, len(self.pairs),
                                     len(self.vehicles))
