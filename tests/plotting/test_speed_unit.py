"""``[scenario] speed_unit``: SI outputs with speeds in km/h (or mph), under Agg.

What is measured: the file's value is refused with the house error (file, key, value, allowed values);
the text report, the CSV files, the scene figure's delta-v labels and arrow scale and the histories'
speed axis show every speed in the chosen unit, each number the m/s one times the unit factor, while
lengths stay in m; a US output shows mph whatever speed_unit says; ``--units SI`` keeps it.
"""

from __future__ import annotations

import csv
import functools
import re
from pathlib import Path

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from crashsim.errors import ScenarioError  # noqa: E402
from crashsim.plotting import plot_histories, plot_scene  # noqa: E402
from crashsim.reconstruct import run_scene  # noqa: E402
from crashsim.scenario import load_scenario, schema_document  # noqa: E402
from crashsim.units import DisplaySystem, resolve_system, to_unit  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"
KMH = 3.6  # km/h per m/s, exact
MPH = 1.0 / 0.44704  # mph per m/s, exact


def _file(tmp_path: Path, value: str | None, units: str = "SI") -> Path:
    text = SCENE.read_text()
    assert "[scenario]\n" in text
    extra = "" if value is None else f'speed_unit = "{value}"\n'
    text = text.replace("[scenario]\n", f"[scenario]\n{extra}", 1)
    if units != "SI":
        text = re.sub(r'(?m)^units = "SI"\s*$', f'units = "{units}"', text, count=1) if 'units = "SI"' in text else \
            text.replace("[scenario]\n", f'[scenario]\nunits = "{units}"\n', 1)
    path = tmp_path / f"scene_{(value or 'none').replace('/', '_')}_{units}.toml"
    path.write_text(text)
    return path


@functools.lru_cache(maxsize=None)
def _run(path: Path):
    return run_scene(load_scenario(path))


def test_a_bad_speed_unit_is_refused_naming_file_key_value_and_allowed(tmp_path):
    path = _file(tmp_path, "kmh")
    with pytest.raises(ScenarioError) as exc:
        load_scenario(path)
    msg = str(exc.value)
    assert str(path) in msg and "scenario.speed_unit" in msg and '"kmh"' in msg
    assert "'m/s', 'km/h', 'mph'" in msg and "did you mean 'km/h'" in msg


def test_the_schema_documents_the_option():
    doc = schema_document("text")
    i = doc.index("speed_unit")
    assert "km/h" in doc[i:i + 600] and "mph" in doc[i:i + 600]


def _speeds(text: str, unit: str) -> list[float]:
    return [float(x) for x in re.findall(rf"(-?\d+(?:\.\d+)?(?:e[+-]?\d+)?) {re.escape(unit)}(?![\w/^])", text)]


def test_the_text_report_shows_every_speed_in_km_h(tmp_path):
    base = _run(_file(tmp_path, None))
    kmh = _run(_file(tmp_path, "km/h"))
    assert kmh.scenario.units == "SI" and kmh.scenario.units.speed_unit == "km/h"
    plain, shown = base.report(), kmh.report()
    assert "units: SI, speeds in km/h" in shown
    ms, kh = _speeds(plain, "m/s"), _speeds(shown, "km/h")
    assert len(ms) > 10 and len(kh) == len(ms)  # every speed converted, none left in m/s
    assert not _speeds(shown, "m/s")
    # each one the m/s value times 3.6, to the 4 significant digits printed
    np.testing.assert_allclose(kh, KMH * np.asarray(ms), rtol=2e-3, atol=1e-9)
    # lengths stay in metres, to the digit
    assert _speeds(plain, "m") == _speeds(shown, "m")
    assert "closing velocity 48.28 km/h" in shown  # 13.41 m/s (30 mph) each


def test_mph_in_an_si_report_and_us_stays_mph(tmp_path):
    scene = _run(_file(tmp_path, "mph"))
    text = scene.report()
    assert "closing velocity 30 mph" in text and not _speeds(text, "m/s")
    assert _speeds(text, "m") and not _speeds(text, "ft")  # lengths in m
    us = _run(_file(tmp_path, "km/h", units="US"))
    assert "mph" in us.report() and not _speeds(us.report(), "km/h")
    # --units SI over the file keeps the file's speed unit; --units US shows mph
    assert resolve_system("si", us.scenario.units).speed_unit == "km/h"
    assert to_unit(13.4112, "speed", resolve_system("SI", DisplaySystem("SI", "km/h"))) == pytest.approx((48.28032,
                                                                                                         "km/h"))
    assert to_unit(13.4112, "speed", resolve_system("US", DisplaySystem("SI", "km/h")))[1] == "mph"


def test_the_csv_speeds_are_in_km_h(tmp_path):
    base, kmh = _run(_file(tmp_path, None)), _run(_file(tmp_path, "km/h"))
    a, b = tmp_path / "ms", tmp_path / "kmh"
    base.write_csv(a)
    kmh.write_csv(b)
    with open(a / "impact.csv") as fa, open(b / "impact.csv") as fb:
        ra, rb = list(csv.DictReader(fa)), list(csv.DictReader(fb))
    speed_cols = [c for c in ra[0] if c.endswith("[m/s]")]
    assert speed_cols
    for c in speed_cols:
        c2 = c.replace("[m/s]", "[km/h]")
        assert c2 in rb[0], (c2, list(rb[0]))
        for x, y in zip(ra, rb):
            assert float(y[c2]) == pytest.approx(KMH * float(x[c]), abs=2e-4)
    assert not any("[m/s]" in c for c in rb[0])


def test_the_figures_show_km_h(tmp_path):
    base, kmh = _run(_file(tmp_path, None)), _run(_file(tmp_path, "km/h"))
    ax = plot_scene(kmh)
    labels = [t.get_text() for t in ax.texts if (t.get_gid() or "").startswith("label:delta-v")]
    assert labels and all(re.search(r"\d km/h$", t) for t in labels), labels
    dv = {b.name: b.delta_v_magnitude for b in kmh.impact.bodies.values() if not b.fixed}
    for t in labels:
        name = t.split("\n")[0].split()[-1]
        v = KMH * dv[name]  # printed to 3 significant digits: within half of the third one
        assert float(t.split("\n")[1].split()[0]) == pytest.approx(v, abs=0.5 * 10 ** (np.floor(np.log10(v)) - 2))
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(re.fullmatch(r"\u0394v at the CG \(1 m of arrow = [\d.]+ km/h\)", t) for t in legend), legend
    assert ax.get_xlabel() == "X [m]"
    plt.close("all")
    axes_m, axes_k = plot_histories(base).axes, plot_histories(kmh).axes
    assert axes_k[0].get_ylabel() == "CG speed [km/h]" and axes_m[0].get_ylabel() == "CG speed [m/s]"
    def curves(ax):  # the bodies' speed curves (labelled "car (B)"), not the marker lines
        return {ln.get_label(): np.asarray(ln.get_ydata(), dtype=float) for ln in ax.get_lines()
                if not ln.get_label().startswith("_")}

    cm, ck = curves(axes_m[0]), curves(axes_k[0])
    assert len(cm) >= 3 and cm.keys() == ck.keys()
    for name in cm:
        np.testing.assert_allclose(ck[name], KMH * cm[name], rtol=1e-12)
    plt.close("all")
