"""The compiled run-out engine against the SciPy engine: same model, same answers.

Every shipped scene (impact solved, separation states made hitch-consistent, then the run-out
of every movable vehicle at the scene's options) and both vehicles of the paper's Table 6
scene (``benchmarks/runout_solvers.py``: zones, a scheduled brake change, jammed wheels) run
on both engines.  Both integrate the same equations to rtol 1e-6, so they may differ by the
integration error only: rest positions within 1 mm, headings within 0.01 deg (at the 10 m
half-length of a trailer, 0.01 deg is 1.7 mm of corner travel: the same order as the position
bound), time to rest within 5 ms (the rest event is located to ~1e-15 s on each engine's
interpolant; the difference is the integration error of the speed near v_stop), the same
sequence of events at times within 1 ms, and the same derived quantities (path lengths,
dissipated energy, hitch forces) to 1e-4 relative.  Sliding (tyre-mark) lengths agree to 1 %:
a wheel's sliding flag can switch inside a solver step (neither engine locates it with an
event), so each switch carries a quadrature error of about speed x step, different for the
two engines' steps; at tight tolerance both converge to the same value.

Measured (``plots/fast_path.md``): the largest differences are 0.02 mm and 3.4e-4 deg.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from crashsim import solve_impact
from crashsim.motion import RunoutOptions, make_hitch_consistent, simulate_runout
from crashsim.scene.run import separation_states
from crashsim.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[2]
SCENES = sorted((ROOT / "scenarios" / "scenes").glob("*.toml"))

POS_TOL = 1e-3  # m
HEADING_TOL = math.radians(0.01)
TIME_TOL = 5e-3  # s
EVENT_TIME_TOL = 1e-3  # s


def _table6():
    spec = importlib.util.spec_from_file_location("runout_solvers", ROOT / "benchmarks" / "runout_solvers.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    vehicles, wheels, road = mod.build_scene()
    initial = mod.post_impact_states(vehicles)
    return [(v, {b.name: initial[b.name] for b in v.bodies}, wheels[v.name], road, RunoutOptions()) for v in vehicles]


def _scene_cases():
    cases = []
    for path in SCENES:
        sc = load_scenario(path)
        states = separation_states(sc, solve_impact(sc.impact))
        spec = sc.runout
        for veh in sc.vehicles:
            if veh.is_barrier:
                continue
            initial = make_hitch_consistent(veh, {b.name: states[b.name] for b in veh.bodies})
            case = (veh, initial, spec.wheels[veh.name], spec.road, spec.options)
            cases.append(pytest.param(case, id=f"{path.stem}-{veh.name}"))
    for case in _table6():
        cases.append(pytest.param(case, id=f"table6-{case[0].name}"))
    return cases


CASES = _scene_cases()


def test_every_shipped_scene_is_covered():
    assert len(SCENES) >= 4
    assert len(CASES) >= len(SCENES) + 2


@pytest.fixture(scope="module")
def runs():
    cache = {}

    def get(case):
        key = id(case[0]), case[0].name
        if key not in cache:
            vehicle, initial, wheels, road, options = case
            ref = simulate_runout(vehicle, initial, wheels, road, options)
            fast = simulate_runout(vehicle, initial, wheels, road, dataclasses.replace(options, engine="compiled"))
            cache[key] = ref, fast
        return cache[key]

    return get


@pytest.mark.parametrize("case", CASES)
def test_rest_states_agree(case, runs):
    ref, fast = runs(case)
    assert fast.method == f"compiled/{fast.options['scheme']}" and ref.method.startswith("scipy/")
    assert fast.status == ref.status == "rest"
    assert fast.success
    assert fast.t_end == pytest.approx(ref.t_end, abs=TIME_TOL)
    for name, body in ref.bodies.items():
        other = fast.bodies[name]
        assert math.dist(other.rest_position, body.rest_position) < POS_TOL, name
        assert abs(other.rest_heading - body.rest_heading) < HEADING_TOL, name
        assert other.time_to_rest == pytest.approx(body.time_to_rest, abs=TIME_TOL)
        assert other.distance == pytest.approx(body.distance, rel=1e-4, abs=1e-4)


@pytest.mark.parametrize("case", CASES)
def test_events_agree(case, runs):
    """Same zone crossings (wheel by wheel), stop impacts/closures/openings and schedule restarts."""
    ref, fast = runs(case)
    assert [(e.kind, e.detail.split(" at ")[0]) for e in fast.events if e.kind != "rest"] == [
        (e.kind, e.detail.split(" at ")[0]) for e in ref.events if e.kind != "rest"
    ]
    for a, b in zip(fast.events, ref.events):
        assert a.t == pytest.approx(b.t, abs=EVENT_TIME_TOL)
        assert a.energy == pytest.approx(b.energy, rel=1e-3, abs=1.0)
    assert fast.n_segments == ref.n_segments


@pytest.mark.parametrize("case", CASES)
def test_trajectories_tracks_and_hitch_forces_agree(case, runs):
    ref, fast = runs(case)
    t = np.linspace(0.0, min(ref.t_end, fast.t_end), 301)
    nb = len(ref.bodies)
    assert np.max(np.abs(fast.sol(t)[: 2 * nb] - ref.sol(t)[: 2 * nb])) < POS_TOL  # CG positions
    # same sample grid (segment starts, the sample_dt grid, the end)
    first = next(iter(ref.bodies.values())).history.t
    other = next(iter(fast.bodies.values())).history.t
    assert len(other) == len(first) and np.allclose(other, first, atol=2 * EVENT_TIME_TOL)
    for key, track in ref.wheels.items():
        mine = fast.wheels[key]
        assert mine.path_length == pytest.approx(track.path_length, rel=1e-4, abs=1e-4)
        assert mine.sliding_length == pytest.approx(track.sliding_length, rel=1e-2, abs=1e-2)
        assert mine.energy == pytest.approx(track.energy, rel=1e-4, abs=1.0)
        assert np.max(np.hypot(*(mine.points - track.points).T)) < 5 * POS_TOL
        assert np.mean(mine.sliding == track.sliding) > 0.98
        # with load transfer the loads follow the integrated filtered accelerations: a derived quantity
        # (1e-4, as the module says); truck_downgrade_abs (load_transfer level) is the first shipped scene whose
        # loads vary: its car, spinning at 300 deg/s, differs by 2.0e-6 between the engines (static loads: 0)
        assert mine.load == pytest.approx(track.load, rel=1e-4)
        assert [s.kind for s in mine.segments][:1] == [s.kind for s in track.segments][:1]
    assert fast.energy_dissipated == pytest.approx(ref.energy_dissipated, rel=1e-5)
    assert abs(fast.energy_residual) < 1e-4
    for h_ref, h_fast in zip(ref.hitches, fast.hitches):
        scale = max(h_ref.peak_force, 1.0)
        assert np.max(np.abs(h_fast.force - h_ref.force)) < 1e-2 * scale
        assert h_fast.peak_force == pytest.approx(h_ref.peak_force, rel=1e-3)
        assert np.max(np.abs(h_fast.articulation - h_ref.articulation)) < 1e-4
    assert fast.max_hitch_gap < 1e-5


def test_scene_pipeline_runs_unchanged_on_the_compiled_engine(tmp_path):
    """run_scene -> evidence -> report -> CSV with the compiled engine: the same verdicts."""
    from crashsim.scene.run import run_scene

    path = ROOT / "scenarios" / "scenes" / "car_trailer_side_impact.toml"
    sc = load_scenario(path)
    ref = run_scene(sc)
    options = dataclasses.replace(sc.runout.options, engine="compiled")
    fast_sc = dataclasses.replace(sc, runout=dataclasses.replace(sc.runout, options=options))
    fast = run_scene(fast_sc)
    assert [c.passed for c in fast.evidence.checks] == [c.passed for c in ref.evidence.checks]
    for c_ref, c_fast in zip(ref.evidence.checks, fast.evidence.checks):
        assert c_fast.residual == pytest.approx(c_ref.residual, abs=2e-3)
    assert "Run-out to rest" in fast.report()
    written = fast.write_csv(tmp_path)
    assert {p.name for p in written} == {p.name for p in ref.write_csv(tmp_path / "ref")}
    d = fast.to_dict(history=True)
    assert d["runout"]["vehicles"]["towing"]["method"] == "compiled/dopri5"
