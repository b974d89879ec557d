"""Orthophoto underlay: a scaled image under the scene figures.

An image is placed by an affine map from pixel coordinates (column, row; (0, 0) the top left
corner of the top left pixel, rows downward) to the survey's axes, from

* a world file (``.pgw``, ``.jgw``, ``.tfw``, ``.wld``: six lines A, D, B, E, C, F with
  ``x = A col + B row + C``, ``y = D col + E row + F`` at pixel centres);
* a GeoTIFF's own transform (rasterio, the optional ``geotiff`` extra);
* two or more control points (pixel -> survey position): a similarity (scale, rotation, shift,
  with the image's rows running down or up, whichever fits better) or, from three points that do
  not lie on a line, an affine, fitted by least squares with each point's residual reported;
  a residual above the tolerance is an error.

Then the survey's unit is converted to metres and the scene frame applied, so the image is drawn
in the scene's metres; the figure's scale bar stays true because the image follows the axes.
"""

from __future__ import annotations

import os

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ScenarioError
from .frame import SceneFrame, unit_scale

__all__ = ["Georef", "read_world_file", "fit_control_points", "georef_from_section", "load_image",
           "draw_underlay", "scene_underlay"]

_WORLD_EXT = {".png": (".pgw", ".pngw"), ".jpg": (".jgw", ".jpgw"), ".jpeg": (".jgw", ".jpgw"),
              ".tif": (".tfw", ".tifw"), ".tiff": (".tfw", ".tiffw")}


@dataclass(frozen=True)
class Georef:
    """Pixel -> scene map of an image.

    Attributes
    ----------
    matrix : ndarray, shape (2, 3)
        ``scene = matrix[:, :2] @ (col, row) + matrix[:, 2]`` [m], pixel-corner coordinates.
    how : str
        Where it comes from (world file, GeoTIFF, control points with their fit).
    residuals : ndarray
        Distance [m] of each control point from where the fit puts its pixel (empty otherwise).
    """

    matrix: np.ndarray
    how: str
    residuals: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def to_scene(self, pixels) -> np.ndarray:
        p = np.asarray(pixels, dtype=float).reshape(-1, 2)
        return p @ self.matrix[:, :2].T + self.matrix[:, 2]

    def to_pixels(self, pts) -> np.ndarray:
        p = np.asarray(pts, dtype=float).reshape(-1, 2) - self.matrix[:, 2]
        return np.linalg.solve(self.matrix[:, :2], p.T).T

    @property
    def pixel_size(self) -> float:
        """Mean ground size of a pixel [m] (the square root of the map's area factor)."""
        return math.sqrt(abs(np.linalg.det(self.matrix[:, :2])))


def _to_scene_matrix(m_survey: np.ndarray, scale: float, frame: SceneFrame) -> np.ndarray:
    """Compose pixel -> survey units (2x3), units -> m, and the scene frame."""
    c, s = math.cos(frame.rotation), math.sin(frame.rotation)
    r = np.array([[c, s], [-s, c]])
    lin = r @ (scale * m_survey[:, :2])
    off = r @ (scale * m_survey[:, 2] - np.asarray(frame.origin, dtype=float))
    return np.column_stack([lin, off])


def read_world_file(path: str, *, field: str = "survey.underlay.world_file", file: str | None = None) -> np.ndarray:
    """The 2x3 pixel-corner -> survey-unit matrix of a world file."""
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace").split()
    except OSError as exc:
        raise ScenarioError(f"cannot read the world file: {exc}", field=field, file=file) from None
    try:
        a, d, b, e, c, f = (float(v) for v in text)
    except ValueError:
        raise ScenarioError(f"{path}: a world file holds six numbers (A, D, B, E, C, F), one a line; got "
                            f"{len(text)} values: {' '.join(text[:8])}", field=field, file=file) from None
    lin = np.array([[a, b], [d, e]])
    if not np.all(np.isfinite(lin)) or abs(np.linalg.det(lin)) < 1e-300:
        raise ScenarioError(f"{path}: the pixel sizes A = {a}, B = {b}, D = {d}, E = {e} do not place an image "
                            "(zero area)", field=field, file=file)
    return np.column_stack([lin, [c - 0.5 * (a + b), f - 0.5 * (d + e)]])


def fit_control_points(pixels, positions, how: str = "similarity"):
    """Least-squares pixel -> position map from control points.

    Parameters
    ----------
    pixels, positions : array_like, shape (n, 2)
    how : {"similarity", "affine"}

    Returns
    -------
    matrix : ndarray, shape (2, 3)
    residuals : ndarray, shape (n,)
        Distance of each position from the fitted image of its pixel (units of ``positions``).

    Raises
    ------
    ValueError
        Too few points, repeated pixels, or (affine) points on one line.
    """
    u = np.asarray(pixels, dtype=float).reshape(-1, 2)
    x = np.asarray(positions, dtype=float).reshape(-1, 2)
    n = len(u)
    need = 2 if how == "similarity" else 3
    if n < need:
        raise ValueError(f"{n} control points; a {how} needs at least {need}")
    spread = np.linalg.svd(u - u.mean(axis=0), compute_uv=False)
    if spread[0] < 1.0:
        raise ValueError("the control points' pixels coincide (less than a pixel apart)")
    if how == "affine":
        if spread[1] < 1e-6 * spread[0] or spread[1] < 0.5:
            raise ValueError(f"the control points lie on one line (spread across it {spread[1]:.3g} px, along it "
                             f"{spread[0]:.3g} px); an affine needs three that do not")
        a = np.column_stack([u, np.ones(n)])
        sol, *_ = np.linalg.lstsq(a, x, rcond=None)
        m = sol.T
    else:
        best = None
        for flip in (1.0, -1.0):  # rows down (north-up images: flip) or up
            uu = u * np.array([1.0, flip])
            # x = p uu0 - q uu1 + tx ; y = q uu0 + p uu1 + ty
            a = np.zeros((2 * n, 4))
            a[0::2] = np.column_stack([uu[:, 0], -uu[:, 1], np.ones(n), np.zeros(n)])
            a[1::2] = np.column_stack([uu[:, 1], uu[:, 0], np.zeros(n), np.ones(n)])
            sol, *_ = np.linalg.lstsq(a, x.ravel(), rcond=None)
            p, q, tx, ty = sol
            m = np.array([[p, -q * flip, tx], [q, p * flip, ty]])
            r = np.hypot(*(u @ m[:, :2].T + m[:, 2] - x).T)
            if best is None or r.sum() < best[1].sum() - 1e-12:
                best = (m, r)
        m = best[0]
    res = np.hypot(*(u @ m[:, :2].T + m[:, 2] - x).T)
    return m, res


def _world_file_for(image: Path) -> Path | None:
    for ext in _WORLD_EXT.get(image.suffix.lower(), ()) + (".wld",):
        for cand in (image.with_suffix(ext), image.with_suffix(ext.upper())):
            if cand.is_file():
                return cand
    return None


def georef_from_section(u: dict, frame: SceneFrame, base: str | None, file: str | None = None) -> Georef:
    """The :class:`Georef` of a validated ``[survey.underlay]`` section (no pixels read but a GeoTIFF's header)."""
    image = _path(u["image"], base)
    if not image.is_file():
        raise ScenarioError(f"underlay image {u['image']!r} not found (looked for {os.path.relpath(image)})",
                            field="survey.underlay.image", file=file)
    scale = unit_scale(u["units"], field="survey.underlay.units", file=file)
    if u["control"]:
        if u["world_file"] is not None:
            raise ScenarioError("give either control points or a world file, not both", field="survey.underlay.control",
                                file=file)
        pix = [c["pixel"] for c in u["control"]]
        pos = [frame.to_scene(c["position"])[0] for c in u["control"]]  # positions in m (SI) -> scene
        try:
            m, res = fit_control_points(pix, pos, u["fit"])
        except ValueError as exc:
            raise ScenarioError(f"{u['image']}: {exc}", field="survey.underlay.control", file=file) from None
        worst = int(np.argmax(res))
        if res[worst] > u["tolerance"]:
            shown = ", ".join(f"{r:.3g} m" for r in res)
            raise ScenarioError(f"{u['image']}: control point {worst} ({pix[worst][0]:g}, {pix[worst][1]:g}) lies "
                                f"{res[worst]:.3g} m from where the {u['fit']} fit puts it (tolerance "
                                f"{u['tolerance']:g} m; residuals {shown})", field="survey.underlay.control",
                                file=file)
        extra = len(pix) - (2 if u["fit"] == "similarity" else 3)
        how = (f"{u['fit']} fit to {len(pix)} control points, largest residual {res.max():.3g} m"
               + ("" if extra else " (no redundant point: the residuals cannot show an error)"))
        return Georef(m, how, res)
    wf = _path(u["world_file"], base) if u["world_file"] is not None else _world_file_for(image)
    if wf is not None:
        return Georef(_to_scene_matrix(read_world_file(str(wf), file=file), scale, frame), f"world file {wf.name}")
    if image.suffix.lower() in (".tif", ".tiff"):
        try:
            import rasterio
        except ImportError:
            raise ScenarioError(f"{u['image']} has no world file; reading a GeoTIFF's own georeferencing needs the "
                                "optional extra: pip install \"crashsim[geotiff]\"", field="survey.underlay.image",
                                file=file) from None
        with rasterio.open(image) as ds:
            t = ds.transform
        m = np.array([[t.a, t.b, t.c], [t.d, t.e, t.f]])
        return Georef(_to_scene_matrix(m, scale, frame), "GeoTIFF transform")
    raise ScenarioError(f"{u['image']}: no world file beside it (looked for "
                        f"{', '.join(_WORLD_EXT.get(image.suffix.lower(), ('.wld',)))}) and no control points; give "
                        "world_file or [[survey.underlay.control]]", field="survey.underlay.image", file=file)


def _path(name: str, base: str | None) -> Path:
    p = Path(name).expanduser()
    if not p.is_absolute() and base is not None:
        p = Path(base).resolve().parent / p
    return p


def load_image(u: dict, base: str | None, file: str | None = None) -> np.ndarray:
    """The pixels of the underlay image, shape (rows, columns, channels)."""
    image = _path(u["image"], base)
    if not image.is_file():
        raise ScenarioError(f"underlay image {u['image']!r} not found (looked for {os.path.relpath(image)})",
                            field="survey.underlay.image", file=file)
    if image.suffix.lower() in (".tif", ".tiff"):
        try:
            import rasterio
        except ImportError:
            raise ScenarioError("a GeoTIFF underlay needs the optional extra: pip install \"crashsim[geotiff]\"",
                                field="survey.underlay.image", file=file) from None
        with rasterio.open(image) as ds:
            arr = ds.read()
        return np.moveaxis(arr, 0, -1)
    import matplotlib.image as mpimg

    try:
        return mpimg.imread(image)
    except Exception as exc:
        shown = os.path.relpath(image) if Path(u["image"]).is_absolute() else u["image"]
        raise ScenarioError(f"cannot read the underlay image {shown!r}: {exc}", field="survey.underlay.image",
                            file=file) from None


def scene_underlay(scenario):
    """(image, Georef, opacity, clip) of a scenario's ``[survey.underlay]``; None without one."""
    data = getattr(scenario, "data", None)
    s = data.get("survey") if isinstance(data, dict) else None
    if not isinstance(s, dict) or not s.get("underlay"):
        return None
    u = s["underlay"]
    frame = SceneFrame(tuple(s["origin"]), s["rotation"])
    g = georef_from_section(u, frame, scenario.path, scenario.path)
    return load_image(u, scenario.path, scenario.path), g, u["opacity"], u["clip"]


def draw_underlay(ax, image: np.ndarray, georef: Georef, *, scale: float = 1.0, opacity: float = 0.6,
                  clip: bool = True, zorder: float = -10.0):
    """Draw ``image`` under everything on ``ax`` (display length ``scale`` per metre), keeping the limits.

    With ``clip`` only the pixels that fall in the current view, widened by half its span on each
    side (later widenings of the view stay covered), are drawn.
    """
    from matplotlib.transforms import Affine2D

    xlim, ylim = ax.get_xlim(), ax.get_ylim()
    rows, cols = image.shape[:2]
    r0, r1, c0, c1 = 0, rows, 0, cols
    if clip:
        # the view and half its span around it: the animation and the Monte Carlo rest clouds widen
        # the scene figure's view after it is drawn
        mx, my = 0.5 * abs(xlim[1] - xlim[0]), 0.5 * abs(ylim[1] - ylim[0])
        x0, x1 = min(xlim) - mx, max(xlim) + mx
        y0, y1 = min(ylim) - my, max(ylim) + my
        corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]) / scale
        pix = georef.to_pixels(corners)
        c0, c1 = (int(np.clip(math.floor(pix[:, 0].min()) - 1, 0, cols)),
                  int(np.clip(math.ceil(pix[:, 0].max()) + 1, 0, cols)))
        r0, r1 = (int(np.clip(math.floor(pix[:, 1].min()) - 1, 0, rows)),
                  int(np.clip(math.ceil(pix[:, 1].max()) + 1, 0, rows)))
        if c1 <= c0 or r1 <= r0:
            return None
    m = georef.matrix * scale
    tr = Affine2D(np.array([[m[0, 0], m[0, 1], m[0, 2]], [m[1, 0], m[1, 1], m[1, 2]], [0, 0, 1]]))
    art = ax.imshow(image[r0:r1, c0:c1], extent=(c0, c1, r1, r0), transform=tr + ax.transData, alpha=opacity,
                    zorder=zorder, interpolation="bilinear", origin="upper")
    art.set_gid("underlay")
    ax.set_xlim(xlim)
    ax.set_ylim(ylim)
    return art
