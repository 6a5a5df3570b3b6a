"""Earth rotation to first order in n: the Coriolis and gyroscopic-coupling terms.

Quet 1853 sec. 1 §III eq. (16): the relative acceleration of a point carries the compound
centrifugal (Coriolis) term 2 Ω × v; sec. 1 §IV eq. (20) gives it for Earth-fixed axes.
For a rigid body turning about a fixed point with relative angular velocity w in axes
rotating at constant Ω, the absolute angular velocity is w + Ω and the absolute angular
acceleration is ẇ + Ω × w, so the inertia torque I α + ω × I ω splits into a part without Ω,
the part linear in Ω given here, and the O(Ω²) part of :mod:`.centrifugal`.
"""

from collections.abc import Callable

import numpy as np

from gyro_instrument.core.effect import (CONSERVATIVE, CORIOLIS, DEFAULT_ON, FRAME_RATE, GYROSCOPIC, POINT_MASS, RIGID_BODY,
                                         Effect)
from gyro_instrument.core.vector import cross3


class EarthRotation(Effect):
    """First-order Earth-rate terms (Coriolis on points, gyroscopic coupling on bodies)."""

    name = "earth_rotation"
    summary = "Coriolis / gyroscopic coupling, first order in the Earth rate n"
    MECHANICS = frozenset({POINT_MASS, RIGID_BODY, FRAME_RATE})
    #: −2 Ω × v on points, the inertia torque's part linear in Ω on bodies; the frame rate n itself.
    TERMS = frozenset({CORIOLIS, GYROSCOPIC})
    #: Gyroscopic (Coriolis does no work) and assumed by a reader: a scene without it gets a note.
    CAPABILITIES = frozenset({CONSERVATIVE, DEFAULT_ON})
    #: What a scene leaving it out simulates, for the note (:func:`gyro_instrument.scenes.scene_notes`).
    ABSENT_MEANS = ("the instruments move as on a non-rotating Earth (n = 0 in the model: no Foucault precession, "
                    "no gyroscopic directing torque) and the predictions say the same")
    #: The same for one instrument that leaves it out.
    ABSENT_MEANS_FOR_ONE = "it moves as on a non-rotating Earth and its predictions assume n = 0"
    #: What an instrument whose kinds it does not meet ignores by design.
    UNSUPPORTED_MEANS = "ignores the Earth's rotation by design"

    def relative_size(self, ctx) -> tuple:
        if ctx.scales.get("sensed_rate_rad_s"):
            return 1.0, "the Earth rate about the rate gyro's sensitive axis is its measured signal itself"
        if ctx.scales.gyro_rate_rad_s:
            return 1.0, "the Earth-rate torque is the gyroscope's restoring torque itself"
        if ctx.scales.get("torsion_share", 0.0) >= 1.0:
            return 0.0, ("no rotor spin, no directing torque (Quet sec. 4 §1 eq. 2 with rho = 0): a torsion "
                         "pendulum on its tape; the Earth's rate enters only at O(n^2) (centrifugal)")
        n = ctx.scales.earth_rate_rad_s
        return n * ctx.scales.duration_s, "n * duration (swing-plane turn over the run, rad, at most)"

    def point_mass_term(self, ctx) -> Callable:
        """Coriolis acceleration −2 Ω × v (:func:`coriolis_acceleration`, component form).

        Ω in ENU has no east part (n (0, cos γ, sin γ)); then the zero products are left out and
        the factor −2 is taken into the coefficients (exact: a power of two), so each component is
        the same double as in the general form for finite v, in 5 array operations instead of 12
        (the pendulum's batched right-hand side calls it ~5 700 times a sidereal day)."""
        ox, oy, oz = (float(o) for o in ctx.omega_enu)
        if ox == 0.0:
            m2y, m2z = -2.0 * oy, -2.0 * oz

            def coriolis_no_east(dx, dy, dz, vx, vy, vz):
                return -m2z * vy + m2y * vz, m2z * vx, -m2y * vx
            return coriolis_no_east

        def coriolis(dx, dy, dz, vx, vy, vz):
            return -2.0 * (oy * vz - oz * vy), -2.0 * (oz * vx - ox * vz), -2.0 * (ox * vy - oy * vx)
        return coriolis

    def rigid_body_torque(self, ctx, inertia, w_rel, omega_b) -> np.ndarray:
        """The inertia torque's part linear in Ω (:func:`rigid_body_inertia_torque_linear`)."""
        return rigid_body_inertia_torque_linear(inertia, w_rel, omega_b)

    def frame_rate_rad_s(self, ctx) -> float:
        """The site's Earth rate n (the frame turns; without this effect n = 0 in the model)."""
        return ctx.site.earth_rate_rad_s


def coriolis_acceleration(omega, v) -> np.ndarray:
    """Coriolis acceleration −2 Ω × v (Quet sec. 1 eq. 16), all vectors in one frame; ndarray (3,)."""
    return -2.0 * cross3(omega, v)


def rigid_body_inertia_torque_linear(inertia, w_rel, omega_b) -> np.ndarray:
    """Part of the inertia torque linear in Ω: I(Ω×w) + w×IΩ + Ω×Iw (body axes)."""
    return inertia @ cross3(omega_b, w_rel) + cross3(w_rel, inertia @ omega_b) \
        + cross3(omega_b, inertia @ w_rel)
