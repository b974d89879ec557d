"""Crush evidence through the command line: ``crashsim run`` (report, JSON) and ``crashsim fit``.

Round trip: the crush energy is made by the model itself (the energy the impact loses at a true
restitution e = 0.3, split between the two cars), then ``crashsim fit`` must find e from the crush
comparison alone. Scene: tests/data/crush_head_on.toml (docs/crush-energy.md, worked example 5:
for this central impact the loss is (1 - e^2) x 75 000 J, so e follows from the loss in closed form).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from crashsim.cli import main
from crashsim.scene.run import run_scene
from crashsim.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "tests" / "data" / "crush_head_on.toml"


def test_run_report_and_json_carry_the_crush_energy(capsys):
    assert main(["run", str(SCENE)]) == 0
    text = capsys.readouterr().out
    assert "Crush energy (CRASH3" in text
    assert "6 points, mean 0.26 m, max 0.35 m" in text
    assert "carA  total" in text and "55175 J" in text and "8.577 m/s" in text
    assert "model loss 74250 J against crush energy 80525 J (crush / loss = 1.085)" in text
    assert "PASS  crush energy" in text
    assert main(["run", str(SCENE), "--units", "US"]) == 0
    us = capsys.readouterr().out
    assert "285.507 lbf/in" in us and "ft lbf" in us
    assert main(["run", str(SCENE), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["crush"]["carA"]["energy"] == pytest.approx(55_175.0)
    assert out["crush"]["carA"]["ees"] == pytest.approx(math.sqrt(2 * 55_175.0 / 1500.0))
    assert out["crush"]["carB"]["ees"] == pytest.approx(6.5)
    first = out["impacts"][0]
    assert first["energy_loss_normal"] == pytest.approx(74_250.0)
    assert first["energy_loss_tangential"] == pytest.approx(0.0, abs=1e-6)
    assert out["impact"]["energy_loss_normal"] == pytest.approx(74_250.0)
    (check,) = [c for c in out["evidence"]["checks"] if c["kind"] == "crush energy"]
    assert check["quantity"] == "energy" and check["residual"] == pytest.approx(-6_275.0)


def test_one_body_only_is_reported_as_a_lower_bound(tmp_path, capsys):
    text = SCENE.read_text()
    text = text[: text.rindex("[[evidence.crush]]")]  # car B's item removed
    path = tmp_path / "one.toml"
    path.write_text(text)
    assert main(["run", str(path)]) == 0
    out = capsys.readouterr().out
    assert "only part of the pair has a crush item (none for carB)" in out
    assert "lower bound" in out and "PASS  crush energy" in out  # 55 175 J < 74 250 J: one-sided pass


FIT = """
[fit]
starts = 1
seed = 0

[[fit.unknowns]]
path = "impact.restitution"
lower = "0"
upper = "0.9"
initial = "0.6"
"""


def test_fit_restitution_from_crush_made_by_the_model(tmp_path, capsys):
    e_true = 0.3
    text = SCENE.read_text().replace("restitution = 0.1", f"restitution = {e_true}")
    truth = run_scene(load_scenario(_write(tmp_path / "truth.toml", text)))
    lost = truth.impact.energy_loss_crush  # the model's own loss at e = 0.3
    assert lost == pytest.approx((1 - e_true**2) * 75_000.0, rel=1e-12)
    e_a = 55_175.0  # car A's six-point profile, square-on (factor 1)
    ees_b = math.sqrt(2 * (lost - e_a) / 1200.0)  # car B's EES takes the rest
    text = text.replace('ees = "6.5 m/s"', f'ees = "{ees_b!r} m/s"').replace("restitution = 0.3", "restitution = 0.6")
    path = _write(tmp_path / "fit.toml", text + FIT)
    assert main(["fit", str(path), "--json", "--workers", "1"]) == 0
    res = json.loads(capsys.readouterr().out)
    (u,) = res["unknowns"]
    assert u["value"] == pytest.approx(e_true, abs=1e-5)
    lo, hi = u["interval"]
    assert lo < e_true < hi
    # sigma of the group: sqrt(5^2 + 2.5^2) kJ; d(loss)/de = -2 e 75 000 J, so the standard error of e is
    # sigma / (2 e 75 000 J) (one residual, linearised at the truth)
    se = math.hypot(5_000.0, 2_500.0) / (2 * e_true * 75_000.0)
    assert u["stderr"] == pytest.approx(se, rel=1e-3)


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def test_fit_residual_of_a_lower_bound_is_one_sided(tmp_path):
    """Only car A measured: its crush is a lower bound of the energy absorbed, so the fit penalises only
    crush in excess of the model's loss (residual min(loss - crush, 0))."""
    from crashsim.reconstruct.fit import EvidenceModel

    text = SCENE.read_text()
    text = text[: text.rindex("[[evidence.crush]]")]
    sc = load_scenario(_write(tmp_path / "one.toml", text))
    model = EvidenceModel(sc)
    (res,), _ = model.raw_residuals(run_scene(sc))
    assert res.tolist() == [0.0]  # 74 250 J lost >= 55 175 J of crush: consistent
    deep = text.replace('["0.10 m", "0.20 m", "0.30 m", "0.35 m", "0.30 m", "0.20 m"]', '["0.4 m", "0.4 m"]')
    sc = load_scenario(_write(tmp_path / "deep.toml", deep))
    (res,), _ = EvidenceModel(sc).raw_residuals(run_scene(sc))
    crush = 1.5 * (50_000.0 + 600_000.0 * 0.4) ** 2 / (2 * 600_000.0)  # uniform 0.4 m: 105 125 J
    assert res[0] == pytest.approx(74_250.0 - crush, rel=1e-12) and res[0] < 0
    assert model.weights().tolist() == [1 / 5_000.0]
