"""Impacts on a time axis: every impact a line, impacts close in time one labelled band.

A run-out in which the vehicles bounce against each other has tens of impacts within a second;
one label per impact on the time-distance chart would need more rows than the panel has (and
labels were lost). :func:`group_times` joins impacts whose labels would touch into one group,
and :func:`mark_impacts` draws each impact's line, each group's band and one label per group
("impacts 5-12"), so that no impact is left out and no two labels overlap.
"""

from __future__ import annotations

__all__ = ["group_times", "group_label", "mark_impacts"]

#: Colours of the first impact and of the later ones.
FIRST, LATER = "#b30000", "#e07b00"


def group_times(times, gap: float) -> list[list[int]]:
    """Indices of ``times`` (ascending) in groups: a time less than ``gap`` after the first time of the
    current group joins it, else starts a new group.

    Examples
    --------
    >>> group_times([0.0, 0.1, 0.15, 1.0, 1.05, 3.0], 0.2)
    [[0, 1, 2], [3, 4], [5]]
    """
    groups: list[list[int]] = []
    start = None
    for i, t in enumerate(times):
        if start is None or t - start >= gap:
            groups.append([i])
            start = t
        else:
            groups[-1].append(i)
    return groups


def group_label(numbers) -> str:
    """``"impact"`` for the first impact alone, ``"impact 7"``, or ``"impacts 5-12"`` (runs of
    consecutive numbers, ``"impacts 3, 5-7"`` otherwise).

    Examples
    --------
    >>> group_label([5, 6, 7, 8]), group_label([1]), group_label([3, 5, 6])
    ('impacts 5-8', 'impact', 'impacts 3, 5-6')
    """
    numbers = sorted(numbers)
    if numbers == [1]:
        return "impact"
    if len(numbers) == 1:
        return f"impact {numbers[0]}"
    runs, a = [], numbers[0]
    for p, q in zip(numbers, numbers[1:] + [None]):
        if q != p + 1:
            runs.append(f"{a}" if a == p else f"{a}-{p}")
            a = q
    return "impacts " + ", ".join(runs)


def mark_impacts(label_ax, axes, impacts, *, halo=None, text_box=None) -> list:
    """Each impact ``(number, time [s])`` as a vertical line on every axes of ``axes`` (the first
    solid red, later ones dashed orange), impacts close in time as one shaded band with one label
    on ``label_ax`` (at its top, gid ``"td:impact:<numbers>"``, the numbers it stands for in the
    label's ``crashsim_impacts``). Labels that would still overlap go one row lower. The figure
    must be laid out (the grouping gap is the width of the widest label at the axes' scale).

    Returns
    -------
    list of matplotlib Annotation
        The labels, in time order.
    """
    fig = label_ax.figure
    impacts = sorted(impacts, key=lambda p: (p[1], p[0]))
    for number, ti in impacts:
        for axx in axes:
            axx.axvline(ti, color=FIRST if number == 1 else LATER, lw=1.0 if number == 1 else 0.8,
                        ls="-" if number == 1 else "--", zorder=1, gid=f"td:impact-line:{number}")
    fig.draw_without_rendering()
    r = fig.canvas.get_renderer()
    probe = label_ax.annotate(group_label([88, 99]), (0.0, 0.0), fontsize=7)
    width_px = probe.get_window_extent(r).width + 8.0
    probe.remove()
    x0, x1 = label_ax.get_xlim()
    frame = label_ax.get_window_extent(r)
    gap = width_px * (x1 - x0) / frame.width
    later = [p for p in impacts if p[0] != 1]
    groups = [[later[i] for i in g] for g in group_times([t for _, t in later], gap)]
    first = [p for p in impacts if p[0] == 1]
    groups = ([first] if first else []) + groups
    groups.sort(key=lambda g: g[0][1])
    labels, boxes = [], []
    for g in groups:
        numbers = [n for n, _ in g]
        t0, t1 = g[0][1], g[-1][1]
        color = FIRST if numbers == [1] else LATER
        if len(g) > 1:
            for axx in axes:
                axx.axvspan(t0, t1, color=LATER, alpha=0.14, lw=0, zorder=0.5, gid=f"td:impact-band:{numbers[0]}")
        label = label_ax.annotate(group_label(numbers), (t0, 1.0), xycoords=("data", "axes fraction"), xytext=(3, -10),
                                  textcoords="offset points", fontsize=7, color=color,
                                  gid=f"td:impact:{'-'.join(map(str, numbers))}", path_effects=halo)
        label.crashsim_impacts = numbers
        labels.append(label)
    fig.draw_without_rendering()
    for label in labels:
        for row in range(len(labels)):
            label.xyann = (3, -10 - 9 * row)
            bb = text_box(label, r) if text_box is not None else label.get_window_extent(r)
            if not any(bb.padded(3.0).overlaps(q) for q in boxes):
                break
        boxes.append(bb)
    return labels
