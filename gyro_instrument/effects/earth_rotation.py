"""Earth rotation to first order in n: the Coriolis and gyroscopic-coupling terms.

Quet 1853 sec. 1 §III eq. (16): the relative acceleration of a point carries the compound
centrifugal (Coriolis) term 2 Ω × v; sec. 1 §IV eq. (20) gives it for Earth-fixed axes.
For a rigid body turning about a fixed point with relative angular velocity w in axes
rotating at constant Ω, the absolute angular velocity is w + Ω and the absolute angular
acceleration is ẇ + Ω × w, so the inertia torque I α + ω × I ω splits into a part without Ω,
the part linear in Ω given here, and the O(Ω²) part of :mod:`.centrifugal`.
"""


from gyro_instrument.core.effect import Effect
from gyro_instrument.core.vector import cross3


class EarthRotation(Effect):
    """First-order Earth-rate terms (Coriolis on points, gyroscopic coupling on bodies)."""

    name = "earth_rotation"
    summary = "Coriolis / gyroscopic coupling, first order in the Earth rate n"

    def relative_size(self, scales):
        if scales.get("gyro_rate_rad_s"):
            return 1.0, "the Earth-rate torque is the gyroscope's restoring torque itself"
        n = scales["earth_rate_rad_s"]
        return n * scales["duration_s"], "n * duration (swing-plane turn over the run, rad, at most)"


def coriolis_acceleration(omega, v):
    """Coriolis acceleration −2 Ω × v (Quet sec. 1 eq. 16), all vectors in one frame."""
    return -2.0 * cross3(omega, v)


def rigid_body_inertia_torque_linear(inertia, w_rel, omega_b):
    """Part of the inertia torque linear in Ω: I(Ω×w) + w×IΩ + Ω×Iw (body axes)."""
    return inertia @ cross3(omega_b, w_rel) + cross3(w_rel, inertia @ omega_b) \
        + cross3(omega_b, inertia @ w_rel)
