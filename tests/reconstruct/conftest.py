import pytest

import crashsim.scenario as scenario_module
from crashsim.inverse_schema import with_inverse_sections


@pytest.fixture(autouse=True)
def inverse_schema(monkeypatch):
    """The scenario schema with [fit], [uncertainty] and the evidence sigma keys.

    A no-op once crashsim.scenario.SCHEMA is built with with_inverse_sections (idempotent).
    """
    monkeypatch.setattr(scenario_module, "SCHEMA", with_inverse_sections(scenario_module.SCHEMA))
    yield
