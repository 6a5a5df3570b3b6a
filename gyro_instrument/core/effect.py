"""The ``Effect`` interface: one physical effect, switched on by listing it in a scene.

Each effect lives in its own module under ``gyro_instrument.effects`` (model: Orekit's
``ForceModel``, whose ``acceleration`` the numerical propagator sums). An effect knows generic
mechanics, never an instrument: it declares in ``MECHANICS`` the kinds it contributes to and
supplies its terms for those kinds through the hooks below; an instrument declares the kinds its
right-hand side sums (``Instrument.MECHANICS``) and adds the terms of its active effects. An
instrument supports exactly the effects that contribute to one of its kinds, so a new effect of a
known kind needs its own module and a line in the registry, nothing else.

The kinds (:data:`MECHANICS`) and their hooks (SI units; a hook of a kind the effect does not
declare is never called):

==================  ==================================================================================
``point_mass``      :meth:`Effect.point_mass_term`: acceleration of a point (a pendulum bob) in the
                    Earth-fixed rotating frame, from its displacement from the rest point and its
                    velocity relative to the Earth (Quet 1853 sec. 1 eqs. 16, 19–20)
``rigid_body``      :meth:`Effect.rigid_body_torque`: part of the inertia torque of a body turning
                    about a fixed point, body axes (hinge chains; sec. 1 §III–IV for rigid bodies)
``damping``         :meth:`Effect.damping_torque`: torque on a swinging hinge
``spin``            :meth:`Effect.spin_torque`: torque on a rotor's spin hinge (its bearing)
``restoring_law``   :meth:`Effect.restoring_law`: the function of the swing angle in a restoring
                    torque (absent: the small-angle law, the angle itself)
``carrier_inertia`` :meth:`Effect.carrier_inertia`: the inertia of carriers (gimbal rings) taking part
                    in the motion (absent: massless carriers)
``frame_rate``      :meth:`Effect.frame_rate_rad_s`: the rotation rate of the Earth-fixed frame, for
                    closed forms that carry every order in it (absent: 0)
==================  ==================================================================================

Contributions are summed in the registry's order (:func:`gyro_instrument.effects.canonical_order`),
so a result does not depend on the order a scene lists its effects.

``relative_size`` estimates, from an instrument's characteristic scales, how much leaving the
effect out would change the result, for ``gyro-instrument describe``.
"""

from collections.abc import Callable
from typing import ClassVar

import numpy as np

from gyro_instrument.core.params import validate_params

POINT_MASS = "point_mass"
RIGID_BODY = "rigid_body"
DAMPING = "damping"
SPIN = "spin"
RESTORING_LAW = "restoring_law"
CARRIER_INERTIA = "carrier_inertia"
FRAME_RATE = "frame_rate"

#: Every kind of mechanics an effect may contribute to (see the module docstring).
MECHANICS = frozenset((POINT_MASS, RIGID_BODY, DAMPING, SPIN, RESTORING_LAW, CARRIER_INERTIA, FRAME_RATE))


def supporting_effects(registry, kinds) -> frozenset:
    """Names of the effects of ``registry`` (name -> Effect subclass) that contribute to one of
    ``kinds`` (a set of :data:`MECHANICS`): frozenset of str."""
    kinds = frozenset(kinds)
    return frozenset(name for name, cls in registry.items() if cls.MECHANICS & kinds)


class Effect:
    """Base class of all physical effects.

    Subclasses set ``name``, ``summary``, ``PARAMS`` (a tuple of :class:`~gyro_instrument.core.params.Param`), ``MECHANICS``
    (the kinds they contribute to, a subset of :data:`MECHANICS`), implement
    :meth:`relative_size` and the hook of each declared kind. A hook's default contributes
    nothing.
    """

    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    PARAMS: ClassVar[tuple] = ()
    MECHANICS: ClassVar[frozenset] = frozenset()

    def __init__(self, field_prefix="effects", **params) -> None:
        self.params = validate_params(f"{field_prefix}.{self.name}", self.PARAMS, params)
        for key, value in self.params.items():
            setattr(self, key, value)

    def relative_size(self, scales) -> tuple:
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

    # ------------------------------------------------------------------ terms, one hook per kind
    def point_mass_term(self, omega_enu) -> Callable | None:
        """``point_mass``: a function ``f(dx, dy, dz, vx, vy, vz) -> (ax, ay, az)`` giving this
        effect's acceleration (m/s²) of a point in the Earth-fixed frame rotating at ``omega_enu``
        (rad/s, ENU, constant), from the point's displacement (m) from its rest point (where local
        gravity is measured) and its velocity relative to the Earth (m/s), all ENU components.
        Built once per right-hand side (constants bound, like Orekit's ``ForceModel.init``), then
        called at every evaluation with floats or with arrays of equal shape (batched states).
        None: no contribution."""
        return None

    def rigid_body_torque(self, inertia, w_rel, omega_b) -> np.ndarray:
        """``rigid_body``: this effect's part of the inertia torque I α_abs + ω_abs × I ω_abs of a
        body turning about a fixed point in axes rotating at the constant ``omega_b`` (body axes,
        rad/s); ``inertia`` (3, 3) kg m² and ``w_rel`` (3,) rad/s the body's angular velocity
        relative to the Earth, body axes. Returns an ndarray (3,), N m, added to I α + w × I w."""
        raise NotImplementedError(f"{self.name} declares no rigid_body term")

    def damping_torque(self, inertia, rate) -> float:
        """``damping``: torque (N m) on a swinging hinge of swinging inertia ``inertia`` (kg m²)
        turning at ``rate`` (rad/s) relative to its carrier."""
        raise NotImplementedError(f"{self.name} declares no damping term")

    def spin_torque(self, inertia, spin_rate) -> float:
        """``spin``: torque (N m) on a rotor's spin hinge, axial moment ``inertia`` (kg m²),
        spinning at ``spin_rate`` (rad/s) relative to its carrier."""
        raise NotImplementedError(f"{self.name} declares no spin term")

    def restoring_law(self) -> Callable:
        """``restoring_law``: the function g(angle) replacing the angle in a restoring torque
        (``math.sin``-like, accepting floats and arrays)."""
        raise NotImplementedError(f"{self.name} declares no restoring law")

    def carrier_inertia(self, inertia) -> float | np.ndarray:
        """``carrier_inertia``: the inertia (kg m², scalar or tensor) a carrier of given
        ``inertia`` contributes to the motion."""
        raise NotImplementedError(f"{self.name} declares no carrier inertia")

    def frame_rate_rad_s(self, site) -> float:
        """``frame_rate``: the rotation rate (rad/s) this effect gives the Earth-fixed frame at
        ``site``."""
        raise NotImplementedError(f"{self.name} declares no frame rate")

    def __repr__(self):
        return f"{type(self).__name__}({self.params})"
