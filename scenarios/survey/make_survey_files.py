"""Write the survey files of scenarios/survey/truck_brakes_survey.toml (run from the repository root).

The scene is scenarios/scenes/truck_brakes_into_car.toml (HYPOTHETICAL evidence), put on a made-up
State Plane grid in US survey feet: the scene origin lies at E 1,455,000.00, N 538,400.00 ftUS and
the scene's +X axis points 30 deg north of east. Written here, committed beside it:

* files/scene.dxf        (ezdxf, R2010, $INSUNITS 21 = US survey feet): road edges, centre line,
                         kerb returns as ARCs, pre-impact skid marks, the point of impact, a gouge,
                         debris, the tractor's and trailer's rest outlines, a sign post as an INSERT
                         of a block, TEXT labels;
* files/points.csv       (PNEZD, US survey feet): the car's four rest corners (code CAR REST, with
                         BEG/END) and the north road edge (code EP);
* files/ortho.png + .pgw a north-up "orthophoto" of the scene, 0.5 ft per pixel, with its world file;
* files/ecm.csv          the tractor engine module's hard-brake record (1 Hz, mph).

Usage:  python scenarios/survey/make_survey_files.py
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
OUT = HERE / "files"
FT = 1200.0 / 3937.0                 # m per US survey foot
ORIGIN = np.array([1455000.0, 538400.0])   # ftUS
ROT = math.radians(30.0)
IFT = 0.3048                          # the scene's evidence is written in international feet


def to_survey(p) -> np.ndarray:
    """Scene points [m] -> survey coordinates [ftUS]."""
    p = np.asarray(p, dtype=float).reshape(-1, 2)
    c, s = math.cos(ROT), math.sin(ROT)
    q = np.column_stack([c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1]])
    return ORIGIN + q / FT


def corners(center, heading, length, width, oc):
    """Outline corners (front_left, rear_left, rear_right, front_right) of a body at rest [m]."""
    hx, hy = length / 2, width / 2
    local = np.array([[oc + hx, hy], [oc - hx, hy], [oc - hx, -hy], [oc + hx, -hy]])
    c, s = math.cos(heading), math.sin(heading)
    return np.asarray(center) + local @ np.array([[c, s], [-s, c]])


ROAD = {  # scene metres
    "south edge": [(-60.0, -1.8), (-3.0, -1.8)],
    "south edge east": [(12.7, -1.8), (60.0, -1.8)],
    "centre": [(-60.0, 1.8), (60.0, 1.8)],
    "side road west": [(1.0, -5.8), (1.0, -30.0)],
    "side road east": [(8.7, -5.8), (8.7, -30.0)],
}
SKIDS = {  # the hand-typed marks of truck_brakes_into_car.toml, ft -> m
    "SKID-TRACTOR-L": [(-102.7, 3.1), (-51.4, 3.1), (-9.2, 3.0)],
    "SKID-TRACTOR-R": [(-102.5, -3.2), (-51.5, -3.3), (-9.3, -3.3)],
}
REST = {  # body: (CG [ft], heading [deg], length, width, outline centre [m]) from the hand-typed scene
    "tractor": ((38.4, 0.6), 4.0, 8.3, 2.5, -0.2),
    "trailer": ((14.6, -0.4), -3.0, 9.3, 2.5, 0.3),
    "car": ((67.0, 32.5), -50.0, 4.8, 1.8, 0.15),
}


def write_dxf() -> None:
    import ezdxf

    doc = ezdxf.new("R2010", setup=True)
    doc.header["$INSUNITS"] = 21
    msp = doc.modelspace()
    for name, color in (("EDGE", 7), ("CENTRE", 2), ("KERB", 8), ("SKID-TRACTOR-L", 1), ("SKID-TRACTOR-R", 1),
                        ("POI", 6), ("GOUGE", 30), ("DEBRIS", 40), ("REST-TRACTOR", 5), ("REST-TRAILER", 5),
                        ("SIGN", 3)):
        doc.layers.add(name, color=color)
    for name, pts in ROAD.items():
        layer = "CENTRE" if name == "centre" else "EDGE"
        msp.add_lwpolyline(to_survey(pts).tolist(), dxfattribs={"layer": layer})
    # kerb returns: quarter circles of 4 m radius at the side road's corners
    for cx, start in ((-3.0, 270.0), (12.7, 180.0)):
        c = to_survey([(cx, -5.8)])[0]
        msp.add_arc(c.tolist(), 4.0 / FT, start + 30.0, start + 120.0, dxfattribs={"layer": "KERB"})
    for layer, pts in SKIDS.items():
        m = np.asarray(pts) * IFT
        msp.add_lwpolyline(to_survey(m).tolist(), dxfattribs={"layer": layer})
        mid = to_survey(m[1:2])[0]
        msp.add_text(f"pre-impact skid, tractor/1/{'left' if layer.endswith('L') else 'right'}", height=1.0,
                     dxfattribs={"layer": layer, "insert": mid.tolist()})
    msp.add_point(to_survey([(13.3 * IFT, 0.4 * IFT)])[0].tolist(), dxfattribs={"layer": "POI"})
    msp.add_line(*to_survey([(3.2, 0.2), (5.6, 0.5)]).tolist(), dxfattribs={"layer": "GOUGE"})
    for p in ((6.0, 1.0), (7.5, 2.2), (9.1, 0.4), (10.2, 3.1)):
        msp.add_point(to_survey([p])[0].tolist(), dxfattribs={"layer": "DEBRIS"})
    for body, layer in (("tractor", "REST-TRACTOR"), ("trailer", "REST-TRAILER")):
        cg, hd, ln, wd, oc = REST[body]
        pts = corners(np.asarray(cg) * IFT, math.radians(hd), ln, wd, oc)
        msp.add_lwpolyline(to_survey(pts).tolist(), close=True, dxfattribs={"layer": layer})
    block = doc.blocks.new("SIGNPOST")
    block.add_circle((0.0, 0.0), 0.25 / FT)  # a post of 0.5 m diameter, on layer 0: takes the INSERT's layer
    msp.add_blockref("SIGNPOST", to_survey([(-20.0, 9.0)])[0].tolist(), dxfattribs={"layer": "SIGN"})
    doc.saveas(OUT / "scene.dxf")


def write_points() -> None:
    cg, hd, ln, wd, oc = REST["car"]
    pts = to_survey(corners(np.asarray(cg) * IFT, math.radians(hd), ln, wd, oc))
    edge = to_survey([(x, 5.4) for x in (-60.0, -30.0, 0.0, 30.0, 60.0)])
    rows, n = [], 100
    for i, p in enumerate(edge):
        n += 1
        rows.append(f"{n},{p[1]:.4f},{p[0]:.4f},{700.0 + 0.01 * i:.3f},EP")
    for i, p in enumerate(pts):
        n += 1
        ctl = " BEG" if i == 0 else " END" if i == len(pts) - 1 else ""
        rows.append(f"{n},{p[1]:.4f},{p[0]:.4f},{700.0:.3f},CAR REST{ctl}")
    (OUT / "points.csv").write_text("\n".join(rows) + "\n")


def write_ortho() -> None:
    """A synthetic north-up orthophoto: asphalt, grass, white and yellow lines, 0.5 ft pixels."""
    import matplotlib.image as mpimg

    px = 0.5  # ftUS per pixel
    lo = to_survey([(-45.0, -22.0), (35.0, -22.0), (35.0, 18.0), (-45.0, 18.0)])
    x0, y1 = lo[:, 0].min(), lo[:, 1].max()
    w = int(math.ceil((lo[:, 0].max() - x0) / px))
    h = int(math.ceil((y1 - lo[:, 1].min()) / px))
    cols, rows = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    e, n = x0 + cols * px, y1 - rows * px
    d = np.column_stack([e.ravel() - ORIGIN[0], n.ravel() - ORIGIN[1]]) * FT
    c, s = math.cos(ROT), math.sin(ROT)
    x = (c * d[:, 0] + s * d[:, 1]).reshape(h, w)
    y = (-s * d[:, 0] + c * d[:, 1]).reshape(h, w)
    img = np.empty((h, w, 3))
    img[:] = (0.42, 0.55, 0.33)                                   # grass
    road = ((y > -1.8) & (y < 5.4)) | ((x > 1.0) & (x < 8.7) & (y < -1.8))
    img[road] = (0.36, 0.36, 0.37)                                # asphalt
    img[road & (np.abs(y - 1.8) < 0.08)] = (0.9, 0.8, 0.2)        # centre line
    img[(np.abs(y + 1.6) < 0.07) & ((x < 1.0) | (x > 8.7))] = (0.95, 0.95, 0.95)
    img[np.abs(y - 5.2) < 0.07] = (0.95, 0.95, 0.95)              # edge lines
    mpimg.imsave(OUT / "ortho.png", img)
    # world file: A (x per column), D, B, E (y per row, negative), C, F (centre of the top left pixel)
    (OUT / "ortho.pgw").write_text("\n".join(f"{v:.10f}" for v in (px, 0.0, 0.0, -px, x0 + px / 2, y1 - px / 2))
                                   + "\n")


def write_recorder() -> None:
    rows = ["Time (sec),Vehicle Speed (MPH),Service Brake,ABS,Accelerator Pedal (%)",
            "-5.0,55,Off,Off,18", "-4.0,54,Off,Off,17", "-3.0,55,Off,Off,18", "-2.0,55,Off,Off,0",
            "-1.0,44,On,Off,0", "0.0,31,On,Off,0"]
    (OUT / "ecm.csv").write_text("\n".join(rows) + "\n")


if __name__ == "__main__":
    OUT.mkdir(exist_ok=True)
    write_dxf()
    write_points()
    write_ortho()
    write_recorder()
