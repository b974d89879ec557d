"""Fuzz: the two run-out engines on seeded random valid inputs (``random_runouts.py``).

Every case is valid, so every run must end (no hang, no exception) with the same status on
both engines, and where both reach rest, at the same rest (within 1 cm and 0.1 deg).  Both are
run at rtol 1e-8: the scene cases chain impacts, and an impact cascade amplifies integration
error (one measured scene moved 1.1 m on the compiled engine at rtol 1e-6, 4 cm at 1e-8,
``plots/engine_fuzz.md``).  A scene can also sit on a bifurcation (a touch just above or
below the impact threshold): if the engines disagree at 1e-8, both are run again at 1e-10 and
must then agree -- the difference was integration error, not a difference of the models.

The scenes draw air brakes too (about a third of their vehicles: :func:`random_runouts._air_braked`).
On every scene both engines report the same later impacts (the same pairs in the same order,
within 1 ms); on every case with load transfer (the rollover check is on there) both report the
same wheel-lift and rollover events (the same kinds of the same bodies, within 1 ms). The
energy ledger closes (the kinetic energy before the run-out is the sum of what the impacts, tyres, articulation stops and contacts took, plus what is left) to 1e-6 of
the start, no line of it is negative (no mechanism makes energy), no point lies deeper than
the pair's peak force over the stiffness plus 1 mm, and no point in contact closes at the
impulse threshold outside an impact (every re-strike is an impact).

The larger sweep behind the numbers is ``benchmarks/engine_fuzz.py`` (``plots/engine_fuzz.md``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from crashsim.motion import ContactModel, simulate_runout, simulate_scene
from crashsim.motion.rollover import ROLL_EVENT_KINDS
from random_runouts import DOLLY_KINDS, random_case, random_scene, random_tangle

SEED = 20261124
N_SINGLE = 16
N_SCENES = 20
N_DOLLIES = 8
N_TANGLES = 12
POS_TOL = 0.01  # m
HEADING_TOL = math.radians(0.1)
IMPACT_TOL = 1e-3  # s
LEDGER_TOL = 1e-6  # of the kinetic energy at the start


def _rest(result):
    vehicles = getattr(result, "vehicles", None) or {"v": result}
    return {n: (b.rest_position, b.rest_heading) for r in vehicles.values() for n, b in r.bodies.items()}


def _difference(a, b):
    ra, rb = _rest(a), _rest(b)
    assert ra.keys() == rb.keys()
    dp = max(math.dist(ra[n][0], rb[n][0]) for n in ra)
    dh = max(abs(math.remainder(ra[n][1] - rb[n][1], 2 * math.pi)) for n in ra)
    return dp, dh


def _impacts(result):
    return [(i.body1, i.body2, i.t) for i in getattr(result, "impacts", ())]


def _same_impacts(a, b) -> bool:
    """The same later impacts on both engines: the same pairs in the same order, within IMPACT_TOL."""
    ia, ib = _impacts(a), _impacts(b)
    return len(ia) == len(ib) and all(x[:2] == y[:2] and abs(x[2] - y[2]) <= IMPACT_TOL for x, y in zip(ia, ib))


def _roll_events(result) -> dict:
    """The wheel-lift and rollover events of a run, ``{(kind, body): time}`` (each at most once per body;
    none without the check)."""
    return {(e.kind, e.data["body"]): e.t for e in result.events if e.kind in ROLL_EVENT_KINDS}


def _same_roll_events(a, b) -> bool:
    """The same wheel-lift and rollover events on both engines: the same kinds of the same bodies, within
    IMPACT_TOL (each located on its engine's own solution by the same rule; events of equal time may be
    listed in either order)."""
    ra, rb = _roll_events(a), _roll_events(b)
    return ra.keys() == rb.keys() and all(abs(ra[k] - rb[k]) <= IMPACT_TOL for k in ra)


def _agree(a, b) -> bool:
    if a.status != b.status or not _same_impacts(a, b) or not _same_roll_events(a, b):
        return False
    dp, dh = _difference(a, b)
    return dp <= POS_TOL and dh <= HEADING_TOL


def _both(run, options, rtol):
    return {e: run(dataclasses.replace(options, engine=e, rtol=rtol, atol=rtol / 100)) for e in ("scipy", "compiled")}


def _check_engines(run, options, label):
    runs = _both(run, options, 1e-8)
    if not _agree(runs["scipy"], runs["compiled"]):
        runs = _both(run, options, 1e-10)
        a, b = runs["scipy"], runs["compiled"]
        assert a.status == b.status, (label, a.status, b.status, a.message, b.message)
        assert _same_impacts(a, b), (label, _impacts(a), _impacts(b))
        assert _same_roll_events(a, b), (label, _roll_events(a), _roll_events(b))
        dp, dh = _difference(a, b)
        assert dp <= POS_TOL and dh <= HEADING_TOL, (label, dp, math.degrees(dh))
    for r in runs.values():
        assert r.status in ("rest", "time_limit"), (label, r.status, r.message)
    return runs


@pytest.mark.parametrize("i", range(N_SINGLE))
def test_single_vehicle_engines_agree(i):
    c = random_case(SEED, i)
    _check_engines(lambda o: simulate_runout(c.vehicle, c.initial, c.wheels, c.road, o), c.options, c.label)


@pytest.mark.parametrize("i", range(N_DOLLIES))
def test_dollies_and_self_steering_axles_engines_agree(i):
    """Doubles with an A- or C-dolly (yaw-locked), self-steering axles free, locked, or locked later."""
    c = random_case(SEED, i, kinds=DOLLY_KINDS)
    runs = _check_engines(lambda o: simulate_runout(c.vehicle, c.initial, c.wheels, c.road, o), c.options, c.label)
    if c.vehicle.hitches[1].yaw_locked:  # the C-dolly stays aligned with the lead trailer to the end
        for r in runs.values():
            semi, dolly = r.bodies["semi"], r.bodies["dolly"]
            assert abs(math.remainder(semi.rest_heading - dolly.rest_heading, 2 * math.pi)) < 1e-6, c.label


@pytest.mark.parametrize("i", range(N_SCENES))
def test_scene_engines_agree_and_the_ledger_closes(i):
    check_scene(random_scene(SEED, i))


@pytest.mark.parametrize("i", range(N_TANGLES))
def test_tangles_run_to_rest_and_nothing_makes_energy(i):
    """Three vehicles in contact at once from the start (a car pinned between two, overlapping by up to
    0.4 m: :func:`random_runouts.random_tangle`): both engines agree as on the other scenes, every ledger
    line is >= 0, no point closes at the threshold outside an impact, the instants solved stay few (no
    chatter), and with load transfer every vehicle's wheel loads sum to its weight at every sample."""
    c = random_tangle(SEED, i)
    runs = check_scene(c)
    for engine, r in runs.items():
        assert r.status == "rest", (c.label, engine, r.status, r.message)
        assert len({m.t for m in r.impacts}) <= 40, (c.label, engine, len(r.impacts))
        if c.options.load_transfer:
            check_loads(r, c, (c.label, engine))


def check_loads(run, c, label):
    """Each vehicle's wheel loads sum to its weight at every sample (wheels that lift carry zero, the
    others the rest: :func:`crashsim.motion.kernels.tyres.redistribute_loads`)."""
    from crashsim.motion.loads import STANDARD_GRAVITY

    for v in c.vehicles:
        res = run.vehicles[v.name]
        total = np.sum([w.load for w in res.wheels.values()], axis=0)
        assert total == pytest.approx(v.mass * STANDARD_GRAVITY, rel=1e-9), (label, v.name)
        assert np.all(np.concatenate([w.load for w in res.wheels.values()]) >= 0.0), (label, v.name)


def test_the_tangles_are_tangles():
    """Every drawn tangle starts with three bodies in contact at once (two pairs disarmed), most overlap,
    and the sample has impacts of several pairs at one instant."""
    simultaneous = 0
    for i in range(N_TANGLES):
        c = random_tangle(SEED, i)
        r = simulate_scene(c.vehicles, c.initial, c.wheels, c.road, dataclasses.replace(c.options, engine="compiled"),
                           obstacles=c.obstacles)
        assert sum(e.kind == "armed" for e in r.events) <= 2
        times = [m.t for m in r.impacts]
        simultaneous += len(times) - len(set(times))
    assert simultaneous >= 1


def test_event_search_regression_scene():
    """Scene 2 of the seed without its air brakes: its pup strikes a car 0.9 ms before its semitrailer
    would (the regression case of the shared event search; with the air brakes the scene draws now,
    the truck brakes and the two strikes no longer come so close)."""
    check_scene(random_scene(SEED, 2, air_brakes=False))


def check_scene(c):
    """Both engines agree on scene ``c``, and every ledger closes with no negative line, impacts booked as
    impacts, contacts bounded (:func:`check_contacts`)."""
    runs = _check_engines(lambda o: simulate_scene(c.vehicles, c.initial, c.wheels, c.road, o, obstacles=c.obstacles),
                          c.options, c.label)
    for engine, r in runs.items():
        e = r.energy
        for line in ("impacts", "tyres", "stops", "contacts", "final"):
            assert e[line] >= -1e-9 * e["initial"], (c.label, engine, line, e)
        assert abs(e["closing_error"]) <= LEDGER_TOL * e["initial"], (c.label, engine, e)
        assert e["impacts"] == pytest.approx(sum(m.energy_loss for m in r.impacts), abs=1e-6)
        check_contacts(r, (c.label, engine))
    return runs


def check_contacts(run, label, contact=ContactModel()):
    """Penetration stays bounded and every re-strike is an impact: no point of a pair lies deeper
    beyond its allowance than the pair's peak force over the stiffness plus 1 mm, and no point in
    contact closes at the impulse threshold or faster outside the pair's impacts (both read off
    the solution at every integrator step, :func:`crashsim.motion.summaries.contact_summaries`)."""
    for p in run.pairs:
        assert p.max_penetration <= p.peak_force / contact.stiffness + 1e-3, (label, p.name, p.max_penetration,
                                                                             p.peak_force)
        assert p.max_closing <= contact.velocity_threshold * (1 + 1e-6) + 1e-9, (label, p.name, p.max_closing)


def test_the_single_sample_draws_air_brakes():
    """The single-vehicle sample has air-braked cases, with and without ABS, on articulated vehicles too."""
    braked = [random_case(SEED, i) for i in range(N_SINGLE)]
    braked = [c for c in braked if c.wheels.brakes is not None]
    assert len(braked) >= 3
    assert any(u.abs for c in braked for u in c.wheels.brakes.units.values())
    assert any(not u.abs for c in braked for u in c.wheels.brakes.units.values())
    assert any(len(c.vehicle.bodies) > 1 for c in braked)


def test_the_scene_sample_draws_air_brakes():
    """The whole-scene sample has vehicles with air brakes, with and without ABS, articulated ones among
    them, and steps of the brake force (a rise or fall time of 0)."""
    braked = [(v, c.wheels[v.name].brakes) for c in (random_scene(SEED, i) for i in range(N_SCENES)) for v in c.vehicles
              if c.wheels[v.name].brakes is not None]
    assert len(braked) >= 5
    units = [u for _, b in braked for u in b.units.values()]
    assert any(u.abs for u in units) and any(not u.abs for u in units)
    assert any(len(v.bodies) > 1 for v, _ in braked)
    assert any(u.rise == 0.0 for u in units)


def test_the_sample_has_impacts_contacts_and_articulated_vehicles():
    """The fuzz sample is not trivial: impacts, sustained contacts, stops and obstacles occur."""
    kinds, impacts, hitched, obstacles, restrikes = set(), 0, 0, 0, 0
    for i in range(N_SCENES):
        c = random_scene(SEED, i)
        r = simulate_scene(c.vehicles, c.initial, c.wheels, c.road, dataclasses.replace(c.options, engine="compiled"),
                           obstacles=c.obstacles)
        kinds |= {e.kind for e in r.events}
        impacts += len(r.impacts)
        pairs = [(i.body1, i.body2) for i in r.impacts]
        restrikes += len(pairs) - len(set(pairs))  # a pair struck again
        hitched += any(v.hitches for v in c.vehicles)
        obstacles += bool(c.obstacles)
    assert impacts >= 5 and hitched >= 5 and obstacles >= 2 and restrikes >= 1
    assert {"impact", "contact_end"} <= kinds


def test_the_scene_sample_draws_slopes_with_impacts_and_zones_of_their_own():
    """Scenes on sloped roads are drawn, some with zones of their own grade (the ledger's gravity work
    across zone edges) and among them the regression scene of the event search (scene 2: two bodies
    reaching one car 0.9 ms apart, without its air brakes: :func:`test_event_search_regression_scene`)."""
    scenes = [random_scene(SEED, i) for i in range(N_SCENES)]
    sloped = [c for c in scenes if c.road.sloped]
    assert len(sloped) >= 4
    assert any(any(z.grade is not None for z in c.road.zones) for c in sloped)
    assert scenes[2].road.sloped
    heights = [b.contact_height for c in scenes if c.options.load_transfer for v in c.vehicles for b in v.bodies]
    assert any(h is not None for h in heights) and any(h is None for h in heights)


def test_the_sample_has_rollover_events():
    """The rollover check of the fuzz is exercised: cases with the check record events, some after the start."""
    times = []
    for i in range(N_SINGLE):
        c = random_case(SEED, i)
        if c.options.rollover:
            r = simulate_runout(c.vehicle, c.initial, c.wheels, c.road, dataclasses.replace(c.options, engine="compiled"))
            times += list(_roll_events(r).values())
    assert len(times) >= 4 and max(times) > 0.1
