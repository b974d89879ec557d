"""One error does not spawn others (issue 31, item 7): a value the schema refuses is reported
once; what depends on it (a vehicle built from it, the run-out options, a sibling key's check) is
not re-reported as missing or unknown. And the messages the review asked for name the cause.

Each case is one mistake in a shipped scene: before the fix each gave 2-5 lines ('unknown body'
for bodies that exist, 'rollover check is off' with runout.rollover = true, 'missing A ... given:
none' with ees given).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from crashsim.cli import main

ROOT = Path(__file__).resolve().parents[2]
TRUCK = ROOT / "scenarios" / "scenes" / "truck_downgrade_abs.toml"
CRUSH = ROOT / "tests" / "data" / "crush_head_on.toml"


def _errors(tmp_path, capsys, src: Path, old: str, new: str) -> list[str]:
    text = src.read_text()
    assert old in text
    f = tmp_path / "case.toml"
    f.write_text(text.replace(old, new, 1))
    assert main(["run", str(f)]) == 2
    err = capsys.readouterr().err
    return [ln for ln in err.splitlines() if ln.strip()]


@pytest.mark.parametrize("old,new,key", [
    ('grade = "-6 %"', 'grade = "-6 %"\ncross_slope = "35 %"', "runout.cross_slope"),
    ('grade = "-6 %"', 'grade = "6 deg/s"', "runout.grade"),
    ('preset = "semitrailer-loaded"', 'preset = "semitrailer-loaded"\nmass = "26.5 T"', "vehicles.truck.bodies[1].mass"),
    ('position = ["0 m", "0 m"]', 'position = ["0 m", "\u22126 ft"]', "vehicles.truck.position[1]"),
])
def test_one_mistake_one_line(tmp_path, capsys, old, new, key):
    lines = _errors(tmp_path, capsys, TRUCK, old, new)
    assert len(lines) == 1, lines
    assert key in lines[0]


def test_a_refused_ees_is_not_reported_missing(tmp_path, capsys):
    lines = _errors(tmp_path, capsys, CRUSH, 'ees = "6.5 m/s"', 'ees = "-55 mph"')
    assert len(lines) == 1 and "evidence.crush[1].ees" in lines[0], lines


def test_messages_name_the_cause(tmp_path, capsys):
    (line,) = _errors(tmp_path, capsys, TRUCK, 'preset = "semitrailer-loaded"',
                      'preset = "semitrailer-loaded"\nmass = "26.5 T"')
    assert "T is the tesla" in line and "did you mean 't'" in line
    (line,) = _errors(tmp_path, capsys, TRUCK, 'position = ["0 m", "0 m"]', 'position = ["0 m", "\u22126 ft"]')
    assert "U+2212 (minus sign)" in line and "'-'" in line


def test_a_real_second_error_is_still_reported(tmp_path, capsys):
    """The filter drops consequences only: two independent mistakes give two lines."""
    text = TRUCK.read_text().replace('grade = "-6 %"', 'grade = "-6 %"\ncross_slope = "35 %"', 1)
    text = text.replace('rollover = true', 'rollover = true\nrollover_typo = 1', 1)
    f = tmp_path / "two.toml"
    f.write_text(text)
    assert main(["run", str(f)]) == 2
    lines = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(lines) == 3 and any("cross_slope" in ln for ln in lines) and any("rollover_typo" in ln for ln in lines)
