"""The model behind the live view: one scene file, the inputs a user may change, and each recompute.

A :class:`LiveSession` reads a scenario file once, names the inputs the view lets the user change
(its :class:`Control` list: each vehicle's position, heading and speed at impact, the approach's
braking distance and speed, the point of impact and the crush normal, e, mu or mu_fraction, f, e',
the road friction and every zone's friction) and keeps each as the text a file would hold, in the
unit the file itself uses for that key (``"40 mph"`` stays mph). A change is a set of such texts;
:meth:`LiveSession.apply` reads them like file values, runs the whole scene (the compiled engine)
and returns the view's payload (:mod:`crashsim.live.view`). The same texts are what
:meth:`LiveSession.save` writes into the file (:mod:`crashsim.live.savefile`), so the file saved
from the page runs, with ``crashsim run``, to the page's numbers.

No web code here: the server (:mod:`crashsim.live.server`) only carries messages to and from it.
"""

from __future__ import annotations

import copy
import hashlib
import io
import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

from ..errors import CrashsimError, ScenarioError
from ..reconstruct import run_scene
from ..reconstruct.montecarlo import UncertaintySpec, sample_inputs
from ..reconstruct.overrides import get_value, resolve_path, set_written
from ..reconstruct.inputs import Scene
from ..scene.models import ModelReuse
from ..reconstruct.tolerance import evidence_tolerance, tolerance_items, with_tolerance
from ..scenario import SCHEMA, load_scenario
from ..schema import in_range, load_toml
from ..survey.mapping import load_scene_data
from ..survey.underlay import scene_underlay
from ..units import Kind, number_and_unit, parse, si_unit, to_unit, write_like
from . import view
from .savefile import save_values

__all__ = ["Control", "LiveSession", "canonical", "SIGNIFICANT"]

#: Significant digits of a value the view writes (in the file's unit): a dragged vehicle moves by
#: a tenth of a millimetre, a typed "65 km/h" in a file that writes mph becomes "40.3891 mph".
SIGNIFICANT = 6

def _round(x: float, digits: int = SIGNIFICANT) -> float:
    if x == 0 or not math.isfinite(x):
        return float(x)
    return float(f"{x:.{digits}g}")


def canonical(si_value: float, kind: Kind, like: Any) -> Any:
    """An SI value written as the file writes the value ``like`` (its unit), to :data:`SIGNIFICANT`
    digits: ``"40.3891 mph"``, or a number for a plain number (a percentage if ``like`` is one)."""
    w = write_like(si_value, kind, like)
    if isinstance(w, str):
        x, unit = number_and_unit(w)
        return f"{_round(x)!r} {unit}".replace(".0 ", " ")
    return _round(float(w))


def _unit_of(written: Any) -> str:
    split = number_and_unit(written)
    return split[1] if split else ""


@dataclass
class Control:
    """One input of the scene the view lets the user change.

    Attributes
    ----------
    path : str
        Its path in the file (``"vehicles.B.speed"``, ``"impact.point[0]"``).
    label, group : str
        What the page calls it and the panel it sits in.
    kind : Kind
        Its unit kind.
    like : str or float
        The file's own value (its unit is the unit written back), or the default as a file writes it.
    unit : str
        That unit (``""`` for a plain number).
    per_si : float
        The value in ``unit`` of one SI unit (1 for a plain number).
    lower, upper : float
        The slider's range, SI: the ``[fit]`` bounds of the path if it is an unknown, else a range
        about the file's value (:meth:`LiveSession._range`); a typed value may lie outside it
        (the schema's own range still holds).
    written : str or float
        The current value as a file holds it.
    value : float
        The current value, SI.
    """

    path: str
    label: str
    group: str
    kind: Kind
    like: Any
    unit: str
    per_si: float
    lower: float
    upper: float
    written: Any
    value: float
    target: Any = field(repr=False, default=None)

    def to_dict(self) -> dict:
        step = _step(self.kind, self.per_si)
        # the slider's ends on whole steps, so that its values are round numbers in the unit
        lo = round(math.floor(self.lower * self.per_si / step) * step, 6)
        hi = round(math.ceil(self.upper * self.per_si / step) * step, 6)
        return {"path": self.path, "label": self.label, "group": self.group, "kind": self.kind.value,
                "unit": self.unit, "per_si": self.per_si, "lower": lo, "upper": hi,
                "written": self.written, "value": self.value * self.per_si, "step": step}


def _step(kind: Kind, per_si: float) -> float:
    """A slider step in the control's unit: 1 cm, 0.01 m/s, 0.1 deg, 0.005 (plain numbers)."""
    si = {Kind.LENGTH: 0.01, Kind.SPEED: 0.01, Kind.ANGLE: math.radians(0.1)}.get(kind)
    return _round(si * per_si, 2) if si is not None else 0.005


class LiveSession:
    """One scene file opened in the live view.

    Parameters
    ----------
    path : str or Path
        The scenario file (TOML). It is validated as ``crashsim run`` validates it; a bad file
        raises the same :class:`~crashsim.errors.ScenarioError`.
    engine : str
        The run-out engine of the view (``"compiled"``, the default: recomputes in milliseconds;
        the file's own ``runout.engine`` is left as it is and saved as it was).

    Attributes
    ----------
    controls : dict
        :class:`Control` by path, in the panel's order.
    result : SceneResult or None
        The last good result (a change that makes the scene invalid keeps it).
    """

    def __init__(self, path, *, engine: str = "compiled"):
        self.path = Path(path)
        self.file = str(path)
        self.engine = engine
        self._open()

    # -- the file ------------------------------------------------------------------------------
    def _open(self) -> None:
        text = self.path.read_bytes()
        self.scenario = load_scenario(self.file)  # the whole file validated, as crashsim run does
        self.file_hash = hashlib.sha256(text).hexdigest()
        self.raw = load_toml(self.file)
        self.data = load_scene_data(self.file)
        self.system = self.scenario.units
        self.controls = self._make_controls()
        self._rebase()
        self.result = None
        self.payload = None
        self.error = None

    def _rebase(self) -> None:
        """The file's own values of the inputs (SI), against which a value counts as changed."""
        self._scene = Scene(self.data, engine=self.engine, file=self.file)
        self._models = ModelReuse()  # the run-out's scene model, kept across the changes
        self.overrides = self._scene.inputs(list(self.controls), field="live", cache=1)
        # where the file gives no value, the schema's default the view started from
        self._base = [self.overrides.base_value(i) for i in range(len(self.controls))]
        self._base = [c.value if b is None else b for b, c in zip(self._base, self.controls.values())]
        self._by_paths = {}

    def changed_on_disk(self) -> bool:
        """The file on disk is not the file opened (its bytes changed since)."""
        try:
            return hashlib.sha256(self.path.read_bytes()).hexdigest() != self.file_hash
        except OSError:
            return True

    def reload(self) -> dict:
        """Read the file again (its changes on disk), dropping the view's changes; the new payload."""
        self._open()
        return self.apply({})

    # -- the inputs ----------------------------------------------------------------------------
    def _fit_bounds(self) -> dict:
        out = {}
        for u in ((self.raw.get("fit") or {}).get("unknowns") or ()):
            try:
                t = resolve_path(u["path"], SCHEMA)
                kind = t.field.kind if isinstance(t.field.kind, Kind) else Kind.DIMENSIONLESS
                out[t.path] = (parse(u["lower"], kind, field="fit.lower"), parse(u["upper"], kind, field="fit.upper"))
            except (KeyError, CrashsimError):
                continue
        return out

    def _make_controls(self) -> dict:
        sc, d = self.scenario, self.data
        wanted: list[tuple[str, str, str]] = []  # (path, label, group)
        for v in sc.vehicles:
            if v.is_barrier:
                continue
            raw = d["vehicles"][v.name]
            name = f"{v.name} ({sc.descriptions.get(v.name)})" if sc.descriptions.get(v.name) else v.name
            wanted += [(f"vehicles.{v.name}.position[0]", "CG x at impact", name),
                       (f"vehicles.{v.name}.position[1]", "CG y at impact", name),
                       (f"vehicles.{v.name}.heading", "heading at impact", name)]
            a = raw.get("approach")
            if raw.get("speed") is not None:
                wanted.append((f"vehicles.{v.name}.speed", "speed at impact", name))
            if a is not None:
                if a.get("speed") is not None:
                    wanted.append((f"vehicles.{v.name}.approach.speed", "speed at the start of braking", name))
                if a.get("distance") is not None:
                    wanted.append((f"vehicles.{v.name}.approach.distance", "braking distance", name))
                if a.get("reaction_time") is not None:
                    wanted.append((f"vehicles.{v.name}.approach.reaction_time", "reaction time", name))
        imp = d["impact"]
        law = imp["tangential"]
        wanted += [("impact.point[0]", f"point of impact x ({imp.get('point_frame', 'world')} axes)", "impact"),
                   ("impact.point[1]", f"point of impact y ({imp.get('point_frame', 'world')} axes)", "impact")]
        if d.get("barrier") is None:
            wanted.append(("impact.normal", f"crush normal ({imp.get('normal_frame', 'world')} axes)", "impact"))
        wanted.append(("impact.restitution", "restitution e", "impact"))
        if law == "ratio":
            wanted.append(("impact.mu", "impulse ratio mu", "impact"))
        elif law == "fraction":
            wanted.append(("impact.mu_fraction", "mu / mu_max", "impact"))
        elif law == "friction":
            wanted.append(("impact.friction", "crush-surface friction f", "impact"))
        wanted.append(("impact.moment_restitution", "moment restitution e'", "impact"))
        if d.get("runout") is not None:
            wanted.append(("runout.road_friction", "road friction", "road"))
            for i, z in enumerate(d["runout"].get("zones") or ()):
                wanted.append((f"runout.zones[{i}].friction", f"zone friction: {z.get('name') or f'zone {i + 1}'}",
                               "road"))
        bounds = self._fit_bounds()
        out = {}
        for path, label, group in wanted:
            t = resolve_path(path, SCHEMA, field="live")
            kind = t.field.kind if isinstance(t.field.kind, Kind) else Kind.DIMENSIONLESS
            like = get_value(self.raw, t)
            if like is None:
                like = get_value(d, t)
            if like is None and t.field.default is not None:
                like = t.field.default if t.component is None else t.field.default[t.component]
            if like is None:  # neither in the file nor a default: not an input of this scene
                continue
            value = parse(like, kind, field=path)
            if kind is not Kind.DIMENSIONLESS and not _unit_of(like):
                like = f"0 {to_unit(1.0, kind, self.system)[1] or si_unit(kind)}"  # the file's display unit
            unit = _unit_of(like)
            w1 = write_like(1.0, kind, like)
            per_si = number_and_unit(w1)[0] if isinstance(w1, str) else 1.0
            lo, hi = bounds.get(t.path) or self._range(t, kind, value)
            written = canonical(value, kind, like)
            out[t.path] = Control(path=t.path, label=label, group=group, kind=kind, like=like, unit=unit,
                                  per_si=per_si, lower=lo, upper=hi, written=written,
                                  value=parse(written, kind, field=path), target=t)
        return out

    @staticmethod
    def _range(t, kind: Kind, value: float) -> tuple[float, float]:
        """The slider range of an input that is not a ``[fit]`` unknown: about its file value, within
        the schema's own range."""
        key = t.steps[-1][0]
        if kind is Kind.LENGTH and key == "position":
            lo, hi = value - 20.0, value + 20.0
        elif kind is Kind.LENGTH and key == "point":
            lo, hi = value - 3.0, value + 3.0
        elif kind is Kind.LENGTH:  # a braking distance
            lo, hi = 0.2 * value, 3.0 * value
        elif kind is Kind.ANGLE:
            lo, hi = value - math.pi, value + math.pi
        elif kind is Kind.SPEED:
            lo, hi = 0.0, max(2.0 * value, 30.0)
        elif kind is Kind.TIME:
            lo, hi = 0.0, max(3.0 * value, 3.0)
        elif key in ("mu", "moment_restitution"):
            lo, hi = -1.0, 1.0
        elif key in ("friction", "road_friction"):
            lo, hi = 0.05, 1.5
        else:
            lo, hi = 0.0, 1.0
        f = t.field
        if f.minimum is not None:
            lo = max(lo, f.minimum)
        if f.maximum is not None:
            hi = min(hi, f.maximum)
        return lo, hi

    def read(self, path: str, written: Any) -> tuple[Any, float]:
        """A value for input ``path`` as the page sends it (``"40 mph"``, ``0.1``, ``"65 km/h"``):
        (its text in the file's unit, its SI value). Raises ScenarioError as a file value would,
        with the allowed range in the unit the value was given in."""
        c = self.controls.get(path)
        if c is None:
            raise ScenarioError(f"{path!r} is not an input of this view; allowed: {', '.join(self.controls)}",
                                field="live", file=self.file)
        if isinstance(written, bool) or not isinstance(written, (str, int, float)):
            raise ScenarioError(f"{written!r}: allowed a number with its unit, e.g. {c.written!r}", field=path,
                                file=self.file)
        x = parse(written, c.kind, field=path, file=self.file)
        if not math.isfinite(x):
            raise ScenarioError(f"{written!r} is not a finite number", field=path, file=self.file)
        f = c.target.field
        if not in_range(x, f):
            lo = "-inf" if f.minimum is None else canonical(f.minimum, c.kind, c.like)
            hi = "inf" if f.maximum is None else canonical(f.maximum, c.kind, c.like)
            raise ScenarioError(f"{written!r}: allowed [{lo}, {hi}]", field=path, file=self.file)
        text = canonical(x, c.kind, c.like)
        return text, parse(text, c.kind, field=path)

    def values(self) -> dict:
        """The current value of every input as the file would hold it: ``{path: written}``."""
        return {p: c.written for p, c in self.controls.items()}

    def changed(self) -> dict:
        """The inputs the view changed from the file: ``{path: written}``."""
        return {p: c.written for p, c in self.controls.items() if _file_value_differs(self, c)}

    # -- a recompute ---------------------------------------------------------------------------
    def scenario_for(self, values: Mapping[str, Any] | None = None):
        """The scenario with the current inputs and ``values`` (``{path: written}``) read over them;
        the controls are updated only if the scenario builds. Raises ScenarioError."""
        new = {}
        for p, w in (values or {}).items():
            new[p] = self.read(p, w)
        si = {p: new[p][1] if p in new else c.value for p, c in self.controls.items()}
        # only the inputs that differ from the file's are written (the others are the file's):
        # a change of the speeds, coefficients, point or friction alone then takes the fast path
        # that rebuilds only the objects it reaches (crashsim.reconstruct.variants)
        differ = tuple(p for p, base in zip(self.controls, self._base) if si[p] != base)
        sc = self._overrides_for(differ).scenario([si[p] for p in differ])
        for p, (text, x) in new.items():
            self.controls[p].written, self.controls[p].value = text, x
        return sc

    def _overrides_for(self, paths: tuple):
        """The :class:`~crashsim.reconstruct.inputs.SceneInputs` of the file and these inputs (a few kept)."""
        o = self._by_paths.get(paths)
        if o is None:
            o = self._scene.inputs(list(paths), field="live", cache=2)
            if len(self._by_paths) >= 8:
                self._by_paths.pop(next(iter(self._by_paths)))
            self._by_paths[paths] = o
        return o

    def apply(self, values: Mapping[str, Any] | None = None) -> dict:
        """Read ``values`` (``{path: written}``) over the current inputs, run the scene, and return
        the view's payload (``{"ok": True, ...}``). A change that makes the scene invalid (or an
        impact that cannot be solved) returns ``{"ok": False, "error": one line}`` and keeps the
        inputs and the result of the last good change."""
        keep = {p: (c.written, c.value) for p, c in self.controls.items()}
        t0 = time.perf_counter()
        try:
            sc = self.scenario_for(values)
            t1 = time.perf_counter()
            result = run_scene(sc, models=self._models)
            t2 = time.perf_counter()
        except CrashsimError as exc:
            for p, (w, x) in keep.items():
                self.controls[p].written, self.controls[p].value = w, x
            self.error = f"{type(exc).__name__}: {exc}" if not isinstance(exc, ScenarioError) else str(exc)
            return {"ok": False, "error": self.error, "values": self.values()}
        self.result, self.error = result, None
        self.payload = view.result_payload(result, self)
        # seconds: reading the values and building the scene, the scene's physics (impact, run-out to
        # rest, evidence checks), the payload (benchmarks/live_view.py states each as a ratio)
        timing = {"build": t1 - t0, "physics": t2 - t1, "payload": time.perf_counter() - t2}
        return {"ok": True, **self.payload, "values": self.values(), "timing": timing}

    def static(self) -> dict:
        """What the page draws once per file: the map, zones, obstacles, evidence, outlines, inputs."""
        return view.static_payload(self)

    # -- saving ----------------------------------------------------------------------------------
    def save(self, target=None, *, force: bool = False) -> str:
        """Write the current inputs into the file (or into ``target``, a new file beside it), keeping
        its comments, order and layout; the path written. Refuses (ScenarioError) to overwrite a
        file changed on disk since it was opened, unless ``force``."""
        if target is None:
            if self.changed_on_disk() and not force:
                raise ScenarioError("the file changed on disk since it was opened: reload it, or save as a new file",
                                    field="save", file=self.file)
            out = self.path
        else:
            out = self.sibling(target)
        # only the inputs the view changed: a default the file does not write (moment_restitution = -1,
        # say) stays unwritten
        text = save_values(self.path.read_text(encoding="utf-8"), self.changed(), self.controls, file=self.file)
        out.write_text(text, encoding="utf-8")
        if out == self.path:  # the file's values are the view's now
            self.file_hash = hashlib.sha256(out.read_bytes()).hexdigest()
            self.raw = load_toml(self.file)
            self.data = load_scene_data(self.file)
            self._rebase()
        return str(out)

    def sibling(self, name: str) -> Path:
        """A new ``.toml`` file named ``name`` in the scene file's folder (no other place, no other
        file overwritten). Raises ScenarioError."""
        if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.\- ]{0,120}\.toml", name) \
                or name.startswith(".") or ".." in name:
            raise ScenarioError(f"{name!r}: allowed a new file name ending in .toml in the scene's folder "
                                "(letters, digits, '-', '_', '.', no path)", field="save as", file=self.file)
        out = self.path.parent / name
        if out.exists():
            raise ScenarioError(f"{name!r} exists already in {str(self.path.parent)!r}; choose a new name",
                                field="save as", file=self.file)
        return out

    @property
    def has_fit(self) -> bool:
        """The file has ``[fit]`` unknowns (Fit from here can run)."""
        return bool((self.raw.get("fit") or {}).get("unknowns"))

    def fit_inputs(self) -> dict:
        """The file's contents with the current inputs written in, the ``[fit]`` unknowns that are
        inputs of the view starting from their current values (within their bounds)."""
        data = copy.deepcopy(self.raw)
        bounds = self._fit_bounds()
        for p, c in self.controls.items():
            data = set_written(data, c.target, c.written)
        for u in ((data.get("fit") or {}).get("unknowns") or ()):
            c = self.controls.get(u.get("path"))
            if c is not None:
                lo, hi = bounds.get(c.path, (c.lower, c.upper))
                x = min(max(c.value, lo), hi)
                v = canonical(x, c.kind, c.like)
                u["initial"] = v if isinstance(v, str) else repr(v)  # [fit] writes every value as text
        return data

    # -- the Monte Carlo band and the survey underlay -------------------------------------------
    def _band_spec(self):
        """The ``[uncertainty]`` spec of the file, or None."""
        if not self.raw.get("uncertainty"):
            return None
        return UncertaintySpec.from_dict(self.raw["uncertainty"], file=self.file)


    def band_inputs(self) -> dict | None:
        spec = self._band_spec()
        if spec is None:
            return None
        return {"inputs": [{"name": getattr(d, "name", "") or d.path, "path": d.path} for d in spec.inputs],
                "seed": spec.seed}


    def band_task(self, n: int) -> tuple[dict, list]:
        """What a worker needs to run the band's ``n`` samples: (the payload it builds its runner from,
        the SI values of each sample). Sample ``i`` draws the ``[uncertainty]`` inputs as ``crashsim mc``
        does (seed, i); an uncertain input the view changed is drawn about the view's value (shifted by
        the change from the file's value); every other input of the view is at its current value."""
        spec = self._band_spec()
        # the inputs written into each sample: those the view changed from the file (at their value)
        # and the uncertain ones (drawn); the rest stay the file's, so that a sample takes the fast
        # path when the changed inputs allow it (crashsim.reconstruct.variants)
        shift = {}
        for i, (p, c) in enumerate(self.controls.items()):
            base = self._base[i]
            shift[p] = 0.0 if base is None else c.value - base
        changed = [p for p, c in self.controls.items() if shift[p] != 0.0 or self._base[list(self.controls).index(p)] is None]
        paths = changed + [d.path for d in spec.inputs if d.path not in changed]
        index = {p: i for i, p in enumerate(paths)}
        current = [self.controls[p].value for p in changed] + [0.0] * (len(paths) - len(changed))
        rows = []
        for i in range(n):
            x = list(current)
            for d, v in zip(spec.inputs, sample_inputs(spec, spec.seed, i)):
                x[index[d.path]] = float(v) + shift.get(d.path, 0.0)
            rows.append(x)
        data, rtol = self.data, None
        ro = self.result.scenario.runout if self.result is not None else None
        raw_runout = data.get("runout")
        if (spec.tolerance == "evidence" and ro is not None and isinstance(raw_runout, dict)
                and "accuracy" not in raw_runout):
            # as crashsim mc runs the samples of this file: at the loosest run-out tolerance whose
            # error stays negligible beside the evidence (crashsim.reconstruct.tolerance)
            tol = evidence_tolerance(tolerance_items(self.result.scenario.evidence), self.result, ro.options.rtol,
                                     ro.options.atol, what="tolerance")
            if tol.changed:
                data, rtol = with_tolerance(data, tol), tol.rtol
        payload = {"data": data, "paths": paths, "engine": self.engine, "file": self.file, "rtol": rtol,
                   "key": hashlib.sha256(repr((self.file_hash, paths, self.engine, rtol)).encode()).hexdigest()}
        return payload, rows


    def _underlay(self):
        if not hasattr(self, "_underlay_cache"):
            self._underlay_cache = scene_underlay(self.scenario)
        return self._underlay_cache


    def underlay_info(self) -> dict | None:
        u = self._underlay()
        if u is None:
            return None
        image, georef, opacity, _ = u
        return {"matrix": georef.matrix.tolist(), "opacity": float(opacity), "width": int(image.shape[1]),
                "height": int(image.shape[0])}


    def underlay_png(self) -> bytes | None:
        """The survey underlay as PNG bytes (the only image the server serves), or None."""
        u = self._underlay()
        if u is None:
            return None
        from matplotlib.image import imsave

        buf = io.BytesIO()
        imsave(buf, u[0], format="png")
        return buf.getvalue()


def _file_value_differs(session: LiveSession, c: Control) -> bool:
    """The current value is not the file's own (SI, by value: the file may write it in other digits)."""
    base = session._base[list(session.controls).index(c.path)]
    return abs(base - c.value) > 1e-12 * max(1.0, abs(base))
