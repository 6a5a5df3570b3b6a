"""Centrifugal terms, second order in the Earth rate n.

Quet sec. 1 §IV eq. (19): −u'', −v'', −w'' are the centrifugal force at the point. Local
gravity g is measured at the instrument's rest point and already holds the centrifugal part
there; what remains is the gradient −Ω × (Ω × δr) over the displacement δr from that point.
For a rigid body about a fixed point, the O(Ω²) inertia torque is Ω × I Ω (body axes).
For the directing-plane gyroscope this is the term (μ − 1) n² sin² ω cos u sin u that
eqs. (1)–(3) of sec. 4 §1 drop; its relative size is n / (μ ρ0).
"""

import math
from collections.abc import Callable

import numpy as np

from gyro_instrument.core.effect import CENTRIFUGAL_GRADIENT, CENTRIFUGAL_TORQUE, CONSERVATIVE, POINT_MASS, RIGID_BODY, Effect
from gyro_instrument.core.vector import cross3


class Centrifugal(Effect):
    """O(n²) centrifugal-gradient terms."""

    name = "centrifugal"
    summary = "centrifugal gradient, second order in the Earth rate n"
    MECHANICS = frozenset({POINT_MASS, RIGID_BODY})
    TERMS = frozenset({CENTRIFUGAL_GRADIENT, CENTRIFUGAL_TORQUE})   # −Ω × (Ω × δr); Ω × I Ω
    CAPABILITIES = frozenset({CONSERVATIVE})   # the gradient of the centrifugal potential

    def relative_size(self, ctx) -> tuple:
        scales = ctx.scales
        n = scales.earth_rate_rad_s
        if scales.gyro_rate_rad_s:
            return n / scales.gyro_rate_rad_s, "n / (mu rho0) (sec. 4 §1: dropped term over kept one)"
        w0 = scales.restoring_rate_rad_s
        if not w0:
            return math.inf, "(n / omega0)^2 with no restoring rate (omega0 = 0): nothing for it to be small against"
        if scales.get("torsion_share", 0.0) >= 1.0:
            return (n / w0) ** 2, "(n / omega0)^2: the O(n^2) torque against the tape's (a torsion pendulum)"
        return (n / w0) ** 2, "(n / omega0)^2 (n^2 l / g for a pendulum)"

    def point_mass_term(self, ctx) -> Callable:
        """−Ω × (Ω × δr) over the displacement δr from the rest point, written |Ω|² δr − (Ω·δr) Ω
        (:func:`centrifugal_gradient_acceleration`, component form).

        Ω in ENU has no east part (n (0, cos γ, sin γ)); then its zero products are left out: the
        same doubles for a finite δr in 10 array operations instead of 14."""
        ox, oy, oz = (float(o) for o in ctx.omega_enu)
        o2 = ox * ox + oy * oy + oz * oz
        if ox == 0.0:
            def gradient_no_east(dx, dy, dz, vx, vy, vz):
                od = oy * dy + oz * dz
                return o2 * dx, o2 * dy - od * oy, o2 * dz - od * oz
            return gradient_no_east

        def gradient(dx, dy, dz, vx, vy, vz):
            od = ox * dx + oy * dy + oz * dz
            return o2 * dx - od * ox, o2 * dy - od * oy, o2 * dz - od * oz
        return gradient

    def rigid_body_torque(self, ctx, inertia, w_rel, omega_b) -> np.ndarray:
        """The inertia torque's part quadratic in Ω (:func:`rigid_body_inertia_torque_quadratic`)."""
        return rigid_body_inertia_torque_quadratic(inertia, omega_b)


def centrifugal_gradient_acceleration(omega, dr) -> np.ndarray:
    """−Ω × (Ω × δr): change of the centrifugal acceleration over the displacement δr."""
    return -cross3(omega, cross3(omega, dr))


def rigid_body_inertia_torque_quadratic(inertia, omega_b) -> np.ndarray:
    """Part of the inertia torque quadratic in Ω: Ω × I Ω (body axes)."""
    return cross3(omega_b, inertia @ omega_b)
