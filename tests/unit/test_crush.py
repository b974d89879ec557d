"""CRASH3 crush energy: the numeric core (crashsim.impact.crush), units, presets and bad input.

Worked numbers: docs/crush-energy.md, "Worked numbers" (computed from the CRASH3 formulas of
Campbell, SAE 740565 (1974) and the NHTSA CRASH3 manual, DOT HS 805 732 (1981), and cross-checked
by quadrature). Case 2 is the US-customary form of case 1 (A in lb/in, B in lb/in^2, lengths in in,
energy in in lb, as in CRASH3 practice, where lb means pound-force).
"""

from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path

import pytest

from crashsim.cli import main
from crashsim.errors import ScenarioError
from crashsim.impact.crush import (campbell_coefficients, campbell_slope, crush_energy, energy_equivalent_speed,
                                   face_angle, force_direction_factor, profile_energy, uniform_energy)
from crashsim.scenario import presets, scenario_from_dict, schema_document
from crashsim.units import Kind, convert, parse

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "tests" / "data" / "crush_head_on.toml"

A, B, L = 50_000.0, 600_000.0, 1.50
SIX = [0.10, 0.20, 0.30, 0.35, 0.30, 0.20]


# ----------------------------------------------------------------------------------- core
def test_six_points_worked_example_1():
    """Case 1: A-term 19 500 J + B-term 32 550 J + G-term 5 x 0.3 m x 2083.333 J/m = 3 125 J = 55 175 J;
    with alpha = 20 deg the factor is 1.132474 and E = 62 484.27 J; EES (1500 kg) 9.1276 m/s, 8.5771 m/s
    without the factor."""
    assert profile_energy(A, B, L, SIX) == pytest.approx(55_175.0, rel=1e-12)
    # the terms separately: A = 0 leaves the B-term alone (G = A^2/(2B) = 0); the rest is A-term + G-term
    assert profile_energy(0.0, B, L, SIX) == pytest.approx(32_550.0, rel=1e-12)
    assert profile_energy(A, B, L, SIX) - 32_550.0 - L * A**2 / (2 * B) == pytest.approx(19_500.0, rel=1e-12)
    assert L * A**2 / (2 * B) == pytest.approx(3_125.0, rel=1e-12)
    factor, capped = force_direction_factor(math.radians(20.0))
    assert factor == pytest.approx(1.132474, abs=1e-6) and not capped
    e = crush_energy(A, B, L, SIX, math.radians(20.0))
    assert e == pytest.approx(62_484.27, abs=0.01)
    assert energy_equivalent_speed(e, 1500.0) == pytest.approx(9.1276, abs=1e-4)
    assert energy_equivalent_speed(55_175.0, 1500.0) == pytest.approx(8.5771, abs=1e-4)
    assert energy_equivalent_speed(e, 1500.0) * 3.6 == pytest.approx(32.86, abs=0.005)


def test_four_and_two_points_worked_example_3():
    assert profile_energy(A, B, L, [0.10, 0.30, 0.35, 0.20]) == pytest.approx(57_125.0, rel=1e-12)
    assert profile_energy(A, B, L, [0.20, 0.30]) == pytest.approx(50_375.0, rel=1e-12)


@pytest.mark.parametrize("n", [2, 4, 6])
@pytest.mark.parametrize("c", [0.0, 0.3, 0.62])
def test_uniform_profile_closed_form(n, c):
    """Uniform crush C at any N: E = L (A + B C)^2 / (2B) (the closed form of the integral of
    e(C) = (A + B C)^2/(2B) over the width); 66 125 J for C = 0.30 m (case 3)."""
    e = profile_energy(A, B, L, [c] * n)
    assert e == pytest.approx(L * (A + B * c) ** 2 / (2 * B), rel=1e-12)
    assert e == pytest.approx(uniform_energy(A, B, L, c), rel=1e-12)
    if c == 0.3:
        assert e == pytest.approx(66_125.0, rel=1e-12)


def test_profile_energy_is_the_integral_of_the_linear_profile():
    """Quadrature of (A + B C(x))^2/(2B) over the piecewise-linear profile (independent of the
    segment formula): Simpson's rule is exact for the quadratic integrand of each segment."""
    prof = [0.05, 0.42, 0.13, 0.27]
    seg = 2.1 / 3
    total = 0.0
    for a, b in zip(prof[:-1], prof[1:]):
        f = [(A + B * c) ** 2 / (2 * B) for c in (a, (a + b) / 2, b)]
        total += seg / 6 * (f[0] + 4 * f[1] + f[2])
    assert profile_energy(A, B, 2.1, prof) == pytest.approx(total, rel=1e-12)


def test_factor_is_capped_at_45_degrees():
    assert force_direction_factor(math.radians(45.0))[0] == pytest.approx(2.0, rel=1e-12)
    assert force_direction_factor(math.radians(-50.0)) == (2.0, True)
    assert force_direction_factor(0.0) == (1.0, False)


@pytest.mark.parametrize("pdof, face, alpha", [(0, "front", 0), (20, "front", 20), (-30, "front", -30),
                                               (90, "right", 0), (110, "right", 20), (-90, "left", 0),
                                               (180, "rear", 0), (-170, "rear", 10)])
def test_angle_to_the_face_normal(pdof, face, alpha):
    assert math.degrees(face_angle(math.radians(pdof), face)) == pytest.approx(alpha, abs=1e-9)


def test_us_units_worked_example_2():
    """Case 2, the same damage in US units: A = 285.507 lb/in, B = 87.023 lb/in^2, L = 59.055 in,
    C in inches; E = 488 340 in lb = 55 175 J. The inputs are rounded to 6 digits, hence rel 2e-5."""
    a = parse("285.507 lb/in", Kind.FORCE_PER_LENGTH, field="A")
    b = parse("87.023 lb/in^2", Kind.FORCE_PER_AREA, field="B")
    width = parse("59.055 in", Kind.LENGTH, field="width")
    prof = [parse(f"{c} in", Kind.LENGTH, field="c") for c in (3.937, 7.874, 11.811, 13.780, 11.811, 7.874)]
    e = profile_energy(a, b, width, prof)
    assert e == pytest.approx(55_175.0, rel=2e-5)
    assert convert(e, "J", "in lbf", Kind.ENERGY) == pytest.approx(488_340.0, rel=2e-5)
    assert parse("285.507 lbf/in", Kind.FORCE_PER_LENGTH, field="A") == a  # lb read as lbf


def test_campbell_barrier_example_4():
    """Case 4: m = 1500 kg, V = 15.6 m/s, C = 0.55 m, L = 1.6 m, b0 = 2.2 m/s: b1 = 24.364 1/s,
    A = 50 250 N/m, B = 556 488 N/m^2, G = 2268.8 J/m, and L e(C) = 1/2 m V^2 = 182 520 J."""
    b1 = campbell_slope(15.6, 0.55, 2.2)
    a, b, g = campbell_coefficients(1500.0, 1.6, 2.2, b1)
    assert b1 == pytest.approx(24.364, abs=5e-4)
    assert a == pytest.approx(50_250.0, rel=1e-9)
    assert b == pytest.approx(556_488.0, abs=0.5)
    assert g == pytest.approx(2268.8, abs=0.05)
    assert uniform_energy(a, b, 1.6, 0.55) == pytest.approx(0.5 * 1500.0 * 15.6**2, rel=1e-12)
    assert 0.5 * 1500.0 * 15.6**2 == pytest.approx(182_520.0)


def test_preset_stiffness_is_the_stated_campbell_example():
    """The library's car-midsize front stiffness is what its source says: Campbell's method on the
    stated barrier test (case 4), not a number typed in from elsewhere."""
    entry = presets()["car-midsize"]["crush"]["front"]
    assert "DERIVED EXAMPLE" in entry["source"]
    a, b, _ = campbell_coefficients(1500.0, 1.6, 2.2, campbell_slope(15.6, 0.55, 2.2))
    assert parse(entry["A"], Kind.FORCE_PER_LENGTH, field="A") == pytest.approx(a, rel=1e-6)
    assert parse(entry["B"], Kind.FORCE_PER_AREA, field="B") == pytest.approx(b, rel=1e-6)


@pytest.mark.parametrize("profile", [[0.1, 0.2, 0.3], [0.1], [0.1, -0.2]])
def test_core_rejects_bad_profiles(profile):
    with pytest.raises(ValueError):
        profile_energy(A, B, L, profile)


# ------------------------------------------------------------------------------ scenario
@pytest.fixture
def data():
    return tomllib.loads(SCENE.read_text())


def test_scenario_items_are_built(data):
    sc = scenario_from_dict(data)
    a, b = sc.evidence.crush
    assert (a.body, a.face, a.A, a.B, a.width, a.profile) == ("carA", "front", A, B, L, tuple(SIX))
    assert a.energy_uncorrected == pytest.approx(55_175.0)
    assert b.ees == 6.5 and b.energy_uncorrected == pytest.approx(0.5 * 1200 * 6.5**2)


def test_preset_stiffness_is_used_when_A_and_B_are_omitted(data):
    d = copy.deepcopy(data)
    d["vehicles"]["A"]["bodies"][0]["preset"] = "car-midsize"
    del d["evidence"]["crush"][0]["A"], d["evidence"]["crush"][0]["B"]
    it = scenario_from_dict(d).evidence.crush[0]
    assert it.A == pytest.approx(50_250.0) and it.B == pytest.approx(556_488.0)
    assert it.source.startswith("preset 'car-midsize'")


def _error(d) -> ScenarioError:
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(d, file="case.toml")
    return info.value


@pytest.mark.parametrize("key, value, field, words", [
    ("profile", ["0.1 m", "0.2 m", "0.3 m"], "evidence.crush[0].profile", ['"0.3 m"]', "has 3 values", "2, 4 or 6"]),
    ("profile", ["0.1 m", "-0.2 m"], "evidence.crush[0].profile[1]", ['"-0.2 m"', "out of range", "[0, 5] m"]),
    ("A", "50000", "evidence.crush[0].A", ['"50000" has no unit', "force per length"]),
    ("B", "600000", "evidence.crush[0].B", ['"600000" has no unit', "force per area"]),
    ("A", "50000 N", "evidence.crush[0].A", ['"50000 N" is a force', "N/m"]),
])
def test_bad_values_name_file_key_and_value(data, key, value, field, words):
    data["evidence"]["crush"][0][key] = value
    exc = _error(data)
    assert exc.field == field and exc.file == "case.toml"
    for w in words:
        assert w in str(exc), str(exc)


def test_missing_B_is_named(data):
    del data["evidence"]["crush"][0]["B"]
    exc = _error(data)
    assert exc.field == "evidence.crush[0].B" and "missing B" in str(exc) and "A, width, profile" in str(exc)


def test_ees_with_a_profile_and_tolerance_rules(data):
    d = copy.deepcopy(data)
    d["evidence"]["crush"][1]["width"] = "1 m"
    assert _error(d).field == "evidence.crush[1].ees"
    d = copy.deepcopy(data)
    del d["evidence"]["crush"][1]["tolerance"]
    assert _error(d).field == "evidence.crush[1].tolerance"
    d = copy.deepcopy(data)
    d["evidence"]["crush"][1]["compare"] = "normal"
    exc = _error(d)
    assert exc.field == "evidence.crush[1].compare" and "'normal'" in str(exc)


def test_bad_input_exits_2_with_one_line(tmp_path, capsys):
    text = SCENE.read_text().replace('profile = ["0.10 m", "0.20 m", "0.30 m", "0.35 m", "0.30 m", "0.20 m"]',
                                     'profile = ["0.10 m", "0.20 m", "0.30 m"]')
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert str(path) in err and "evidence.crush[0].profile" in err and "2, 4 or 6" in err


def test_schema_documents_the_crush_item():
    doc = schema_document()
    assert "[[evidence.crush]]" in doc
    for key in ("evidence.crush[].A", "evidence.crush[].B", "evidence.crush[].profile", "evidence.crush[].ees",
                "evidence.crush[].compare", "evidence.crush[].sigma"):
        assert key in doc
    assert "list of 2, 4 or 6 x length [m]" in doc
    assert "force per length [N/m]" in doc and "lbf/in" in doc


def test_presets_command_lists_the_crush_stiffness_and_its_source(capsys):
    assert main(["presets"]) == 0
    out = capsys.readouterr().out
    assert "crush stiffness, front: A 50250 N/m, B 556488 N/m^2" in out and "DERIVED EXAMPLE" in out
