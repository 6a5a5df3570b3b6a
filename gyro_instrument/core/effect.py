"""The ``Effect`` interface: one physical effect, switched on by listing it in a scene.

Each effect lives in its own module under ``gyro_instrument.effects`` (model: Orekit's
``ForceModel`` added one by one to a propagator). An effect knows generic mechanics (a point
mass, a rigid body, a hinge), never an instrument; instruments ask their active effects for
terms and evaluate only those. ``relative_size`` estimates, from an instrument's characteristic
scales, how much leaving the effect out would change the result, for ``gyro-instrument
describe``.
"""

from typing import ClassVar

from gyro_instrument.core.params import validate_params


class Effect:
    """Base class of all physical effects.

    Subclasses set ``name``, ``summary``, ``PARAMS`` (a tuple of :class:`Param`) and implement
    :meth:`relative_size`.
    """

    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    PARAMS: ClassVar[tuple] = ()

    def __init__(self, field_prefix="effects", **params):
        self.params = validate_params(f"{field_prefix}.{self.name}", self.PARAMS, params)
        for key, value in self.params.items():
            setattr(self, key, value)

    def relative_size(self, scales):
        """Estimated relative size of the effect for an instrument.

        Parameters
        ----------
        scales : dict
            The instrument's characteristic scales (see ``Instrument.scales``), e.g.
            ``earth_rate_rad_s``, ``restoring_rate_rad_s``, ``gyro_rate_rad_s``,
            ``amplitude_rad``, ``duration_s``.

        Returns
        -------
        (float, str)
            The size and the formula it comes from.
        """
        raise NotImplementedError

    def __repr__(self):
        return f"{type(self).__name__}({self.params})"
