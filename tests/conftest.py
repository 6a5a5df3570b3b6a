"""Shared fixtures: effects and instruments built the way scenes build them."""

import pytest

from gyro_instrument.core.params import validate_params
from gyro_instrument.effects import REGISTRY as EFFECTS


def make(cls, site, effects=(), **params):
    """Build an instrument of class ``cls`` at ``site`` with the named effects (default params)."""
    eff = {}
    for e in effects:
        if isinstance(e, tuple):
            eff[e[0]] = EFFECTS[e[0]](**e[1])
        else:
            eff[e] = EFFECTS[e]()
    return cls("test", site, validate_params("instruments.test", cls.PARAMS, params), eff)


@pytest.fixture
def build():
    return make
