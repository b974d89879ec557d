"""Work-energy identity with locked wheels in combined motion (note sec. 5 item 5).

    1/2 m v0^2 + 1/2 I w0^2 = sum_k mu N_k s_k,      s_k = integral |v_k| dt (the wheel's sliding path)

holds for ideal Coulomb friction.  The regularised law dissipates ``mu N |v|^2/sqrt(|v|^2+eps^2)``
instead of ``mu N |v|``; the difference is below ``0.3 eps mu N`` per wheel at any speed
(max of ``v (1 - v/sqrt(v^2+eps^2))``), so over a run of duration T the identity holds within
``0.3 eps T sum(mu N_k) + KE_end`` plus the solver tolerance.  The exact power identity of the model,
``KE_0 - KE_end = sum of the wheels' dissipated energies``, must hold to the solver tolerance.
"""

from __future__ import annotations

import pytest
from runout_cases import GLOBAL, car, tractor_semitrailer

from crashsim.motion import Road, RunoutOptions, make_hitch_consistent, simulate_runout
from crashsim.vehicles import BodyState, chain_states

OPTS = RunoutOptions(rtol=1e-10, atol=1e-12, eps=1e-4, v_stop=1e-3)


def _check_identity(res, mu):
    ke0 = res.kinetic_energy_initial
    assert abs(res.energy_residual) < GLOBAL * OPTS.rtol
    work = sum(mu * track.static_load * track.sliding_length for track in res.wheels.values())
    friction_total = sum(mu * track.static_load for track in res.wheels.values())
    bound = 0.3 * OPTS.eps * res.t_end * friction_total + res.kinetic_energy_final + GLOBAL * OPTS.rtol * ke0
    assert abs(ke0 - work) <= bound
    assert bound < 1e-4 * ke0  # the check is sharp, not vacuous


@pytest.mark.parametrize(
    "velocity, yaw_rate", [((15.0, 3.0), 2.0), ((2.0, 0.0), 10.0), ((-6.0, 9.0), -4.0)]
)
def test_single_body_locked(velocity, yaw_rate):
    mu = 0.75
    res = simulate_runout(car(), {"car": BodyState((1.0, 2.0), 0.7, velocity, yaw_rate)}, None, Road(mu), OPTS)
    assert res.status == "rest"
    _check_identity(res, mu)


def test_articulated_locked():
    """Both units slide and yaw; the hitch must do no net work (the best test of the constraint code)."""
    mu = 0.7
    veh = tractor_semitrailer()
    init = make_hitch_consistent(veh, chain_states(veh, (0.0, 0.0), 0.2, (14.0, 3.0), yaw_rates=[0.8, -0.3]))
    res = simulate_runout(veh, init, None, Road(mu), OPTS)
    assert res.status == "rest"
    assert abs(res.hitches[0].articulation[-1] - res.hitches[0].articulation[0]) > 0.05  # it did articulate
    _check_identity(res, mu)


def test_simultaneous_stop_of_sliding_and_spinning():
    """Translation and rotation cease together (Farkas et al. 2003, note item 6): when the body stops,
    both the CG speed and |w| L_ref have fallen to the rest threshold within the same short interval."""
    mu = 0.75
    opts = RunoutOptions(rtol=1e-10, atol=1e-12, eps=1e-4, v_stop=1e-3)
    res = simulate_runout(car(), {"car": BodyState((0.0, 0.0), 0.0, (15.0, 3.0), 2.0)}, None, Road(mu), opts)
    h = res.bodies["car"].history
    speed = (h.vx**2 + h.vy**2) ** 0.5
    spin = abs(h.yaw_rate) * 2.3
    t_v = h.t[speed < 0.01 * speed[0]][0]
    t_w = h.t[spin < 0.01 * spin[0]][0]
    assert abs(t_v - t_w) < 0.03 * res.t_end
