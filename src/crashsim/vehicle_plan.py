"""A body of the vehicle library drawn to scale in plan view: outline, axles with their tyres,
hitch points and the CG, dimensioned in the user's units (``crashsim presets --plot NAME``).

The drawing takes the validated SI geometry of one body (:func:`crashsim.scenario.preset_geometry`
gives it for a preset): ``length``, ``width``, ``outline_center``, ``axles`` (``x``, ``track``,
``dual``, ``name``), ``front_hitch``, ``rear_hitch``, ``cg_height``, ``articulation_limit``.
"""

from __future__ import annotations

import numpy as np

from .units import format_value

__all__ = ["plot_body_plan", "geometry_lines"]

#: Drawn size of one tyre [m]: the contact patch of a truck or car tyre, about 1.0 m x 0.3 m.
TYRE_LENGTH, TYRE_WIDTH = 1.0, 0.3
#: A short body's tyres are drawn at most this share of its length long (a motorcycle's 2.2 m would
#: otherwise show two 1 m tyres that touch), and at most this share of its closest axle spacing (a
#: travel trailer's tandem 0.86 m apart); no wider than its track (a narrow-track axle shows its two
#: contacts side by side as one tyre).
TYRE_LENGTH_SHARE, TYRE_SPACING_SHARE = 0.25, 0.8


def tyre_size(g: dict, track: float) -> tuple[float, float]:
    """Drawn (length, width) [m] of one tyre of an axle of ``track`` on the body of geometry ``g``."""
    length = TYRE_LENGTH if g.get("length") is None else min(TYRE_LENGTH, TYRE_LENGTH_SHARE * g["length"])
    xs = sorted(a["x"] for a in g.get("axles") or [])
    gaps = [b - a for a, b in zip(xs, xs[1:]) if b > a]
    if gaps:
        length = min(length, TYRE_SPACING_SHARE * min(gaps))
    return length, min(TYRE_WIDTH, track)


def geometry_lines(g: dict, system: str = "SI") -> list[str]:
    """The geometry of one body as text lines in ``system`` units (SI or US): length, width, outline
    centre, CG height, each axle's position and track, the hitch points, the articulation limit."""
    def L(x):
        return format_value(x, "length", system)

    lines = []
    if g.get("length") is not None and g.get("width") is not None:
        cx, cy = g["outline_center"]
        lines.append(f"length {L(g['length'])}, width {L(g['width'])}, outline centre ({L(cx)}, {L(cy)}) from the CG")
    lines.append(f"CG height {L(g['cg_height'])}" if g.get("cg_height") is not None else "CG height not given")
    for a in g.get("axles") or []:
        dual = ", dual tyres" if a["dual"] else ""
        lines.append(f"axle {a['name']!r}: x {L(a['x'])} from the CG (forward +), track {L(a['track'])}{dual}")
    for key, what in (("front_hitch", "front hitch (kingpin, drawbar eye)"), ("rear_hitch", "rear hitch (fifth wheel, "
                                                                                           "ball, pintle)")):
        if g.get(key) is not None:
            x, y = g[key]
            lines.append(f"{what}: ({L(x)}, {L(y)}) from the CG")
    if g.get("articulation_limit") is not None:
        lines.append(f"articulation limit {format_value(g['articulation_limit'], 'angle', system)}")
    if g.get("yaw_locked"):
        lines.append("front hitch yaw-locked to the body ahead (C-dolly: no articulation)")
    return lines


def plot_body_plan(g: dict, ax=None, *, title: str | None = None, system: str = "SI"):
    """Draw one body to scale (equal axes) in plan view, x forward to the right, with dimension lines.

    Parameters
    ----------
    g
        Validated SI geometry of the body (see the module notes).
    ax
        Matplotlib axes to draw into (a new figure when None).
    title
        Figure title (default: the body's ``name``).
    system
        ``"SI"`` or ``"US"``: units of the dimension labels and the axis labels.

    Returns
    -------
    matplotlib.axes.Axes
    """
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, Polygon, Rectangle

    if ax is None:
        _, ax = plt.subplots(figsize=(10, 5), layout="constrained")
    L, W = g.get("length"), g.get("width")
    cx, cy = g.get("outline_center") or (0.0, 0.0)
    if L is not None and W is not None:
        corners = np.array([[cx + L / 2, cy + W / 2], [cx - L / 2, cy + W / 2], [cx - L / 2, cy - W / 2],
                            [cx + L / 2, cy - W / 2]])
        ax.add_patch(Polygon(corners, closed=True, facecolor="#dde6f0", edgecolor="#1f3b5a", lw=1.5,
                             label="outline", gid="outline"))
    for a in g.get("axles") or []:
        tl, tw = tyre_size(g, a["track"])
        for side in (1, -1):
            y = side * a["track"] / 2
            ax.add_patch(Rectangle((a["x"] - tl / 2, y - tw / 2), tl, tw,
                                   facecolor="#333333", edgecolor="none", gid=f"tyre {a['name']}"))
        ax.plot([a["x"], a["x"]], [-a["track"] / 2, a["track"] / 2], color="#333333", lw=1.2)
        ax.annotate(a["name"] or "axle", (a["x"], -a["track"] / 2 - tw), ha="center", va="top", fontsize=8)
    ax.add_patch(Circle((0, 0), 0.12, facecolor="white", edgecolor="black", zorder=5))
    ax.plot([0], [0], "k+", ms=10, zorder=6, label="CG")
    for key, colour, text in (("front_hitch", "#c0392b", "front hitch"), ("rear_hitch", "#27ae60", "rear hitch")):
        if g.get(key) is not None:
            x, y = g[key]
            ax.plot([x], [y], "o", color=colour, ms=8, zorder=6, label=text, gid=key)
    # dimension lines: overall length above, axle positions from the front below
    if L is not None and W is not None:
        top = cy + W / 2 + 0.6
        ax.annotate("", (cx - L / 2, top), (cx + L / 2, top), arrowprops={"arrowstyle": "<->", "lw": 0.8})
        ax.text(cx, top + 0.1, f"length {format_value(L, 'length', system)}", ha="center", va="bottom", fontsize=9)
        # beyond a coupler ahead of the box (a trailer's A-frame), which the label would cover
        ahead = max([cx + L / 2] + [g[k][0] for k in ("front_hitch", "rear_hitch") if g.get(k) is not None])
        right = ahead + 0.4
        ax.annotate("", (right, cy - W / 2), (right, cy + W / 2), arrowprops={"arrowstyle": "<->", "lw": 0.8})
        ax.text(right + 0.1, cy, f"width\n{format_value(W, 'length', system)}", ha="left", va="center", fontsize=9)
        front = cx + L / 2
        low = cy - W / 2 - 0.9
        for a in g.get("axles") or []:
            ax.annotate("", (a["x"], low), (front, low), arrowprops={"arrowstyle": "<->", "lw": 0.5, "color": "0.4"})
            low -= 0.45
            # centred on its arrow, which lies inside the drawing (on a short body a label beside the
            # arrow's end ran out of the axes)
            ax.text((a["x"] + front) / 2, low + 0.47, f"{format_value(front - a['x'], 'length', system, 3)} from the front",
                    ha="center", va="bottom", fontsize=7, color="0.3")
    ax.set_aspect("equal")
    ax.autoscale_view()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    if L is not None and W is not None:  # the dimension lines are annotations: autoscale leaves them out
        x0, x1 = min(x0, cx - L / 2), max(x1, right + 1.2)
        y0, y1 = min(y0, low - 0.2), max(y1, top + 0.6)
    ax.set_xlim(x0 - 0.5, x1 + 0.5)
    ax.set_ylim(y0 - 0.3, y1 + 0.3)
    ax.set_xlabel("x from the CG, forward [m]")
    ax.set_ylabel("y, left [m]")
    ax.set_title(title if title is not None else str(g.get("name", "")))
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.22), fontsize=8, ncols=4, frameon=False)
    ax.grid(True, lw=0.3, alpha=0.5)
    return ax
