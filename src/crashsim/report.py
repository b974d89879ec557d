"""Readable reports of results, in SI or US customary units (an edge module: formats only)."""

from __future__ import annotations

import math
import re

import numpy as np

from .units import Kind, format_value, speed_unit_of, to_unit

__all__ = ["format_approach", "format_impact", "format_runout", "format_joint", "format_events", "format_evidence",
           "format_crush", "describe_event", "fmt", "table", "validity_text",
           "closing_error_text", "message_in", "LEDGER_BOUND"]


fmt = format_value  # an SI value in the display unit of a system (crashsim.units.format_value)

#: The energy ledger closes when its closing error is within this multiple of the run-out solver's
#: rtol, relative to the energy before the impact (1e-6 at the default rtol 1e-8; the shipped scenes
#: close to 1.2e-8 at most, and the engine fuzz tests hold every random scene to 1e-6).
LEDGER_BOUND = 100.0


def _vec(values, kind, system):
    """A vector in display units; components below 1e-9 of its largest are shown as 0."""
    v = [to_unit(x, kind, system) for x in values]
    label = v[0][1]
    big = max(abs(x) for x, _ in v)
    parts = ["0" if abs(x) <= 1e-9 * big else f"{x:.4g}" for x, _ in v]
    return (f"({', '.join(parts)}) {label}").rstrip()


def table(rows, align: str = "", indent: str = "  ") -> list[str]:
    """Rows of cells as aligned text lines (each column as wide as its widest cell).

    ``align``: one letter per column, ``"l"`` (default) or ``"r"``; trailing blanks are cut.
    """
    rows = [[str(c) for c in r] for r in rows]
    if not rows:
        return []
    n = max(len(r) for r in rows)
    rows = [r + [""] * (n - len(r)) for r in rows]
    widths = [max(len(r[i]) for r in rows) for i in range(n)]
    align = align.ljust(n, "l")
    out = []
    for r in rows:
        cells = [c.rjust(w) if a == "r" else c.ljust(w) for c, w, a in zip(r, widths, align)]
        out.append((indent + "  ".join(cells)).rstrip())
    return out


def _law_text(result) -> str:
    law = result.tangential_law
    frac = result.mu_fraction
    share = "n/a" if frac is None else f"{100 * frac:.1f} %"
    state = "sliding at separation" if result.sliding else "no sliding at separation"
    words = {"ratio": "given impulse ratio", "fraction": "impulse ratio as a share of mu_max",
             "no_slide": "no sliding at separation", "friction": "crush-surface friction"}.get(law, law)
    said = "" if state == words else f"; {state}"  # law no_slide says it once
    if result.slides_throughout:
        bound = (f"mu_max = {result.mu_max:.4f} is no bound (stopping the sliding would need a tensile normal "
                 "impulse: the contact slides throughout, friction against the initial slip)")
        return f"impulse ratio mu = {result.mu:.4f}; {bound} (law {law}: {words}{said})"
    return (f"impulse ratio mu = {result.mu:.4f}, mu_max = {result.mu_max:.4f}, mu / mu_max = {share} "
            f"(law {law}: {words}{said})")


def format_impact(result, system: str = "SI") -> str:
    """Multi-line text report of an :class:`~crashsim.impact.ImpactResult`."""
    s = system
    lines = []
    lines.append(f"Impact: {result.body1} (body 1) against {result.body2} (body 2)")
    lines.append(f"  crush surface normal {_vec(result.normal, 'dimensionless', s)}, "
                 f"tangent {_vec(result.tangent, 'dimensionless', s)}, point {_vec(result.point, 'length', s)}")
    lines.append(f"  closing velocity {fmt(-result.closing_velocity, 'speed', s)}; separation: normal "
                 f"{fmt(result.separation_normal_velocity, 'speed', s)}, tangential "
                 f"{fmt(result.separation_tangential_velocity, 'speed', s)}")
    lines.append("")
    rows = [["body", "velocity after", "yaw rate", "delta-v", "PDOF"]]
    for name, b in result.bodies.items():
        if b.fixed:
            continue
        pdof = "" if b.pdof is None else f"{math.degrees(b.pdof):.1f} deg ({b.clock} o'clock)"
        rows.append([name, _vec(b.velocity, 'speed', s), fmt(b.yaw_rate, 'angular_velocity', s),
                     fmt(b.delta_v_magnitude, 'speed', s), pdof])
    lines += table(rows)
    lines.append("")
    moment = 0.0 if abs(result.moment_impulse) < 1e-9 else result.moment_impulse
    lines.append(f"  crush impulse: normal {fmt(result.normal_impulse, 'impulse', s, 6)}, tangential "
                 f"{fmt(result.tangential_impulse, 'impulse', s, 6)}, moment {fmt(moment, 'moment_impulse', s)}")
    lines.append("  " + _law_text(result))
    for name, h in result.hitches.items():
        lock = "" if h.lock_moment is None else f"; yaw lock (C-dolly): moment {fmt(h.lock_moment, 'moment_impulse', s)}"
        lines.append(f"  hitch {name}: impulse on front body {_vec(h.impulse, 'impulse', s)} "
                     f"(longitudinal {fmt(h.longitudinal, 'impulse', s)}, lateral {fmt(h.lateral, 'impulse', s)}){lock}")
    for name, c in result.constraints.items():
        lines.append(f"  constraint {name!r} on {c.body}: impulse {fmt(c.impulse, 'impulse', s)}")
    for name, x in result.external.items():
        lines.append(f"  external impulse {name!r} on {x['body']}: {_vec(x['impulse'], 'impulse', s)}")
    lines.append("")
    rows = [["kinetic energy", "before", "after", "loss"]]
    for name, ke in result.kinetic_energy.items():
        if name not in result.energy_loss:
            continue
        loss = result.energy_loss[name]
        # a vehicle at rest before the impact has no energy to lose a share of: it gains what it takes
        share = (f"{100 * loss:.1f} %" if math.isfinite(loss)
                 else "n/a (at rest before)" if abs(ke['before']) <= 1e-12 * max(1.0, abs(ke['after']))
                 else "n/a")
        rows.append([name, fmt(ke['before'], 'energy', s), fmt(ke['after'], 'energy', s), share])
    lines += table(rows, "lrrr")
    lines.append(f"  condition number of the impulse equations: {result.condition_number:.3g}")
    for w in result.warnings:
        lines.append(f"  WARNING: {w}")
    return "\n".join(lines)


def _status_text(r, system: str) -> str:
    """Why a vehicle's run-out ended, in the display units."""
    if r.status == "rest":
        v_stop = (r.options or {}).get("v_stop")
        below = f" (all bodies below v_stop = {fmt(v_stop, 'speed', system)})" if v_stop is not None else ""
        return f"at rest after {fmt(r.t_end, 'time', system)}{below}"
    return f"{r.status} after {fmt(r.t_end, 'time', system)} ({message_in(r.message, system)})"


_SI_QUANTITY = re.compile(r"(?<![\w.])(-?\d+(?:\.\d+)?(?:e[+-]?\d+)?) (m/s|m|J|N s|N)(?![\w/^])")


def message_in(text: str, system: str = "SI") -> str:
    """A message written in SI (the run-out's stop reasons: ``"... 2.489 m/s > v_stop = 0.03 m/s"``)
    with its speeds, lengths, energies, impulses and forces in the display units of ``system``."""
    kinds = {"m/s": "speed", "m": "length", "J": "energy", "N s": "impulse", "N": "force"}
    if system == "SI":  # SI as written, but speeds in the speed unit of SI outputs ([scenario] speed_unit)
        if speed_unit_of(system) == "m/s":
            return text
        kinds = {"m/s": "speed"}
    return _SI_QUANTITY.sub(lambda m: fmt(float(m[1]), kinds[m[2]], system) if m[2] in kinds else m[0], text)


def format_runout(runout: dict, system: str = "SI", *, joint: bool = False) -> str:
    """Text report of the run-outs (dict vehicle name -> RunoutResult); ``joint``: one run-out of
    the whole scene (its method and work are stated once)."""
    s = system
    lines = ["Run-out to rest"]
    if joint and runout:
        r0 = next(iter(runout.values()))
        lines[0] += f" (one run-out of the whole scene: method {r0.method}, {r0.nfev} right-hand-side evaluations)"
    for vname, r in runout.items():
        how = "" if joint else f"; method {r.method}, {r.nfev} right-hand-side evaluations"
        lines.append(f"  vehicle {vname}: {_status_text(r, s)}{how}")
        if not r.success:
            lines.append(f"    NOT AT REST ({r.status}): the positions below are where the run stopped, not rest "
                         "positions")
        rows = []
        for name, b in r.bodies.items():
            ttr = "n/a" if b.time_to_rest is None else fmt(b.time_to_rest, "time", s)
            where = "rest at" if b.time_to_rest is not None else "stopped at"
            rows.append([name, where, _vec(b.rest_position, 'length', s),
                         f"heading {math.degrees(b.rest_heading_wrapped):.1f} deg",
                         f"travelled {fmt(b.distance, 'length', s)}", f"time to rest {ttr}"])
        lines += table(rows, indent="    ")
        if r.rollover is not None:
            lines.append(f"    {validity_text(r, s)}")
    return "\n".join(lines)


def validity_text(r, system: str = "SI") -> str:
    """What the wheel-lift and rollover check says of a vehicle's run-out (its ``rollover`` summary)."""
    roll = r.rollover
    thr = ", ".join(f"{b} {t:.3g} g" for b, t in roll["thresholds_g"].items())
    if roll["valid_until_s"] is None:
        return (f"wheel lift and rollover: no wheel lifts and no body passes its rollover threshold ({thr}); "
                "the planar run-out stays within its validity")
    first = min((e for e in r.events if e.t == roll["valid_until_s"] and "ltr" in e.data), key=lambda e: e.t)
    verdict = (f"ROLLS: {', '.join(roll['rolled_bodies'])} (threshold passed or all inner wheels off)"
               if roll["rolled"] else "wheels lift, no body passes its rollover threshold")
    return (f"wheel lift and rollover: {verdict}; the planar run-out is OUTSIDE ITS VALIDITY from "
            f"{fmt(roll['valid_until_s'], 'time', system)} ({first.kind} of {first.data['body']} at "
            f"{_vec(first.place, 'length', system)}, {fmt(first.data['speed_m_s'], 'speed', system)}); "
            f"thresholds {thr}")


def _impact_line(i, s: str, energy: bool = True) -> str:
    """One pair's part of an impact: bodies, approach, point, impulses, (energy,) delta-v, law."""
    dv = ", ".join(f"{b} {fmt(float(np.hypot(*d)), 'speed', s)}" for b, d in i.delta_v.items() if b in (i.body1, i.body2))
    approach = (f"closing {fmt(i.closing_speed, 'speed', s)}" if i.closing_speed >= 0 else
                f"separating at {fmt(-i.closing_speed, 'speed', s)} before it (pushed by the others)")
    lost = f"energy lost {fmt(i.energy_loss, 'energy', s)}; " if energy else ""
    return (f"{i.body1} against {i.body2}, {approach}, point {_vec(i.point, 'length', s)}, normal impulse "
            f"{fmt(i.normal_impulse, 'impulse', s)}, tangential {fmt(i.tangential_impulse, 'impulse', s)}, {lost}"
            f"delta-v {dv} (e = {i.restitution:g}, {i.law}{'' if i.law == 'frictionless' else f' f = {i.friction:g}'})")


def _impact_event_lines(ev, s: str) -> list[str]:
    """The lines of one impact event: one line for a single pair at a single instant; else a heading with
    the event's energy loss and a line per pair and instant (a pair's share of an instant's loss is not
    printed: with several points pushing each other, a share can be of either sign)."""
    first = ev.records[0]
    if len(ev.records) == 1:
        out = [f"  #{ev.number} at {fmt(first.t, 'time', s)}: {_impact_line(first, s)}"]
    else:
        when = (f"{len(ev.pairs)} pairs at once" if ev.instants == 1 else
                f"{len(ev.records)} impulses over {fmt(ev.records[-1].t - first.t, 'time', s)}")
        out = [f"  #{ev.number} at {fmt(first.t, 'time', s)} ({when}): energy lost {fmt(ev.energy_loss, 'energy', s)}"]
        for r in ev.records:
            at = "" if ev.instants == 1 else f"at {fmt(r.t, 'time', s)}: "
            out.append(f"      {at}{_impact_line(r, s, energy=False)}")
    out += [f"     {w}" for w in dict.fromkeys(r.warning for r in ev.records if r.warning)]
    return out


def format_joint(scene, system: str = "SI") -> str:
    """Later impacts, contacts, events and the energy ledger of a scene's joint run-out."""
    s = system
    j = scene.joint
    lines = []
    if j.impacts:
        lines.append("Impacts after the first (every point touching at an instant solved at once)")
        for ev in j.impact_events():
            lines += _impact_event_lines(ev, s)
    touched = [p for p in j.pairs if p.contact_time > 0 or p.impacts]
    if touched:
        lines.append("Contacts")
        for p in touched:
            if p.sustained:
                sustained = (f"sustained contact {fmt(p.contact_time, 'time', s)}, peak force "
                             f"{fmt(p.peak_force, 'force', s)}, deepest {fmt(p.max_penetration, 'length', s)} beyond "
                             f"the crush, work taken {fmt(-p.contact_work, 'energy', s)}")
            elif p.contact_time > 0:
                sustained = (f"in contact {fmt(p.contact_time, 'time', s)} until it separated, no sustained contact "
                             "force")
            else:
                sustained = "no sustained contact"
            lines.append(f"  {p.name}: {p.impacts} impact(s), {sustained}")
    ledger = scene.energy_ledger()
    if ledger:
        lines.append("Energy from the first impact to rest")
        labels = [("before_impact", "kinetic energy before the impact"), ("first_impact", "lost in the first impact"),
                  ("later_impacts", "lost in later impacts"), ("tyres", "tyre work"),
                  ("stops", "articulation-stop impacts"), ("contacts", "sustained contact"),
                  ("final", "kinetic energy left"), ("closing_error", "closing error")]
        if "potential" in ledger:  # a sloped road
            labels.insert(-2, ("potential", "potential energy gained (slope)"))
        for key, label in labels[:-1]:
            lines.append(f"  {label:<34} {fmt(ledger[key], 'energy', s):>14}")
        opts = getattr(getattr(scene.scenario, "runout", None), "options", None)
        lines.append(f"  {'closing error':<34} {closing_error_text(ledger, getattr(opts, 'rtol', 1e-8))}")
    return "\n".join(lines)


def closing_error_text(ledger: dict, rtol: float = 1e-8) -> str:
    """The energy ledger's closing error, relative to the energy before the impact, against a bound.

    The closing error is the integration error of the run-out's work terms: round-off and solver
    error of a ledger of megajoules, whose digits change with the processor numba compiled for and
    with a last-bit change of any input (a 1e-16 change of a speed moves it by up to 10 %; on the
    shipped scenes it is 1e-11 to 1.2e-8 of the energy at rtol 1e-8). What carries meaning is
    whether it stays within :data:`LEDGER_BOUND` x the solver's ``rtol`` (1e-6 at the default):
    "within 1e-6 of the energy before the impact"; beyond it the value is given (one digit), as a
    sign that the work terms are inaccurate. The JSON keeps the value in J.
    """
    before = float(ledger["before_impact"])
    err = abs(float(ledger["closing_error"]))
    if not (math.isfinite(err) and before > 0):
        return "n/a (no kinetic energy before the impact)" if math.isfinite(err) else "n/a (not finite)"
    rel = err / before
    bound = LEDGER_BOUND * float(rtol)
    mant, exp = f"{bound:.0e}".split("e")
    shown = f"{mant}e{int(exp)}"
    if rel <= bound:
        return f"within {shown} of the energy before the impact ({LEDGER_BOUND:g} x the solver's rtol)"
    return (f"{rel:.0e} of the energy before the impact: more than {shown} ({LEDGER_BOUND:g} x the solver's rtol), "
            "the run-out's work terms are inaccurate")


def describe_event(e, system: str = "SI") -> str:
    """What a run-out event did, in the display units of ``system`` (from its numbers; the
    event's own ``detail`` text, in SI, where it carries none)."""
    s, d = system, e.data
    a, b = (d.get("bodies") or [None, None])[:2]
    k = e.kind
    if k in ("zone_enter", "zone_exit") and "wheel" in d:
        f = f" (f = {d['friction']:g})" if "friction" in d else ""
        return f"wheel {d.get('label', d['wheel'])} {'enters' if k == 'zone_enter' else 'leaves'} zone {d['zone']!r}{f}"
    if k in ("stop_closed", "stop_impact") and "angle_rad" in d:
        how = "closes" if k == "stop_closed" else "struck and left"
        return (f"articulation stop of hitch {d['hitch']} {how} at {math.degrees(d['angle_rad']):+.1f} deg "
                f"(impact dissipates {fmt(e.energy, 'energy', s)})")
    if k == "vehicle_rest" and "v_stop_m_s" in d:
        return f"vehicle {d['vehicle']} at rest (all bodies below v_stop = {fmt(d['v_stop_m_s'], 'speed', s)})"
    if k == "rest" and "v_stop_m_s" in d:
        return f"every vehicle at rest (all bodies below v_stop = {fmt(d['v_stop_m_s'], 'speed', s)})"
    if k == "armed" and "arm_distance_m" in d:
        return f"{a} and {b} have separated by {fmt(d['arm_distance_m'], 'length', s)}: a later touch is an impact"
    if k == "contact" and "threshold_m_s" in d:
        return (f"{a} touches {b} at {fmt(d['speed_m_s'], 'speed', s)} (below the impulse threshold "
                f"{fmt(d['threshold_m_s'], 'speed', s)}): sustained contact")
    if k == "contact_pressed" and "depth_m" in d:
        return (f"{a} is pressed into {b} beyond the crush of the impact ({fmt(d['depth_m'], 'length', s)} deep): "
                "sustained contact")
    if k in ("wheel_lift", "unit_lift", "rollover_threshold") and "ltr" in d:
        at = f"at {fmt(d['speed_m_s'], 'speed', s)}, lateral acceleration {abs(d['lateral_acceleration_g']):.3g} g"
        if k == "wheel_lift":
            return f"{d['lifting_side']} wheel of axle {d['axle']!r} of {d['body']} lifts (axle load transfer ratio 1), {at}"
        if k == "unit_lift":
            return f"all {d['lifting_side']} wheels of {d['body']} lift (load transfer ratio {d['ltr']:+.3f}), {at}"
        return f"{d['body']} passes its rollover threshold {d['threshold_g']:.3g} g, {at}"
    if k == "impact" and "delta_v_m_s" in d:
        dv = ", ".join(f"{n} {fmt(v, 'speed', s)}" for n, v in d["delta_v_m_s"].items())
        how = (f"{a} strikes {b} at {fmt(d['speed_m_s'], 'speed', s)}" if d["speed_m_s"] >= 0 else
               f"{a} is pushed against {b} (parting at {fmt(-d['speed_m_s'], 'speed', s)} before)")
        many = d.get("pairs_at_once", 1)
        # numbered as the figures and the impact table number it (an event may span instants)
        lost = (f"impact {d['event']}: {fmt(e.energy, 'energy', s)} lost" if many == 1 else
                f"impact {d['event']}: {many} pairs at once, {fmt(d['instant_energy_J'], 'energy', s)} lost in all")
        return f"{how}: normal impulse {fmt(d['normal_impulse_N_s'], 'impulse', s)}, delta-v {dv}, {lost}"
    return message_in(e.detail, s)


def format_events(events, system: str = "SI", title: str = "Run-out events") -> str:
    """The run-out's events, one line each: time, kind, place (world frame) and what happened."""
    rows = [["time", "event", "place", "what"]]
    for e in events:
        place = "" if e.place is None else _vec(e.place, "length", system)
        rows.append([fmt(e.t, 'time', system), e.kind, place, describe_event(e, system)])
    return "\n".join([title] + table(rows, "r"))


def rollover_cells(c) -> tuple[str, str]:
    """The residual and tolerance cells of a rollover statement (a verdict, not a number)."""
    res = ("computed: " + ("rolls" if c.details["computed"] else "does not roll")
           if "computed" in c.details else "none computed")
    return res, "the statement must hold"


def format_evidence(report, system: str = "SI", labels: dict | None = None) -> str:
    """Text table of evidence residuals and verdicts; ``labels`` names the wheels (key -> the axle's name
    from the file, :func:`crashsim.motion.wheels.wheel_labels`)."""
    labels = labels or {}
    s = system
    lines = [f"Evidence: {len(report.checks) - report.n_failed} of {len(report.checks)} items within tolerance"]
    rows = []
    for c in report.checks:
        if c.kind == "rollover":
            res, tol = rollover_cells(c)
            rows.append(["PASS" if c.passed else "FAIL", c.kind, c.name, res, tol, c.details.get("reason", "")])
            continue
        if c.quantity == "angle":
            res, tol = f"{math.degrees(c.residual):+.1f} deg", f"{math.degrees(c.tolerance):.1f} deg"
        elif math.isinf(c.residual):
            res, tol = "none computed", fmt(c.tolerance, c.quantity, s)
        else:
            res, tol = fmt(c.residual, c.quantity, s), fmt(c.tolerance, c.quantity, s)
        extra = ""
        if "matched_wheel" in c.details:
            extra = f"closest track: {labels.get(c.details['matched_wheel'], c.details['matched_wheel'])}"
        elif "reason" in c.details:
            extra = c.details["reason"]
        elif c.kind == "recorder":
            k = c.details["worst_sample"]
            n, left = c.details.get("n_compared", len(c.details["times"])), ""
            if n < len(c.details["times"]):
                left = f" ({len(c.details['times']) - n} after the impact with its time_offset, not compared)"
            extra = (f"worst of {n} samples at {fmt(c.details['times'][k], 'time', s)}{left}: "
                     f"recorded {fmt(c.details['recorded'][k], 'speed', s)}, computed "
                     f"{fmt(c.details['computed'][k], 'speed', s)}")
        rows.append(["PASS" if c.passed else "FAIL", c.kind, c.name, f"residual {res}", f"tolerance {tol}", extra])
    lines += table(rows)
    return "\n".join(lines)


#: What each crush comparison compares, for the report.
_CRUSH_COMPARE = {"total": "crush energies with the force-direction factor against the whole loss at the crush "
                           "surface T_n + T_t + T_M",
                  "normal": "crush energies without the force-direction factor against the normal and moment "
                            "parts T_n + T_M (Brach & Brach's partition)"}


def _mean_depth(profile) -> float:
    """Mean crush depth over the damage width [m]: the area of the piecewise-linear profile over its width."""
    return sum(a + b for a, b in zip(profile[:-1], profile[1:])) / (2 * (len(profile) - 1))


def format_crush(report, system: str = "SI") -> str:
    """The crush-energy section: per body its CRASH3 inputs (the profile as its count, its mean depth over
    the width and its largest depth), force-direction factor, energy and EES;
    per group the impacts' energy loss split into normal, tangential and moment work, and the verdict."""
    s = system
    E = lambda v: fmt(v, "energy", s, 6)  # noqa: E731
    deg = lambda a: "n/a" if a is None else f"{math.degrees(a):.1f} deg"  # noqa: E731
    lines = ["Crush energy (CRASH3; docs/crush-energy.md)"]
    for c in report.checks:
        if c.kind != "crush energy":
            continue
        d = c.details
        lines.append(f"  {c.name}: {_CRUSH_COMPARE[d['compare']]}")
        rows = [["body", "face", "A", "B", "width", "profile", "PDOF", "alpha", "factor", "energy", "EES"]]
        for name, b in d["bodies"].items():
            for it in b["items"]:
                if "ees_given" in it:
                    inputs = ["", "", "", f"EES given {fmt(it['ees_given'], 'speed', s)}"]
                else:
                    prof = it["profile"]
                    inputs = [fmt(it["A"], "force_per_length", s, 6), fmt(it["B"], "force_per_area", s, 6),
                              fmt(it["width"], "length", s),
                              f"{len(prof)} points, mean {fmt(_mean_depth(prof), 'length', s, 3)}, "
                              f"max {fmt(max(prof), 'length', s, 3)}"]
                factor = "none (EES)" if "ees_given" in it else (
                    f"{it['factor']:.4f}" + (" (capped)" if it["factor_capped"] else ""))
                rows.append([name, it["face"], *inputs, deg(it["pdof"]), deg(it["alpha"]), factor, E(it["energy"]),
                             ""])
            rows.append([name, "total", "", "", "", "", "", "", "", E(b["energy"]), fmt(b["ees"], "speed", s)])
        lines += table(rows, "llrrrlrrrrr", indent="    ")
        for name, b in d["bodies"].items():
            for it in b["items"]:
                if it["source"] != "given in the scenario" and "ees_given" not in it:
                    lines.append(f"    {name} {it['face']}: A and B from {it['source']}")
        if "impacts_counted" in d:
            rows = [["impact", "time", "kinetic loss", "normal T_n", "tangential T_t", "moment T_M", "T_n + T_t + T_M"]]
            for x in d["impacts_counted"]:
                rows.append([f"{x['body1']} / {x['body2']}", fmt(x["time"], "time", s), E(x["energy_loss"]),
                             E(x["normal"]), E(x["tangential"]), E(x["moment"]), E(x["crush_surface"])])
            lines += table(rows, "llrrrrr", indent="    ")
            ratio = "" if d["ratio"] is None else f" (crush / loss = {d['ratio']:.3f})"
            lines.append(f"    model loss {E(d['computed'])} against crush energy {E(d['measured'])}{ratio}: residual "
                         f"{E(c.residual)}, tolerance {E(c.tolerance)}: {'PASS' if c.passed else 'FAIL'}")
            if not d["complete"]:
                lines.append(f"    only part of the pair has a crush item (none for {', '.join(d['missing'])}): the crush "
                             "energy is a lower bound of the energy absorbed, so the check is one-sided (it fails only "
                             "if the crush energy exceeds the loss by more than the tolerance)")
        else:
            lines.append(f"    not compared: {d['reason']}")
        for w in d["warnings"]:
            lines.append(f"    WARNING: {w}")
    return "\n".join(lines)


def format_approach(approaches: dict, system: str = "SI") -> str:
    """The approaches before the impact: one block per vehicle (speeds, times, distances, placement)."""
    s = system
    lines = ["Approach before the impact (simulated from the start of braking; constant speed before it)"]
    for name, a in approaches.items():
        how = {"distance": "braking distance given", "time": "braking time given",
               "start": "start position given", "path": "driven along a path from a distance given",
               "recorded": "driven by a recorder's table from its first sample"}[a.mode]
        speed_note = ("the table's first" if a.speed_control is not None
                      else "solved from the speed at impact" if a.speed_solved else "given")
        lines.append(f"  vehicle {name} ({how}; speed at braking {speed_note})")
        rows = [
            ["speed at the start of braking", fmt(a.speed_at_braking, "speed", s)],
            ["speed at impact", fmt(a.speed_at_impact, "speed", s)],
            ["perception-reaction time", fmt(a.reaction_time, "time", s),
             f"distance {fmt(a.reaction_distance, 'length', s)} at constant speed"],
            ["from the start of braking to impact", fmt(a.time_to_impact, "time", s),
             f"distance {fmt(a.distance, 'length', s)} (CG path of the first body)"],
            ["from perception to impact", fmt(a.reaction_time + a.time_to_impact, "time", s),
             f"distance {fmt(a.reaction_distance + a.distance, 'length', s)}"],
            ["start of braking, first body's CG", _vec(a.braking_start[next(iter(a.braking_start))], "length", s)],
            ["perception point, first body's CG", _vec(a.perception_point, "length", s)],
        ]
        if any(a.start_articulation):
            rows.append(["articulation at the start", ", ".join(f"{math.degrees(x):.1f} deg" for x in a.start_articulation)])
        if a.articulation_at_impact:
            rows.append(["articulation at impact (approach)",
                         ", ".join(f"{math.degrees(x):.1f} deg" for x in a.articulation_at_impact)])
        if a.steering is not None:
            st = a.steering
            before = st["t"] <= 1e-12
            peak = float(np.max(np.abs(st["delta"][before]))) if np.any(before) else 0.0
            if a.mode == "recorded":
                rows.append(["recorded steering", f"{math.degrees(peak):.1f} deg",
                             "largest steer angle of the first axle's centre (steering-wheel angle / ratio)"])
            else:
                rows.append(["driver (pure pursuit), path error", fmt(a.max_lateral_error, "length", s),
                             "largest offset of the rear axles' centre from the path; largest steer "
                             f"{math.degrees(peak):.1f} deg"])
        if a.speed_control is not None:
            rows.append(["recorded speeds, followed within", fmt(a.max_speed_error, "speed", s),
                         "largest difference of the CG speed from the table's (speed controller)"])
        if a.mode in ("start", "path"):
            rows.append(["miss of the impact position", fmt(a.miss, "length", s),
                         f"heading off by {math.degrees(a.heading_miss):+.1f} deg"])
        lines += table(rows, indent="    ")
    return "\n".join(lines)
