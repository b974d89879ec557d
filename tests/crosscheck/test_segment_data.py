"""The run-out results read the integrators' segment arrays through ``segment_data``: for both engines
the same arrays (dtype, shape, values) as stacking the per-segment modes of ``segment_table``, also
for a vehicle at rest from the start (no segment: the arrays of the run's final mode)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import crashsim.motion.postprocess as post
from crashsim.motion import engine, simulate_runout

from test_fast_vs_scipy import CASES


@pytest.mark.parametrize("engine_name", ["scipy", "compiled"])
def test_segment_data_is_the_stacked_segment_table(engine_name, monkeypatch):
    seen = {"runs": 0, "empty": 0}
    assemble = post.assemble_scene

    def check(model, integrator, **kw):
        table = integrator.segment_table()
        ref = post.segment_arrays(table if table else [(0.0, 0.0, post.mode_snapshot(0, kw["mode"]))], model)
        bounds, arrays = integrator.segment_data(kw["mode"])
        assert [(a, b) for a, b, _ in bounds] == [(a, b) for a, b, _ in table]
        for x, y in zip(ref, arrays, strict=True):
            assert x.dtype == y.dtype and x.shape == y.shape and y.flags.c_contiguous and np.array_equal(x, y)
        seen["runs"] += 1
        seen["empty"] += not table
        return assemble(model, integrator, **kw)

    monkeypatch.setattr(engine, "assemble_scene", check)  # the name the engine calls
    for p in CASES:
        vehicle, initial, wheels, road, options = p.values[0]
        simulate_runout(vehicle, initial, wheels, road, dataclasses.replace(options, engine=engine_name))
    assert seen["runs"] == len(CASES) and seen["empty"] >= 1
