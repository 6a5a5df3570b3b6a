"""Errors raised by the core.

``SceneError`` is a ``ValueError`` whose message names the field, the bad value and the valid
range (astropy style), so the CLI can print it on one line and exit with status 2.
"""


class SceneError(ValueError):
    """A scene or parameter value is invalid.

    Parameters
    ----------
    field : str
        Dotted path of the offending field, e.g. ``site.latitude_deg``.
    value : object
        The value that was given.
    valid : str
        Human-readable description of the valid range or choices.
    """

    def __init__(self, field, value, valid) -> None:
        self.field = field
        self.value = value
        self.valid = valid
        super().__init__(f"{field} = {value!r} is invalid: {valid}")


class IntegrationError(RuntimeError):
    """The integrator failed (step size underflow, non-finite state, ...)."""
