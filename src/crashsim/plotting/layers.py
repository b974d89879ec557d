"""The layers of a scene figure over the road: the survey's underlay, wheel tracks, the approaches,
measured crush, the evidence with its verdicts, delta-v and PDOF arrows, fixed obstacles, numbered
impacts and the barrier face.
"""

from __future__ import annotations

import numpy as np

from ..evidence.crush import profile_outline
from ..geometry import to_world
from ..report import fmt
from ..survey.underlay import draw_underlay, scene_underlay
from ..units import Kind, convert, to_unit
from .drawing import SceneDrawing
from .road import clip_polygon, clip_polyline
from .style import (EVIDENCE_COLOR, FAIL_COLOR, PASS_COLOR, Z_ARROW, Z_BARRIER, Z_EVIDENCE, Z_GHOST, Z_IMPACT, Z_TEXT,
                    Z_TRACK, halo, nice_at_most, wrap)

__all__ = ["draw_scene_underlay", "draw_track", "draw_approaches", "CRUSH_KEY", "crush_text", "draw_crush", "check_map",
           "draw_evidence", "draw_arrows", "draw_obstacles", "draw_impacts", "draw_barrier"]


def draw_scene_underlay(S: SceneDrawing) -> None:
    """The survey's orthophoto ([survey.underlay]) under everything, in the figure's units."""
    got = scene_underlay(S.sc)
    if got is not None:
        image, georef, opacity, clip = got
        draw_underlay(S.ax, image, georef, scale=S.k, opacity=opacity, clip=clip)


def draw_track(S: SceneDrawing, track, line, dark, gid: str | None = None) -> None:
    """A wheel's track: sliding stretches bold and dark (a tyre mark expected), rolling ones thin and dashed."""
    for seg in track.segments:
        if len(seg.points) < 2:
            continue
        xy = S.d(seg.points)
        if seg.kind == "sliding":
            (ln,) = S.ax.plot(xy[:, 0], xy[:, 1], "-", color=dark, lw=2.2, alpha=0.85, zorder=Z_TRACK,
                              solid_capstyle="butt", gid=gid)
        else:
            (ln,) = S.ax.plot(xy[:, 0], xy[:, 1], "--", color=line, lw=0.7, alpha=0.8, zorder=Z_TRACK, dashes=(4, 3),
                              gid=gid)
        S.timed.append((ln, np.asarray(seg.t, dtype=float), xy))
        S.add(xy)


def draw_approaches(S: SceneDrawing) -> None:
    """The approach of each vehicle before the impact: its tyre tracks (sliding bold: pre-impact
    marks expected), the CG paths (dash-dot), the outlines at the start of braking (thin,
    dashed) and the first body's CG at perception (open diamond, joined by a dotted line)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    ax = S.ax
    for vn, a in S.sc.approaches.items():
        v = next(x for x in S.sc.vehicles if x.name == vn)
        fill, line, dark = S.family[vn]
        for tr in a.tracks.values():
            draw_track(S, tr, line, dark, gid=f"approach:track:{tr.key}")
        poses = {}
        for name, rows in a.bodies.items():
            xy = S.d(rows[:, 1:3])
            (ln,) = ax.plot(xy[:, 0], xy[:, 1], "-.", color=dark, lw=0.9, zorder=Z_TRACK, gid=f"approach:path:{name}")
            S.timed.append((ln, np.asarray(rows[:, 0], dtype=float), xy))
            S.add(xy)
            poses[name] = ((rows[0, 1], rows[0, 2]), rows[0, 3])
            S.outline(S.body_of[name], poses[name][0], poses[name][1], gid=f"outline:braking:{name}", fill=None,
                      edge=line, lw=0.8, ls="--", alpha=0.8, zorder=Z_GHOST)
        S.pins(v, poses, line, 2.5, alpha=0.7, zorder=Z_GHOST)
        first = next(iter(a.bodies))
        start = S.d(a.bodies[first][0, 1:3])
        S.text(start, f"braking starts, {fmt(a.speed_at_braking, 'speed', S.system)}", kind="approach", fontsize=6.5,
               color=dark,
               ha="center", va="bottom", path_effects=halo(1.8))
        S.labels.append(start)
        if a.reaction_time > 0:
            pp = S.d(a.perception_point)
            ax.plot([pp[0], start[0]], [pp[1], start[1]], ":", color=dark, lw=1.0, zorder=Z_TRACK)
            ax.plot(*pp, "D", ms=5, mfc="white", mec=dark, zorder=Z_IMPACT, gid=f"approach:perception:{vn}")
            ahead = fmt(a.reaction_time, "time", S.system, digits=3)  # a Monte Carlo median without float noise
            S.text(pp, f"perception ({ahead} before braking)", kind="approach", fontsize=6.5, color=dark, ha="center",
                   va="bottom", path_effects=halo(1.8))
            S.labels.append(pp)
            S.add(pp)
    S.legend_entry("approach: CG path from the start of braking", Line2D([], [], color="0.2", lw=0.9, ls="-."))
    S.legend_entry("at the start of braking", Patch(facecolor="none", edgecolor="0.3", lw=0.8, ls="--"))
    if any(a.reaction_time > 0 for a in S.sc.approaches.values()):
        S.legend_entry("perception point (reaction at constant speed)",
                       Line2D([], [], ls=":", color="0.2", marker="D", ms=5, mfc="white", mec="0.2"))


CRUSH_KEY = "measured crush (to scale)"


def draw_crush(S, sc) -> None:
    """Each measured crush profile (``[[evidence.crush]]``) on the damaged face of its body's outline at
    impact, to scale (gid ``"crush:<body>:<face>"``)."""
    from matplotlib.patches import Patch, Polygon

    drawn = False
    for it in sc.evidence.crush:
        body = S.body_of.get(it.body)
        poly = None if body is None else profile_outline(body, it)
        if poly is None:
            continue
        st = sc.states[it.body]
        xy = S.d(to_world(poly, st.position, st.heading))
        _, _, dark = S.colors(it.body)
        S.ax.add_patch(Polygon(xy, closed=True, facecolor="none", edgecolor=dark, hatch="xxxx", lw=1.0,
                               zorder=Z_IMPACT + 0.5, gid=f"crush:{it.body}:{it.face}"))
        S.add(xy)
        drawn = True
    if drawn:
        S.legend_entry(CRUSH_KEY, Patch(facecolor="none", edgecolor="0.2", hatch="xxxx", lw=1.0))


def check_map(scene) -> dict:
    """Evidence checks keyed by (kind, index of the evidence item), walking the report in the
    order :func:`crashsim.evidence.checks.evaluate_evidence` writes it; each key is
    confirmed by the check's kind and its (default) name."""
    ev = scene.scenario.evidence
    rep = scene.evidence
    if rep is None:
        return {}
    out = {}
    checks = list(rep.checks)
    by_name = {(c.kind, c.name): c for c in checks}

    def take(kind, index, name):
        c = by_name.get((kind, name))
        if c is not None:
            out[(kind, index)] = c

    if ev.impact_point is not None:
        take("point of impact", 0, ev.impact_point.name)
    for i, r in enumerate(ev.rest):
        name = r.name or f"rest of {r.body}"
        take("rest", i, name)
        take("rest heading", i, f"{name} (heading)")
    for i, m in enumerate(ev.marks):
        take("mark", i, m.name or f"mark {i + 1}")
    for i, x in enumerate(ev.delta_v):
        take("delta-v", i, x.label)
    for i, x in enumerate(getattr(ev, "recorder", ())):
        take("recorder", i, x.name or f"recorder in {x.body}")
    return out


def _verdict(checks) -> tuple[str, str]:
    """('PASS'/'FAIL', colour) of one or more checks (all must pass)."""
    checks = [c for c in checks if c is not None]
    if not checks:
        return "not checked", "0.3"
    ok = all(c.passed for c in checks)
    return ("PASS", PASS_COLOR) if ok else ("FAIL", FAIL_COLOR)


def _residual_text(c, system) -> str:
    if c is None:
        return ""
    if np.isinf(c.residual):
        return "nothing computed"
    if c.quantity == "angle":
        return (f"{convert(c.residual, 'rad', 'deg', Kind.ANGLE):+.1f}\N{DEGREE SIGN} "
                f"(tol. {convert(c.tolerance, 'rad', 'deg', Kind.ANGLE):.0f}\N{DEGREE SIGN})")
    return f"{fmt(abs(c.residual), c.quantity, system, 2)} (tol. {fmt(c.tolerance, c.quantity, system, 2)})"


def _three_digits(x: float) -> str:
    """``x`` to three significant digits without an exponent: 72,400 (not 7.24e+04), 0.0125."""
    if x == 0 or not np.isfinite(x):
        return f"{x:g}"
    decimals = max(0, 2 - int(np.floor(np.log10(abs(float(f"{x:.3g}"))))))
    return f"{float(f'{x:.3g}'):,.{decimals}f}"


def crush_text(c, verdict: str, system) -> str:
    """The legend text of a crush-energy check: two-sided, the residual |model loss - crush| against
    its tolerance; one-sided (a body of the impact without a crush item: the crush energy is a lower
    bound of the energy absorbed, as the report says), the bound it is checked against, marked so:
    "PASS (one-sided bound)", "model loss at least crush - tol.: 72,400 >= 48,000 - 12,000 ft lbf"
    (with the sign >= as one character)."""
    d = c.details
    if d.get("complete", True) or np.isinf(c.residual):
        return wrap(f"{c.name}: {verdict}", 52) + f"\n  |model loss - crush| {_residual_text(c, system)}"
    k, unit = to_unit(1.0, Kind.ENERGY, system)
    num = [_three_digits(k * v) for v in (d["computed"], d["measured"], c.tolerance)]
    rel = "\N{GREATER-THAN OR EQUAL TO}" if c.passed else "<"
    return (wrap(f"{c.name}: {verdict} (one-sided bound)", 52)
            + f"\n  model loss at least crush - tol.: {num[0]} {rel} {num[1]} - {num[2]} {unit}"
            + f"\n  (no crush item for {', '.join(d['missing'])}: the crush energy is a lower bound)")


def draw_evidence(S: SceneDrawing, checks: dict) -> None:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Polygon

    ax, ev, system = S.ax, S.sc.evidence, S.system
    for i, r in enumerate(ev.rest):
        c_pos, c_head = checks.get(("rest", i)), checks.get(("rest heading", i))
        verdict, color = _verdict([c_pos, c_head])
        p = S.d(r.position)
        body = S.body_of.get(r.body)
        if r.heading is not None and body is not None and body.outline() is not None:
            xy = S.d(to_world(body.outline(), r.position, r.heading))
            ax.add_patch(Polygon(xy, closed=True, facecolor="none", edgecolor=EVIDENCE_COLOR, lw=1.2, ls=(0, (4, 2)),
                                 zorder=Z_EVIDENCE, gid=f"evidence:rest:{r.body}"))
            S.add(xy)
        ax.add_patch(Circle(p, S.k * r.tolerance, facecolor="none", edgecolor=EVIDENCE_COLOR, lw=0.6, ls=":",
                            zorder=Z_EVIDENCE))
        ax.plot(*p, "x", color=EVIDENCE_COLOR, ms=7, mew=1.8, zorder=Z_EVIDENCE + 0.5)
        S.add(p)
        S.labels.append(p)
        detail = _residual_text(c_pos, system)
        if c_head is not None:
            detail += f", heading {_residual_text(c_head, system)}"
        label = f"measured rest, {r.body}: {verdict}" + (f"\n  {detail}" if detail else "")
        S.legend_entry(label, Line2D([], [], ls=(0, (4, 2)), color=EVIDENCE_COLOR, lw=1.2, marker="x", ms=6, mew=1.5),
                       color)
    for i, m in enumerate(ev.marks):
        if m.phase == "approach" and not S.approach:
            continue  # a pre-impact mark belongs to the approach, left out of this view
        c = checks.get(("mark", i))
        verdict, color = _verdict([c])
        xy = S.d(m.points)
        ax.plot(xy[:, 0], xy[:, 1], "-", color=EVIDENCE_COLOR, lw=1.4, marker="o", ms=2.5, zorder=Z_EVIDENCE)
        S.add(xy)
        name = m.name or f"mark {i + 1}"
        detail = _residual_text(c, system)
        if c is not None and "matched_wheel" in c.details:
            detail += f", nearest {c.details['matched_wheel']}"
        S.legend_entry(wrap(f"measured mark \u201c{name}\u201d: {verdict}", 52) + (f"\n  {detail}" if detail else ""),
                       Line2D([], [], color=EVIDENCE_COLOR, lw=1.4, marker="o", ms=2.5), color)
    if ev.impact_point is not None:
        c = checks.get(("point of impact", 0))
        verdict, color = _verdict([c])
        p = S.d(ev.impact_point.position)
        # above the PDOF arrows (it lies at the contact point), below the contact-point dot
        ax.plot(*p, "*", ms=13, mfc=EVIDENCE_COLOR, mec="white", mew=0.8, zorder=Z_ARROW + 0.3)
        S.add(p)
        detail = _residual_text(c, system)
        S.legend_entry(f"measured point of impact: {verdict}" + (f"\n  {detail}" if detail else ""),
                       Line2D([], [], ls="none", marker="*", ms=11, mfc=EVIDENCE_COLOR, mec="white"), color)
    for i, x in enumerate(ev.delta_v):
        c = checks.get(("delta-v", i))
        verdict, color = _verdict([c])
        name = x.label
        detail = _residual_text(c, system)
        S.legend_entry(wrap(f"recorded \u0394v \u201c{name}\u201d: {verdict}", 52)
                       + (f"\n  {detail}" if detail else ""),
                       Line2D([], [], ls="none"), color)
    for c in (S.scene.evidence.checks if S.scene.evidence is not None else ()):
        if c.kind == "crush energy":  # one check per group of crush items (drawn on the faces)
            verdict, color = _verdict([c])
            S.legend_entry(crush_text(c, verdict, system), Line2D([], [], ls="none"), color)
    for i, x in enumerate(getattr(ev, "recorder", ())):
        c = checks.get(("recorder", i))
        verdict, color = _verdict([c])
        name = x.name or f"recorder in {x.body}"
        detail = ""
        if c is not None and "times" in c.details:
            detail = (f"{c.details.get('n_compared', len(x.times))} pre-crash speeds, worst "
                      f"{_residual_text(c, system)}")
        S.legend_entry(wrap(f"recorded speeds \u201c{name}\u201d: {verdict}", 52)
                       + (f"\n  {detail}" if detail else ""),
                       Line2D([], [], ls="none"), color)


def draw_arrows(S: SceneDrawing) -> None:
    from matplotlib.lines import Line2D
    from matplotlib.patches import FancyArrowPatch

    ax, imp, system, sc = S.ax, S.scene.impact, S.system, S.sc
    moving = [b for b in imp.bodies.values() if not b.fixed]
    if not moving:
        return
    # results of the impact: in the animation they appear at the impact (t = 0), not before it
    first = (len(ax.patches), len(ax.lines), len(S.texts))
    # one arrow scale for all bodies: display length per display speed, a 1-2-2.5-5 number,
    # such that the largest delta-v is drawn about 6 m (20 ft) long
    ref_len = to_unit(6.0, Kind.LENGTH, system)[0]
    dv_max = max(to_unit(b.delta_v_magnitude, Kind.SPEED, system)[0] for b in moving)
    sunit = to_unit(1.0, Kind.SPEED, system)[1]
    if dv_max > 0:
        scale = nice_at_most(ref_len / dv_max)  # display length per display speed unit
        for b in moving:
            dv, _ = to_unit(b.delta_v_magnitude, Kind.SPEED, system)
            if dv <= 0:
                continue
            tail = S.d(sc.states[b.name].position)
            vec = np.asarray(b.delta_v, dtype=float) / b.delta_v_magnitude * dv * scale
            dark = S.colors(b.name)[2]
            ax.add_patch(FancyArrowPatch(tail, tail + vec, arrowstyle="-|>", mutation_scale=12, lw=1.6, color=dark,
                                         shrinkA=0, shrinkB=0, zorder=Z_ARROW, gid=f"arrow:delta-v:{b.name}"))
            S.add(tail + vec)
            # label beyond the tip, on the arrow's line
            u = vec / np.hypot(*vec)
            tip = tail + vec + u * 0.5 * S.k
            S.text(tip, f"\u0394v {b.name}\n{fmt(b.delta_v_magnitude, Kind.SPEED, system, 3)}", kind="delta-v",
                    fontsize=7, color=dark, ha="left" if u[0] >= 0 else "right", va="bottom" if u[1] >= 0 else "top",
                    zorder=Z_TEXT, path_effects=halo())
        per = 1.0 / scale
        S.legend_entry(f"\u0394v at the CG (1 {S.lunit} of arrow = {per:.3g} {sunit})",
                       Line2D([], [], color="0.15", lw=1.6, marker=">", markevery=[1], ms=5))
    # principal direction of force at the contact point
    length = 3.0 * S.k
    p0 = S.d(imp.point)
    ax.plot(*p0, "o", ms=5, mfc="black", mec="white", mew=0.8, zorder=Z_ARROW + 0.5)
    S.add(p0)
    S.legend_entry("contact point (crush impulse centre)",
                   Line2D([], [], ls="none", marker="o", ms=5, mfc="black", mec="white"))
    for name in (imp.body1, imp.body2):
        b = imp.bodies[name]
        if b.fixed or b.crush_impulse is None or b.pdof is None:
            continue
        f = np.asarray(b.crush_impulse, dtype=float)
        if not np.hypot(*f) > 0:
            continue
        u = f / np.hypot(*f)
        tip = p0 + length * u
        dark = S.colors(name)[2]
        ax.add_patch(FancyArrowPatch(p0, tip, arrowstyle="simple,head_width=0.9,head_length=0.9,tail_width=0.35",
                                     mutation_scale=14, facecolor="white", edgecolor=dark, lw=1.2, shrinkA=0,
                                     shrinkB=0, zorder=Z_ARROW, gid=f"arrow:pdof:{name}"))
        S.add(tip)
        deg = convert(b.pdof, "rad", "deg", Kind.ANGLE)
        text = f"PDOF {name}\n{deg:.0f}\N{DEGREE SIGN} ({b.clock} o'clock)"
        # beyond the tip, or beyond the tail (the side the force comes from) if that covers fewer labels
        best = None
        for anchor, d in ((tip + u * 0.4 * S.k, u), (p0 - u * 0.4 * S.k, -u)):
            hits = S.label_hits(anchor, d, 17, 2)
            if best is None or hits < best[0]:
                best = (hits, anchor, d)
        _, lab, d = best
        S.text(lab, text, kind="pdof", fontsize=7, color=dark, ha="left" if d[0] >= 0 else "right",
               va="bottom" if d[1] >= 0 else "top", zorder=Z_TEXT, path_effects=halo())
        S.labels.append(lab)
    S.legend_entry("PDOF: crush force on each body in contact",
                   Line2D([], [], ls="none", marker=r"$\Rightarrow$", ms=12, color="0.15"))
    S.appear += [(a, 0.0) for a in (*ax.patches[first[0]:], *ax.lines[first[1]:], *S.texts[first[2]:])]


def draw_obstacles(S: SceneDrawing) -> None:
    """Fixed obstacles of the scene (guardrails, walls, poles), hatched, with their names."""
    from matplotlib.patches import Patch, Polygon

    spec = S.sc.runout
    barrier = next((v.bodies[0].name for v in S.sc.vehicles if v.is_barrier), None)
    obstacles = [o for o in (spec.obstacles if spec is not None else ()) if o.name != barrier]
    for o in obstacles:
        for piece in o.pieces():
            xy = S.d(piece)
            S.ax.add_patch(Polygon(xy, closed=True, facecolor="0.78", edgecolor="0.25", lw=0.8, hatch="xxx",
                                   zorder=Z_BARRIER, gid=f"obstacle:{o.name}"))
            S.far.append(xy)  # a long guardrail counts toward the view only near the scene
        # its name at the point of the obstacle nearest the scene (a long guardrail's middle may lie
        # far outside the view)
        centre = np.vstack(S.points).mean(axis=0) if S.points else np.zeros(2)
        line = S.d(np.asarray(o.points, dtype=float))
        mid = line[int(np.argmin(np.hypot(*(line - centre).T)))]
        S.text(mid, o.name, kind="obstacles", fontsize=7, color="0.15", ha="center", va="bottom", zorder=Z_TEXT,
               path_effects=halo())
    if obstacles:
        S.legend_entry("fixed obstacle", Patch(facecolor="0.78", edgecolor="0.25", hatch="xxx", lw=0.8))


def draw_impacts(S: SceneDrawing) -> None:
    """Every impact as a numbered marker at its contact point, in time order (1 = the first impact)."""
    from matplotlib.lines import Line2D

    joint = getattr(S.scene, "joint", None)
    marks = [(1, S.scene.impact.point, 0.0)]
    for ev in (joint.impact_events() if joint is not None else ()):
        seen = set()
        for r in ev.records:  # an event's number once at each of its pairs (not at every bounce)
            if (r.body1, r.body2) not in seen:
                seen.add((r.body1, r.body2))
                marks.append((ev.number, r.point, float(r.t)))
    if len(marks) < 2:
        return
    for n, p, t_mark in marks:
        xy = S.d(np.asarray(p, dtype=float))
        first = (len(S.ax.lines), len(S.texts))
        # the point itself, and its number in a yellow disc on it (moved aside with a leader line
        # by place_labels when impacts lie close together)
        S.ax.plot(*xy, "o", ms=3.5, mfc="0.1", mec="#ffd54f", mew=0.8, zorder=Z_ARROW + 1, gid=f"impact:{n}")
        S.text(xy, str(n), kind="impacts", fontsize=7, fontweight="bold", ha="center", va="center",
               zorder=Z_ARROW + 2, bbox=dict(boxstyle="circle,pad=0.25", facecolor="#ffd54f", edgecolor="0.1", lw=1.0))
        S.add(xy)
        # each impact appears (in the animation) when it happens: the first at t = 0
        S.appear += [(a, t_mark) for a in (*S.ax.lines[first[0]:], *S.texts[first[1]:])]
    S.legend_entry("impacts in time order (1: the first; the report lists them)",
                   Line2D([], [], ls="none", marker="o", ms=9, mfc="#ffd54f", mec="0.1"))


def draw_barrier(S: SceneDrawing, lo, hi) -> None:
    """The barrier face through the contact point along the crush tangent, over its extent
    (endless: across the view), cut to the view widened by half its span on each side (so it
    never widens the view, and a later widening, as the animation's, stays covered)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Polygon

    sc = S.sc
    if not any(v.is_barrier for v in sc.vehicles):
        return
    surf = sc.impact.surface
    p0 = np.asarray(surf.point, dtype=float)
    t = np.asarray(surf.tangent, dtype=float)
    n = np.asarray(surf.normal, dtype=float)  # from the barrier into the vehicle
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    half = 0.5 * (hi - lo)
    blo, bhi = lo - half, hi + half
    reach = float(np.hypot(*(bhi - blo))) / S.k + float(np.hypot(*p0))  # metres: beyond the box either way
    extent = getattr(sc, "barrier_extent", None) or (-np.inf, np.inf)
    a, b = (max(float(extent[0]), -reach), min(float(extent[1]), reach))
    ends = S.d(np.array([p0 + a * t, p0 + b * t]))
    depth = 0.6 * S.k
    back = ends - depth * n
    name = next(v.bodies[0].name for v in sc.vehicles if v.is_barrier)
    poly = clip_polygon(np.vstack([ends, back[::-1]]), blo, bhi)
    if len(poly) >= 3:
        S.ax.add_patch(Polygon(poly, closed=True, facecolor="0.85", edgecolor="0.35", lw=0.0, hatch="////",
                               zorder=Z_BARRIER, gid=f"barrier:{name}"))
    for piece in clip_polyline(ends, blo, bhi):
        S.ax.plot(piece[:, 0], piece[:, 1], "-", color="0.15", lw=4.0, solid_capstyle="butt", zorder=Z_BARRIER + 0.5,
                  gid=f"barrier-face:{name}")
    S.legend_entry(f"barrier face ({name})", Line2D([], [], color="0.15", lw=4.0))
