"""Checks of a validated file: each vehicle's geometry (outlines, axles, hitches), the overlap of the outlines at
impact, the contact point, the impact law.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ScenarioError
from ..geometry import rotate
from ..impact import ImpactProblem
from ..motion.road import signed_distance
from ..units import Kind, format_value, parse
from ..vehicles import Vehicle
from .problems import Problems, as_in_file, error_at


def check_impact_law(imp: dict, problems: Problems, file: str | None) -> None:
    """The [impact] table's tangential law and its coefficient, and the moment restitution: each error kept."""
    law = imp["tangential"]
    with problems.each():
        if law == "ratio" and imp["mu"] is None:
            raise error_at('tangential = "ratio" needs mu (the impulse ratio P_t/P_n), e.g. mu = 0.3', "impact.mu", file)
        if law == "fraction" and imp["mu_fraction"] is None:
            raise error_at('tangential = "fraction" needs mu_fraction (mu as a share of mu_max, 0 to 1), e.g. '
                           'mu_fraction = 0.85', "impact.mu_fraction", file)
        if law == "friction" and imp["friction"] is None:
            raise error_at('tangential = "friction" needs friction (f >= 0), e.g. friction = 0.6', "impact.friction",
                           file)
    for k, needed in (("mu", "ratio"), ("mu_fraction", "fraction"), ("friction", "friction")):
        with problems.each():
            if imp[k] is not None and law != needed:
                raise error_at(f"{k} = {imp[k]} is given but tangential = {law!r} does not use it "
                               f'(it belongs to tangential = "{needed}")', f"impact.{k}", file)
    ep = imp["moment_restitution"]
    with problems.each():
        if not (ep == -1.0 or 0.0 <= ep <= 1.0):
            raise error_at(f"{ep} is out of range; allowed -1 (no moment impulse) or [0, 1]", "impact.moment_restitution",
                           file)


def outline_problem(points) -> str | None:
    """Why ``points`` (a closed outline, in order) is not a simple polygon, or None: fewer than 3
    points, all on one line (no area), or edges crossing (a bow-tie: points not in order around it)."""
    p = np.asarray(points, dtype=float)
    n = len(p)
    if n < 3:
        return f"{n} point(s); an outline needs at least 3"

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    scale = max(float(np.ptp(p[:, 0])), float(np.ptp(p[:, 1])), 1e-300)
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue  # adjacent through the closing edge
            a, b, c, d = p[i], p[(i + 1) % n], p[j], p[(j + 1) % n]
            d1, d2, d3, d4 = cross(c, d, a), cross(c, d, b), cross(a, b, c), cross(a, b, d)
            if d1 * d2 < 0 and d3 * d4 < 0:
                return (f"its edges cross (points {i + 1}-{i + 2} and points {j + 1}-{(j + 1) % n + 1}): the outline "
                        "intersects itself; list the points in order around the zone")
    x, y = p[:, 0], p[:, 1]
    area = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    if area <= 1e-12 * scale * scale:
        return "its points lie on one line: it has no area"
    return None


def check_vehicle_geometry(veh: Vehicle, v: dict, raw: dict, system: str, file: str | None) -> None:
    """Hitch points within (or within ``drawbar`` of) both bodies they join; tyre contacts within
    (or within ``overhang`` of) their body's outline. One error, naming the key as written, the
    value as written in the file, how far it is off and the allowed range."""
    def L(x, like=None):
        """A length in the unit of ``like`` (a value as written in the file), else the file's system's."""
        like = like[0] if isinstance(like, (list, tuple)) and like else like
        if isinstance(like, str) and len(like.split(maxsplit=1)) == 2:
            unit = like.split(maxsplit=1)[1]
            try:
                return f"{x / parse(f'1 {unit}', Kind.LENGTH, field='unit'):.4g} {unit}"
            except ScenarioError:
                pass
        return format_value(x, Kind.LENGTH, system)

    bodies = v["bodies"]
    for i, body in enumerate(veh.bodies):
        corners = body.outline()
        if corners is None:
            continue
        b, rb = bodies[i], raw["bodies"][i]
        key = f"vehicles.{veh.name}.bodies[{i}]"
        size = f"outline {L(body.length, rb.get('length'))} x {L(body.width, rb.get('width'))}"
        for which in ("rear_hitch", "front_hitch"):
            if b[which] is None:
                continue
            out = max(0.0, -float(signed_distance(np.asarray(b[which], dtype=float)[None], corners)[0]))
            if out > b["drawbar"] + 1e-9:
                raise error_at(f"{which} = {as_in_file(rb[which])} lies {L(out, rb[which])} outside the {size} of body "
                               f"{body.name!r}; allowed: within the outline or at most drawbar = "
                               f"{L(b['drawbar'], rb.get('drawbar'))} outside "
                               f"it (a longer drawbar or tongue: set {key}.drawbar)", f"{key}.{which}", file)
        cx, cy = body.outline_center
        ahead, side = b["overhang"]
        for k, ax in enumerate(body.axles):
            front, rear = cx + body.length / 2 + ahead, cx - body.length / 2 - ahead
            rax = rb["axles"][k] if isinstance(rb.get("axles"), list) and k < len(rb["axles"]) else {}
            akey = f"{key}.axles[{k}]"
            if not rear - 1e-9 <= ax.x <= front + 1e-9:
                lx = rax.get("x")
                raise error_at(f"x = {as_in_file(rax.get('x', ax.x))} puts the axle outside the body: allowed "
                               f"[{L(rear, lx)}, {L(front, lx)}] from the CG ({size} centred at {L(cx, lx)}, plus overhang "
                               f"= {L(ahead, rb.get('overhang'))} beyond its ends; set {key}.overhang for more)", f"{akey}.x", file)
            half = body.width / 2 + side - abs(cy)  # tyre contacts at +-track/2 from the CG line
            if ax.track / 2 > half + 1e-9:
                lt = rax.get("track")
                raise error_at(f"track = {as_in_file(rax.get('track', ax.track))} is wider than body {body.name!r} "
                               f"(width {L(body.width, lt)}); allowed a track <= {L(2 * half, lt)} (the width plus overhang "
                               f"= {L(side, (rb.get('overhang') or [None, None])[1:])} on each side; set {key}.overhang for more)",
                               f"{akey}.track", file)


def _sat_depth(a: np.ndarray, b: np.ndarray) -> float:
    """How far one convex polygon must move to clear the other (separating axes) [m]; 0 if apart."""
    depth = math.inf
    for poly in (a, b):
        for i in range(len(poly)):
            e = poly[(i + 1) % len(poly)] - poly[i]
            n = np.array([-e[1], e[0]]) / math.hypot(e[0], e[1])
            pa, pb = a @ n, b @ n
            ov = min(pa.max(), pb.max()) - max(pa.min(), pb.min())
            if ov <= 0:
                return 0.0
            depth = min(depth, ov)
    return float(depth)


def check_overlap(problem: ImpactProblem, vehicles, states: dict, tolerance: float, system: str,
                  file: str | None) -> None:
    """Bodies of different vehicles may overlap at the impact by at most ``tolerance``: the impact's
    two bodies measured along the impact normal (their crush), any other pair by the distance one
    must move to clear the other (they are not in the impact: any overlap is a misplaced vehicle)."""
    normal = np.asarray(problem.surface.normal, dtype=float)
    pair = {problem.body1, problem.body2}
    placed = []
    for v in vehicles:
        for b in v.bodies:
            corners = b.outline()
            if corners is None or b.is_fixed or b.name not in states:
                continue
            st = states[b.name]
            placed.append((v.name, b.name, np.asarray(st.position) + rotate(corners, st.heading)))
    for i, (va, ba, pa) in enumerate(placed):
        for vb, bb, pb in placed[i + 1:]:
            if va == vb or _sat_depth(pa, pb) == 0.0:
                continue
            crush = {ba, bb} == pair
            if crush:
                qa, qb = pa @ normal, pb @ normal
                depth, how = min(qa.max(), qb.max()) - max(qa.min(), qb.min()), "along the impact normal"
            else:
                depth, how = _sat_depth(pa, pb), "(the distance one must move to clear the other)"
            if depth > tolerance:
                L = lambda x: format_value(x, Kind.LENGTH, system)  # noqa: E731
                raise error_at(f"at the impact the outlines of {ba!r} (vehicle {va!r}) and {bb!r} (vehicle {vb!r}) overlap "
                               f"{L(depth)} deep {how}: one vehicle is placed on top of the other; allowed at most "
                               f"impact.overlap_tolerance = {L(tolerance)} (the crush of the first impact); check the "
                               f"positions and headings of vehicles.{va} and vehicles.{vb}", f"vehicles.{vb}.position",
                               file)


def contact_outlines(problem: ImpactProblem, states: dict) -> list[tuple[str, np.ndarray]]:
    """``(name, corners in world coordinates)`` of the impact's two contacting bodies at ``states``
    (a fixed body, or one without an outline, left out)."""
    out = []
    for name in (problem.body1, problem.body2):
        body = next(b for v in problem.vehicles for b in v.bodies if b.name == name)
        corners = body.outline()
        if body.is_fixed or corners is None:
            continue
        st = states[name]
        out.append((name, np.asarray(st.position) + rotate(corners, st.heading)))
    return out


def check_contact_point(problem: ImpactProblem, tolerance: float, system: str, file: str | None) -> None:
    """The contact point must lie in or near (``tolerance``) the outline of both contacting bodies."""
    point = np.asarray(problem.surface.point)
    far = []
    for name, world in contact_outlines(problem, problem.states):
        gap = max(0.0, -float(signed_distance(point[None], world)[0]))
        if gap > tolerance:
            far.append(f"{format_value(gap, Kind.LENGTH, system)} outside the outline of {name!r}")
    if far:
        shown = ", ".join(format_value(float(c), Kind.LENGTH, system) for c in point)
        raise error_at(f"the contact point ({shown}) lies " + " and ".join(far)
                       + f" at impact (allowed: within impact.contact_tolerance = {format_value(tolerance, Kind.LENGTH, system)} "
                       "of both outlines); check impact.point and its point_frame, and the vehicles' positions and headings",
                       "impact.point", file)


#: The smallest radius of gyration about the vertical axis, as a share of the outline's length, that a
#: vehicle body's ``yaw_inertia`` is taken for without a warning. The shipped scenes and presets lie
#: between 0.17 and 0.35 (a uniform box: 0.29 of its diagonal); a value in pound-mass ft^2 meant as
#: slug ft^2 is 32.2 times too small, its radius of gyration 5.7 times, about 0.05 of the length.
GYRATION_LOW = 0.1


def inertia_warnings(veh: Vehicle, raw: dict) -> list[str]:
    """A warning for every ``yaw_inertia`` the file writes (``raw``: the vehicle's table as written)
    whose radius of gyration ``sqrt(I / m)`` is below ``GYRATION_LOW`` of the body's length or beyond
    half its outline's diagonal (no rigid body whose mass lies within its outline, CG at its centre,
    has more): most likely a value in the wrong unit."""
    out: list[str] = []
    bodies = raw.get("bodies") if isinstance(raw, dict) else None
    for i, body in enumerate(veh.bodies):
        rb = bodies[i] if isinstance(bodies, list) and i < len(bodies) and isinstance(bodies[i], dict) else {}
        written = rb.get("yaw_inertia")
        if written is None or not body.length or not body.width or not body.mass > 0 or not body.yaw_inertia > 0:
            continue
        k = math.sqrt(body.yaw_inertia / body.mass)
        high = 0.5 * math.hypot(body.length, body.width)
        if GYRATION_LOW * body.length <= k <= high:
            continue
        out.append(f"vehicles.{veh.name}.bodies[{i}].yaw_inertia = {as_in_file(written)}: with the body's mass its "
                   f"radius of gyration is {k / body.length:.3g} x its length (vehicle bodies lie near 0.17-0.35; "
                   f"expected {GYRATION_LOW:g} to {high / body.length:.3g}, half the outline's diagonal); check the "
                   "unit: 1 slug ft^2 = 1 lbf ft s^2 = 32.17 lb ft^2 (lb ft^2 is pound-mass)")
    return out
