"""The suite's results as text, JSON, CSV, error summaries per case class, and one figure per case.

Values are shown in the unit system of each quantity's published source (US customary where the
source is US: Day2004's rest positions, the MASH report, FMVSS 121, SAE J695) unless a system is
asked for. Errors of ``relative`` and ``range`` metrics are percentages; an energy loss (a fraction of
the kinetic energy before the impact) is in percent of it, its error in percentage points.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

from ..units import format_value, to_unit
from .core import STATUS, CaseResult, Quantity

__all__ = ["value_text", "error_text", "band_text", "table_text", "summaries", "summary_text", "summary_value_text",
           "write_csv", "results_dict", "plot_case"]


def _system(q: Quantity, system: str | None) -> str:
    return system or q.display


def value_text(q: Quantity, value: float, system: str | None = None) -> str:
    """A measured or computed value of ``q`` with its unit."""
    if q.metric == "criterion":
        return "holds" if value >= 0.5 else "fails"
    if not math.isfinite(value):
        return "n/a"
    if q.kind == "dimensionless":
        return f"{100 * value:.1f} %"
    return format_value(value, q.kind, _system(q, system), 4)


def _diff(q: Quantity, x: float, system: str | None) -> str:
    if q.kind == "dimensionless":
        return f"{100 * x:+.1f} pts"
    if q.kind == "angle":
        return f"{math.degrees(x):+.1f} deg"
    v, unit = to_unit(x, q.kind, _system(q, system))
    return f"{v:+.3g} {unit}"


def _percent(x: float, sign: str) -> str:
    """A fraction as a percentage: two decimals below 10 %, one above."""
    return f"{100 * x:{sign}.2f} %" if abs(x) < 0.1 else f"{100 * x:{sign}.1f} %"


def error_text(q: Quantity, system: str | None = None) -> str:
    """The error by the quantity's metric."""
    if not math.isfinite(q.error):
        return "n/a"
    if q.metric in ("relative", "range"):
        return _percent(q.error, "+")
    if q.metric == "criterion":
        return "0" if q.error == 0 else "1"
    return _diff(q, q.error, system)


def band_text(q: Quantity, system: str | None = None) -> str:
    """The band: +- half-width, or the one-sided limit."""
    if q.metric == "limit":
        return "<= 0"
    if q.metric == "criterion":
        return "holds"
    if q.metric in ("relative", "range"):
        return "+-" + _percent(q.band, "")
    return "+-" + _diff(q, q.band, system).lstrip("+")


def _anchor_text(q: Quantity, system: str | None = None) -> str:
    parts = []
    for name, e in q.anchors.items():
        if q.metric in ("relative", "range"):
            parts.append(f"{name} {100 * e:+.1f} %")
        else:
            parts.append(f"{name} {_diff(q, e, system)}")
    return "; ".join(parts)


def _pair(q: Quantity, system: str | None) -> tuple[str, str]:
    """The measured and computed columns (a range metric: the measured path length, the computed miss)."""
    if q.metric == "range":
        return f"path {value_text(q, q.measured, system)}", f"{value_text(q, q.computed, system)} off"
    return value_text(q, q.measured, system), value_text(q, q.computed, system)


def _rows(results, system):
    for r in results:
        for q in r.quantities:
            yield r, q, [r.id, q.name, *_pair(q, system), error_text(q, system), band_text(q, system), q.status]


def table_text(results: list[CaseResult], system: str | None = None) -> str:
    """The plain-text table of every quantity, with a count line and the summary per class."""
    header = ["case", "quantity", "measured", "computed", "error", "band", "status"]
    rows = [row for _, _, row in _rows(results, system)]
    widths = [max(len(str(x)) for x in col) for col in zip(header, *rows)] if rows else [len(h) for h in header]
    lines = ["  ".join(str(x).ljust(w) for x, w in zip(header, widths)).rstrip()]
    lines += ["  ".join(str(x).ljust(w) for x, w in zip(row, widths)).rstrip() for row in rows]
    qs = [q for r in results for q in r.quantities]
    counts = {s: sum(q.status == s for q in qs) for s in STATUS}
    cpu = sum(r.cpu_seconds for r in results)
    lines += ["", f"{len(results)} cases, {len(qs)} quantities: {counts[STATUS[0]]} within their band, "
              f"{counts[STATUS[1]]} documented misses (why: validation/<case>/README.md), {counts[STATUS[2]]} new misses, "
              f"{counts[STATUS[3]]} documented misses now within (record stale); CPU {cpu:.1f} s",
              "", summary_text(results, system)]
    return "\n".join(lines).rstrip() + "\n"


def summaries(results: list[CaseResult]) -> list[dict]:
    """Errors per case class, result group and metric: count, mean and largest |error|, count within."""
    groups: dict[tuple, list[Quantity]] = {}
    classes = {}
    for r in results:
        for q in r.quantities:
            groups.setdefault((r.case_class, q.group, q.metric), []).append(q)
            classes[q.case] = r.case_class
    out = []
    for (cls, group, metric), qs in groups.items():
        errs = [abs(q.error) for q in qs if math.isfinite(q.error)]
        out.append({"class": cls, "group": group, "metric": metric, "kind": qs[0].kind, "display": qs[0].display,
                    "n": len(qs), "cases": sorted({q.case for q in qs}),
                    "mean_abs_error": sum(errs) / len(errs) if errs else math.nan,
                    "max_abs_error": max(errs) if errs else math.nan,
                    "within": sum(q.within for q in qs), "band_basis": sorted({q.basis.split(":")[0] for q in qs})})
    return out


def summary_value_text(s: dict, x: float, system: str | None = None) -> str:
    """A summary row's error (mean or largest |error|) as text, by its metric: % or the unit shown."""
    if x is None or not math.isfinite(x):
        return "n/a"
    if s["metric"] in ("relative", "range"):
        return f"{100 * x:.1f} %"
    if s["metric"] == "criterion":
        return f"{x:.0f}"
    q = Quantity("", "", s["group"], s["kind"], 0.0, 0.0, s["metric"], x, 0.0, "", "", display=s["display"])
    return _diff(q, x, system).lstrip("+")


def summary_text(results: list[CaseResult], system: str | None = None) -> str:
    """The errors per case class and group, as text."""
    lines = ["Errors per case class (mean and largest |error| over the quantities; within: inside their bands)"]
    rows = [[s["class"], s["group"], str(s["n"]), summary_value_text(s, s["mean_abs_error"], system),
             summary_value_text(s, s["max_abs_error"], system), f"{s['within']}/{s['n']}", ", ".join(s["cases"])]
            for s in summaries(results)]
    header = ["class", "result", "n", "mean |error|", "largest", "within", "cases"]
    widths = [max(len(x) for x in col) for col in zip(header, *rows)]
    lines.append("  " + "  ".join(h.ljust(w) for h, w in zip(header, widths)).rstrip())
    lines += ["  " + "  ".join(x.ljust(w) for x, w in zip(row, widths)).rstrip() for row in rows]
    return "\n".join(lines)


def write_csv(results: list[CaseResult], path: Path, system: str | None = None) -> Path:
    """One row per quantity: the text columns, the SI values and the band's basis."""
    path = Path(path)
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["case", "class", "quantity", "group", "metric", "measured", "computed", "error", "band", "status",
                "measured_si", "computed_si", "error_si_or_fraction", "band_si_or_fraction", "basis", "source",
                "anchors", "note"])
    for r, q, row in _rows(results, system):
        w.writerow([r.id, r.case_class, q.name, q.group, q.metric, row[2], row[3], row[4], row[5], q.status,
                    f"{q.measured:.6g}", f"{q.computed:.6g}", f"{q.error:.6g}", f"{q.band:.6g}", q.basis, q.source,
                    _anchor_text(q, system), q.note])
    path.write_text(buf.getvalue(), encoding="utf-8")
    return path


def results_dict(results: list[CaseResult]) -> dict:
    """The JSON of ``crashsim validate --json`` (SI; fractions for relative errors)."""
    qs = [q for r in results for q in r.quantities]
    return {"cases": [r.to_dict() for r in results], "summary": summaries(results),
            "counts": {s: sum(q.status == s for q in qs) for s in STATUS},
            "cpu_seconds": sum(r.cpu_seconds for r in results)}


# ------------------------------------------------------------------ figures
_COLOURS = {STATUS[0]: "#1a7f37", STATUS[1]: "#bf8700", STATUS[2]: "#cf222e", STATUS[3]: "#8250df"}
_CLIP = 4.0


def _score(q: Quantity) -> float:
    """The error in units of its band half-width (limits: of 25 % of the limit; criteria: 0 or 2)."""
    if q.metric == "criterion":
        return 0.0 if q.error == 0 else 2.0
    if q.metric == "limit":
        return q.error / (0.25 * abs(q.measured))
    return q.error / q.band if q.band > 0 else (0.0 if q.error == 0 else math.copysign(_CLIP, q.error))


def _forest(ax, result: CaseResult, system: str | None):
    qs = list(result.quantities)
    n = len(qs)
    for i, q in enumerate(qs):
        y = n - 1 - i
        if q.metric == "limit":
            ax.fill_betweenx([y - 0.35, y + 0.35], -_CLIP, 0, color="#d0e8ff", lw=0)
        else:
            ax.fill_betweenx([y - 0.35, y + 0.35], -1, 1, color="#d0e8ff", lw=0)
        for name, e in q.anchors.items():
            if q.band > 0 and q.metric not in ("limit", "criterion") and math.isfinite(e):
                ax.plot(max(-_CLIP, min(_CLIP, e / q.band)), y, marker="d", ms=4, color="#8c959f", ls="none")
        s = _score(q)
        x = max(-_CLIP, min(_CLIP, s)) if math.isfinite(s) else _CLIP
        ax.plot(x, y, marker="o", ms=6, color=_COLOURS.get(q.status, "k"), ls="none", zorder=3)
        if abs(s) > _CLIP:
            ax.annotate("", xy=(math.copysign(_CLIP + 0.35, s), y), xytext=(x, y),
                        arrowprops={"arrowstyle": "->", "color": _COLOURS.get(q.status, "k")})
        m, c = _pair(q, system)
        ax.text(_CLIP + 0.8, y, f"{m} -> {c}: {error_text(q, system)} (band {band_text(q, system)})", va="center",
                fontsize=7)
    ax.axvline(0, color="k", lw=0.6)
    ax.set_yticks(range(n))
    ax.set_yticklabels([q.name for q in reversed(qs)], fontsize=7)
    ax.set_xlim(-_CLIP - 0.5, _CLIP + 0.5)
    ax.set_ylim(-0.7, n - 0.3)
    ax.set_xlabel("error / band half-width (limits: error / 25 % of the limit)\nshaded: the band; dots: green within, "
                  "amber documented miss,\nred new miss; grey diamonds: published methods' errors", fontsize=7)
    ax.tick_params(axis="x", labelsize=7)


def _plan(ax, result: CaseResult, system: str | None):
    """A plan view where the case has positions: run-outs against rest positions, circles, stops."""
    fig = result.figure
    scale, unit = (1 / 0.3048, "ft") if (system or "US") == "US" else (1.0, "m")
    if "rest_runs" in fig:
        styles = {"from measured separation": "-", "end to end": "--"}
        for label, run in fig["rest_runs"].items():
            for v, r in run.runout.items():
                for b in r.bodies.values():
                    h = b.history
                    ax.plot(h.x * scale, h.y * scale, styles[label], lw=1, label=f"{b.name}, {label}")
        import matplotlib.patches as mpatches

        for k, p in enumerate(fig["rest_measured"]):
            ax.plot(p[0] * scale, p[1] * scale, "kx", ms=8, mew=2, label="measured rest (Day2004)" if k == 0 else None)
            q = next(q for q in result.quantities if q.metric == "range" and q.name.endswith("(end to end)")
                     and q.name.startswith("rest position") and q.name.split(", ")[1].split(" (")[0] ==
                     list(fig["rest_runs"]["end to end"].runout)[k])
            ax.add_patch(mpatches.Circle((p[0] * scale, p[1] * scale), q.band * q.measured * scale, fill=False,
                                         ls=":", color="k", label="its band" if k == 0 else None))
        ax.set_title("CG paths to rest; the test's frame recovered as README.md says", fontsize=8)
    elif "scene" in fig:
        scene = fig["scene"]
        for v, r in scene.runout.items():
            for b in r.bodies.values():
                ax.plot(b.history.x * scale, b.history.y * scale, "-", lw=1, label=f"{b.name} CG, computed")
        import matplotlib.patches as mpatches

        x, y = fig["rest_measured"]
        p = scene.impact.point
        ax.plot((p[0] + x) * scale, (p[1] + y) * scale, "kx", ms=8, mew=2, label="measured rest")
        bx = next(q.band for q in result.quantities if q.name == "rest position downstream")
        by = next(q.band for q in result.quantities if q.name == "rest position toward traffic")
        ax.add_patch(mpatches.Rectangle(((p[0] + x - bx) * scale, (p[1] + y - by) * scale), 2 * bx * scale,
                                        2 * by * scale, fill=False, ls=":", color="k", label="its band"))
        ax.axhline(0, color="0.3", lw=2, label="barrier face")
        ax.set_title("CG path to rest against the measured rest position", fontsize=8)
    elif "trailer" in fig:
        for key, style in (("front", "-"), ("trailer", "--")):
            x, y = fig[key]
            ax.plot(x * scale, y * scale, style, lw=0.8, label=f"{key} axle centre")
        ax.set_title(f"axle paths; off-tracking {(fig['r_front'] - fig['r_trailer']) * scale:.2f} {unit} against the "
                     f"closed form's {fig['expected'] * scale:.2f} {unit} (fitted to the last lap)", fontsize=8)
    elif "stops" in fig:
        for s in fig["stops"]:
            ax.plot(s["t"], s["x"] * scale, "-", lw=1, label=f"from {s['label']}")
            ax.axhline(s["limit"] * scale, color="0.5", ls=":", lw=1)
        ax.set_xlabel("time [s]", fontsize=7)
        ax.set_ylabel(f"distance [{unit}]", fontsize=7)
        ax.set_title("tractor CG from the first movement of the control; dotted: the limits", fontsize=8)
        ax.legend(fontsize=6)
        return
    elif "sensitivity" in fig:
        for label in dict.fromkeys(s["factor"] for s in fig["sensitivity"]):
            pts = [s for s in fig["sensitivity"] if s["factor"] == label]
            ax.plot([s["value"] for s in pts], [math.degrees(s["exit_tractor"]) for s in pts], "o-", ms=3,
                    label=f"{label}: tractor")
            ax.plot([s["value"] for s in pts], [math.degrees(s["exit_trailer"]) for s in pts], "s--", ms=3,
                    label=f"{label}: trailer")
        ax.axhline(math.degrees(fig["limit"]), color="#cf222e", lw=1, label="NCHRP 350 criterion M (60 % of 15 deg)")
        ax.set_xlabel("coefficient (one at a time; the others at the rules' values)", fontsize=7)
        ax.set_ylabel("exit angle [deg] (missing: still at the barrier at rest)", fontsize=7)
        ax.set_title("sensitivity of the exit angle", fontsize=8)
        ax.legend(fontsize=5)
        return
    else:
        ax.set_visible(False)
        return
    ax.autoscale_view()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    if (x1 - x0) > 4 * (y1 - y0) or (y1 - y0) > 4 * (x1 - x0):
        ax.set_ylabel(f"y [{unit}] (not to the x axis' scale)", fontsize=7)
    else:
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_ylabel(f"y [{unit}]", fontsize=7)
    ax.set_xlabel(f"x [{unit}]", fontsize=7)
    ax.tick_params(labelsize=7)
    ax.legend(fontsize=6, loc="best")


def plot_case(result: CaseResult, path: Path | None = None, system: str | None = None, dpi: int = 150):
    """The case's figure: every quantity's error against its band (left), its plan view or history (right).

    Written to ``path`` (and closed; returns the path), or, without a path, returned open (a
    :class:`matplotlib.figure.Figure`, which a notebook shows)."""
    import matplotlib.pyplot as plt

    n = len(result.quantities)
    has_plan = any(k in result.figure for k in ("rest_runs", "scene", "trailer", "stops", "sensitivity"))
    height = max(3.2, 0.3 * n + 1.6)
    fig = plt.figure(figsize=(17.0 if has_plan else 11.0, height))
    bottom, top = 0.9 / height, 1 - 0.55 / height
    if has_plan:
        ax = fig.add_axes((0.2, bottom, 0.16, top - bottom))
        ax2 = fig.add_axes((0.67, bottom, 0.31, top - bottom))
        _plan(ax2, result, system)
    else:
        ax = fig.add_axes((0.3, bottom, 0.25, top - bottom))
    _forest(ax, result, system)
    fig.suptitle(f"{result.id}: {result.title}", fontsize=9, x=0.01, ha="left")
    if path is None:
        return fig
    path = Path(path)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path
