"""Instrument-agnostic core: Earth site, frames, effect interface, scenes, integration."""

from gyro_instrument.core.errors import IntegrationError, SceneError
from gyro_instrument.core.site import SIDEREAL_RATE_RAD_S, Site
from gyro_instrument.core.integrate import Trajectory, integrate

__all__ = ["IntegrationError", "SceneError", "SIDEREAL_RATE_RAD_S", "Site", "Trajectory", "integrate"]
