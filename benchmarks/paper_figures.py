"""Reproduce the paper's Figures 4 and 5 (barrier impacts) in shape, and tabulate the numbers
its text states about them.

Run from the repository root::

    PYTHONPATH=src python benchmarks/paper_figures.py [--out plots] [--n 1801]

Writes, into ``--out`` (default ``plots/``):

* ``figure4_5.png``         Figs. 4 (loaded) and 5 (empty), contact moving from the Table 3
                            point to the front corner ("interpolate"), the rule that satisfies
                            both statements of the text;
* ``figure4_5_fixed.png``   the same with the contact fixed at the Table 3 point;
* ``figure4_5_corner.png``  the same with the contact at the front corner (Table 4);
* ``figure4_5.csv``         per truck, contact rule and f: sliding-onset angle (|mu_max| = f),
                            tractor yaw-rate sign change, energy loss at 0 deg, |mu_max| at 60 deg;
* ``figure4_5.md``          those numbers next to the paper's statements, and the Table 3/4
                            spot checks of the same sweeps.

Source: "Impact of Articulated Vehicles", RIGID BARRIER COLLISIONS, Table 2, Figs. 4 and 5;
dimensions from ``docs/paper-geometry.md``.
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import matplotlib  # noqa: E402

matplotlib.use("Agg")

from crashsim.impact.sweeps import barrier_angle_sweep, crossings, sliding_onset  # noqa: E402
from crashsim.plotting import plot_barrier_figures  # noqa: E402

CONTACTS = ("interpolate", "fixed", "corner")
TRUCKS = ("loaded", "empty")
FRICTION = (0.2, 0.6)

#: What the paper and docs/paper-geometry.md state, for the markdown table.
PAPER = {
    "onset_0.2": "about 14 deg (text)",
    "mu60": "f = 1.2 needed (text); 1.12 loaded / 1.06 empty with the corner contact (recovered geometry)",
    "el0": "near 100 % for e = 0.05 (text)",
}

#: Tables 3 and 4 of the paper (f = 0.6): energy loss [%], mu used, tractor yaw rate [rad/s].
TABLES = {
    ("loaded", 15): (99.4, -90270 / 403164, 0.18),
    ("empty", 15): (99.4, -46202 / 212215, 0.16),
    ("loaded", 75): (4.4, -7054 / 11757, -0.64),
    ("empty", 75): (7.2, -6098 / 10164, -0.71),
}


def summarise(sw: dict) -> list[dict]:
    g = np.degrees(sw["angle"])
    i60 = int(np.argmin(np.abs(g - 60.0)))
    i0 = int(np.argmin(np.abs(g)))
    rows = []
    for k, f in enumerate(sw["friction"]):
        yaw_x = crossings(g, sw["tractor_yaw_rate"][k])
        yaw_x = yaw_x[yaw_x > 1.0]  # ignore a crossing at the very first sample
        rows.append({
            "truck": sw["truck"],
            "contact": sw["contact_rule"],
            "f": float(f),
            "sliding_onset_deg": sliding_onset(g, sw["mu_max"][k], float(f)),
            "yaw_sign_change_deg": float(yaw_x[0]) if yaw_x.size else float("nan"),
            "energy_loss_0deg_pct": 100.0 * float(sw["energy_loss"][k, i0]),
            "abs_mu_max_60deg": float(abs(sw["mu_max"][k, i60])),
        })
        el = np.where(sw["approaching"][k], 100.0 * sw["energy_loss"][k], np.nan)
        ip = int(np.nanargmax(el))
        on = rows[-1]["sliding_onset_deg"]
        rows[-1].update({
            "peak_energy_loss_pct": float(el[ip]),
            "peak_energy_loss_deg": float(g[ip]),
            "energy_loss_at_onset_pct": float(np.interp(on, g, el)),
            "energy_loss_onset_plus_5deg_pct": float(np.interp(on + 5.0, g, el)),
        })
    return rows


def notes(rows: list[dict], sweeps: dict) -> list[str]:
    """Observations, with their numbers computed from this run."""
    r = {(x["truck"], x["contact"], x["f"]): x for x in rows}
    rise = max(x["peak_energy_loss_pct"] - x["energy_loss_at_onset_pct"] for x in rows if x["contact"] == "fixed")
    lag = max(x["peak_energy_loss_deg"] - x["sliding_onset_deg"] for x in rows if x["contact"] == "fixed")
    yaw_gap = max(abs(x["peak_energy_loss_deg"] - x["yaw_sign_change_deg"]) for x in rows if x["contact"] == "fixed")
    fl = r["loaded", "fixed", 0.2]
    drop5 = fl["energy_loss_at_onset_pct"] - fl["energy_loss_onset_plus_5deg_pct"]
    d_on = max(abs(r["loaded", "fixed", f]["sliding_onset_deg"] - r["empty", "fixed", f]["sliding_onset_deg"])
               for f in FRICTION)
    L, E = sweeps["loaded", "fixed"], sweeps["empty", "fixed"]
    g = np.degrees(L["angle"])
    sel = g <= 60.0
    d_mu = float(np.max(np.abs(np.abs(L["mu_max"][0, sel]) - np.abs(E["mu_max"][0, sel]))))
    both_stick = ~L["sliding"] & ~E["sliding"] & L["approaching"]
    d_el = 100 * np.abs(L["energy_loss"] - E["energy_loss"])
    d_stick = float(np.max(d_el[both_stick]))
    d_slide = float(np.max(np.where(L["approaching"], d_el, 0.0)))
    ci = r["loaded", "corner", 0.2]
    return [
        "* f = 0.2: the onset angle is the same for `fixed` and `interpolate` (the contact only starts to",
        f"  move at 15 deg). With the corner contact |mu_max| is {abs(sweeps['loaded', 'corner']['mu_max'][0, 0]):.3f} "
        f"already at 0 deg, the onset is at {ci['sliding_onset_deg']:.1f} deg, and the energy",
        f"  loss at 0 deg is {ci['energy_loss_0deg_pct']:.1f} % rather than 'near 100 %': the paper's contact was not",
        "  at the corner for small angles.",
        "* |mu_max| at 60 deg: the corner gives the values of docs/paper-geometry.md; the interpolated contact gives",
        f"  {r['loaded', 'interpolate', 0.6]['abs_mu_max_60deg']:.2f} / {r['empty', 'interpolate', 0.6]['abs_mu_max_60deg']:.2f}, "
        "also about the text's '1.2', so that statement needs a contact near the corner at 60 deg,",
        f"  not necessarily at it. The Table 3 point gives {r['loaded', 'fixed', 0.6]['abs_mu_max_60deg']:.2f}.",
        "* The energy loss does not fall the moment sliding starts (Table 3 contact): it rises by at most",
        f"  {rise:.2f} point over the first {lag:.2f} deg of sliding, peaks where the tractor's final yaw rate changes",
        f"  sign (within {yaw_gap:.2f} deg), and falls monotonically from there, steeply: {drop5:.1f} points within",
        "  5 deg of the onset for f = 0.2, loaded. At the scale of the paper's figures this is its",
        "  'drop rapidly once mu = f is less than mu_max'.",
        f"* Loaded vs empty (Table 3 contact): the onset angles differ by {d_on:.2f} deg at most, |mu_max| by",
        f"  {d_mu:.3f} at most up to 60 deg, and the energy loss by {d_stick:.2f} point where both stick: the text's",
        "  'results do not differ greatly from Figure 4 to Figure 5'. The sliding-branch energy losses do",
        f"  differ, by up to {d_slide:.1f} points (the empty trailer losing more at glancing angles, as in",
        "  Table 4: 4.4 % loaded vs 7.2 % empty).",
    ]


def table_checks(n: int) -> list[str]:
    """Tables 3 (15 deg, Table 3 contact) and 4 (75 deg, corner contact) from the same sweeps."""
    out = []
    for (truck, gdeg), (el, mu, w) in TABLES.items():
        contact = "fixed" if gdeg == 15 else "corner"
        sw = barrier_angle_sweep(truck, np.radians([gdeg]), friction=(0.6,), contact=contact)
        out.append(
            f"| {truck} | {gdeg} | {contact} | {el:.1f} | {100 * sw['energy_loss'][0, 0]:.2f} | {mu:.3f} | "
            f"{sw['mu'][0, 0]:.3f} | {w:+.2f} | {sw['tractor_yaw_rate'][0, 0]:+.3f} |"
        )
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "plots")
    ap.add_argument("--n", type=int, default=1801, help="barrier angles from 0 to 90 deg (default 0.05 deg step)")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)

    t0 = time.perf_counter()
    rows = []
    sweeps = {}
    for contact in CONTACTS:
        for truck in TRUCKS:
            sweeps[truck, contact] = sw = barrier_angle_sweep(truck, friction=FRICTION, contact=contact, n=args.n)
            rows += summarise(sw)
    t_sweep = time.perf_counter() - t0

    names = {"interpolate": "figure4_5.png", "fixed": "figure4_5_fixed.png", "corner": "figure4_5_corner.png"}
    for contact, fname in names.items():
        fig = plot_barrier_figures(sweeps["loaded", contact], sweeps["empty", contact])
        fig.savefig(args.out / fname, dpi=110)
        matplotlib.pyplot.close(fig)

    with open(args.out / "figure4_5.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in r.items()})

    def cell(truck, contact, f, key, fmt):
        for r in rows:
            if (r["truck"], r["contact"], r["f"]) == (truck, contact, f):
                return format(r[key], fmt)
        return "-"

    md = [
        "# Figures 4 and 5: barrier impacts of the Table 2 tractor-semitrailer",
        "",
        "Generated by `PYTHONPATH=src python benchmarks/paper_figures.py` "
        f"({len(CONTACTS) * len(TRUCKS)} sweeps of {args.n} barrier angles x {len(FRICTION)} friction "
        f"coefficients in {t_sweep:.2f} s). e = 0.05, e' = -1, 13.41 m/s.",
        "",
        "The paper's figures are lost, and its contact point moved with the barrier angle in a way it",
        "does not state. The figures are reproduced in shape, not line for line, for three contact rules:",
        "`fixed` (Table 3 point (3.924, 0.240) m), `corner` (Table 4 point (3.884, 1.205) m), and",
        "`interpolate` (linear in the angle from the first at 15 deg to the second at 75 deg; only its",
        "ends come from the paper). `figure4_5.png` uses `interpolate`.",
        "",
        "## Statements of the text",
        "",
        "| quantity | paper | contact | loaded (Fig. 4) | empty (Fig. 5) |",
        "|---|---|---|---|---|",
    ]
    for contact in CONTACTS:
        md.append(f"| sliding onset, f = 0.2: angle where \\|mu_max\\| = 0.2 [deg] | {PAPER['onset_0.2']} | {contact} | "
                  f"{cell('loaded', contact, 0.2, 'sliding_onset_deg', '.2f')} | "
                  f"{cell('empty', contact, 0.2, 'sliding_onset_deg', '.2f')} |")
    for contact in CONTACTS:
        md.append(f"| sliding onset, f = 0.6 [deg] | sticks at 30 deg, slides at 60 deg (text) | {contact} | "
                  f"{cell('loaded', contact, 0.6, 'sliding_onset_deg', '.2f')} | "
                  f"{cell('empty', contact, 0.6, 'sliding_onset_deg', '.2f')} |")
    for contact in CONTACTS:
        md.append(f"| \\|mu_max\\| at 60 deg | {PAPER['mu60']} | {contact} | "
                  f"{cell('loaded', contact, 0.6, 'abs_mu_max_60deg', '.3f')} | "
                  f"{cell('empty', contact, 0.6, 'abs_mu_max_60deg', '.3f')} |")
    for contact in CONTACTS:
        for f in FRICTION:
            md.append(f"| energy loss at 0 deg, f = {f} [%] | {PAPER['el0']} | {contact} | "
                      f"{cell('loaded', contact, f, 'energy_loss_0deg_pct', '.2f')} | "
                      f"{cell('empty', contact, f, 'energy_loss_0deg_pct', '.2f')} |")
    for contact in CONTACTS:
        for f in FRICTION:
            md.append(f"| tractor yaw rate changes sign (+ to -), f = {f} [deg] | the 'cutoff' the section asks about | "
                      f"{contact} | {cell('loaded', contact, f, 'yaw_sign_change_deg', '.2f')} | "
                      f"{cell('empty', contact, f, 'yaw_sign_change_deg', '.2f')} |")
    md += [
        "",
        "## Tables 3 and 4 from the same sweeps (f = 0.6)",
        "",
        "| truck | G [deg] | contact | energy loss, paper [%] | computed [%] | mu, paper | computed | "
        "tractor yaw rate, paper [rad/s] | computed |",
        "|---|---|---|---|---|---|---|---|---|",
        *table_checks(args.n),
        "",
        "## Notes",
        "",
        *notes(rows, sweeps),
    ]
    (args.out / "figure4_5.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
