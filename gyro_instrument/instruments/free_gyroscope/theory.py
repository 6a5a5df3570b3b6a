"""The free gyroscope's geometry and closed-form axis motion (Quet 1853 sec. 4 §II).

Pure functions of SI arguments: the axis from altitude and azimuth, the equatorial basis of a
site, a body frame about an axis, the angle between two vectors, and the closed-form motion of
the figure axis relative to the Earth (:func:`axis_relative_to_earth`). The instrument
(:mod:`gyro_instrument.instruments.free_gyroscope`) re-exports them.
"""

import math

import numpy as np

from gyro_instrument.core.quaternion import rotate_about


def axis_from_alt_az(altitude_rad, azimuth_rad) -> np.ndarray:
    """Unit ENU vector at ``altitude_rad`` above the horizon, compass ``azimuth_rad``."""
    ca = math.cos(altitude_rad)
    return np.array([ca * math.sin(azimuth_rad), ca * math.cos(azimuth_rad), math.sin(altitude_rad)])


def equatorial_basis(site) -> tuple:
    """ENU unit vectors (m, w, ê): m toward the local meridian's equator point (hour angle 0),
    w toward the west (hour angle +90°), ê the north part of Earth's axis."""
    g = site.latitude_rad
    return (np.array([0.0, -math.sin(g), math.cos(g)]), np.array([-1.0, 0.0, 0.0]),
            site.earth_axis_north_enu())


def body_frame(k0) -> np.ndarray:
    """A rotation matrix (columns b1, b2, k0) whose third column is the unit axis ``k0``."""
    ref = np.eye(3)[int(np.argmin(np.abs(k0)))]
    b1 = ref - np.dot(ref, k0) * k0
    b1 /= np.linalg.norm(b1)
    return np.column_stack([b1, np.cross(k0, b1), k0])


def angle_between(a, b) -> float:
    """Angle between two vectors, rad, accurate at 0 and π (atan2 of |a×b| and a·b)."""
    return math.atan2(float(np.linalg.norm(np.cross(a, b))), float(np.dot(a, b)))


def axis_relative_to_earth(k0, e_axis, n, mu, rho0, tau) -> np.ndarray:
    """Exact direction of the figure axis relative to the Earth at times ``tau`` after release.

    The torque-free closed form of the module docstring: ω0 = ρ0 k0 + n ê, ω3 = ω0·k0,
    Λ = ω0 + (μ − 1) ω3 k0; the axis turns about Λ at |Λ| in the inertial frame and the Earth
    turns at n about ê: k(τ) = Rot(ê, −nτ) Rot(Λ̂, |Λ|τ) k0.

    Parameters
    ----------
    k0, e_axis : array (3,)
        Unit initial axis and north part of Earth's axis (ENU).
    n, mu, rho0 : float
        Earth rate (rad/s), μ = C/A, relative spin at release (rad/s).
    tau : array (m,)
        Seconds since release.

    Returns
    -------
    ndarray (m, 3)
        Unit axis in ENU.
    """
    omega0 = rho0 * k0 + n * e_axis
    Lam = omega0 + (mu - 1.0) * float(np.dot(omega0, k0)) * k0
    lam = float(np.linalg.norm(Lam))
    tau = np.atleast_1d(np.asarray(tau, dtype=float))
    k_in = rotate_about(np.broadcast_to(k0, (tau.size, 3)), Lam / lam, lam * tau) if lam > 0.0 else \
        np.broadcast_to(k0, (tau.size, 3))
    return rotate_about(k_in, e_axis, -n * tau)
