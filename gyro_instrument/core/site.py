"""The Earth site: latitude, Earth rate and local gravity, with Quet's and ENU frames.

Conventions
-----------
ENU (REP-103): x east, y north, z up. The Earth-rate vector at latitude γ is
``n (0, cos γ, sin γ)`` in ENU (REP-145).

Quet's local axes for the pendulum (Quet 1853, sec. 1 §IV eq. 17 and sec. 2 §I): ``ox`` north
(projection of the north part of Earth's axis), ``oz`` down the plumb line and ``oy`` such that
p = n sin ω, q = 0, r = −n cos ω with ω = 90° − γ. Working the signs through gives a
right-handed north-east-down (NED) triad: ``oy`` points east. Quet's azimuth ψ is counted
"from the meridian, going from north to south by the east", i.e. a compass azimuth
(clockwise from north seen from above), and his k = n sin γ, k' = n cos γ.
"""

from dataclasses import dataclass, field

import numpy as np

from gyro_instrument.core.errors import SceneError

#: Earth's rotation rate relative to the stars (IERS Conventions 2010 / GRS80: 7.292115e-5 rad/s),
#: 2π / 86164.0989 s (the stellar day). The often-quoted 2π / 86164.0905 s uses the mean
#: sidereal day (relative to the precessing equinox) and gives 7.2921159e-5: 1.2e-7 higher.
SIDEREAL_RATE_RAD_S = 7.2921150e-5

#: Quet's value n = 1/13713 s⁻¹ (sec. 2), kept for reproducing his printed numbers.
QUET_RATE_RAD_S = 1.0 / 13713.0

#: Rotation matrix from Quet's pendulum axes (N, E, D) to ENU; its transpose goes back.
QUET_NED_TO_ENU = np.array([[0.0, 1.0, 0.0],
                            [1.0, 0.0, 0.0],
                            [0.0, 0.0, -1.0]])


def normal_gravity_m_s2(latitude_rad) -> float:
    """Normal gravity on the WGS-84 ellipsoid (Somigliana's closed form).

    Parameters
    ----------
    latitude_rad : float
        Geodetic latitude in radians.

    Returns
    -------
    float
        Gravity in m/s² (9.7803 at the equator, 9.8322 at the poles).
    """
    ge, k, e2 = 9.7803253359, 0.00193185265241, 0.00669437999013
    s2 = np.sin(latitude_rad) ** 2
    return float(ge * (1.0 + k * s2) / np.sqrt(1.0 - e2 * s2))


@dataclass(frozen=True)
class Site:
    """A place on the rotating Earth.

    Parameters
    ----------
    latitude_rad : float
        Geodetic latitude γ in radians, in [−π/2, π/2].
    earth_rate_rad_s : float
        Earth's rotation rate n in rad/s (default: sidereal rate).
    gravity_m_s2 : float, optional
        Local gravity g (plumb-line, includes the centrifugal part at the site).
        Defaults to WGS-84 normal gravity at the latitude.
    latitude_known : bool
        False when the latitude is a placeholder (a measured record from an unknown place): the
        estimator then does not compare its estimate with it (scene key ``site.latitude_known``).
    """

    latitude_rad: float
    earth_rate_rad_s: float = SIDEREAL_RATE_RAD_S
    gravity_m_s2: float = field(default=None)
    latitude_known: bool = True

    def __post_init__(self):
        lat = float(self.latitude_rad)
        if not np.isfinite(lat) or abs(lat) > np.pi / 2 + 1e-12:
            raise SceneError("site.latitude_deg", float(np.degrees(lat)) if np.isfinite(lat) else lat,
                             "must be a finite number in [-90, 90] degrees")
        n = float(self.earth_rate_rad_s)
        if not np.isfinite(n) or n < 0.0 or n > 1.0:
            raise SceneError("site.earth_rate_rad_s", self.earth_rate_rad_s,
                             "must be in [0, 1] rad/s (sidereal rate is 7.2921150e-5)")
        g = normal_gravity_m_s2(lat) if self.gravity_m_s2 is None else float(self.gravity_m_s2)
        if not np.isfinite(g) or g <= 0.0 or g > 1000.0:
            raise SceneError("site.gravity_m_s2", self.gravity_m_s2, "must be in (0, 1000] m/s^2")
        object.__setattr__(self, "latitude_rad", min(max(lat, -np.pi / 2), np.pi / 2))
        object.__setattr__(self, "earth_rate_rad_s", n)
        object.__setattr__(self, "gravity_m_s2", g)

    @classmethod
    def from_degrees(cls, latitude_deg, earth_rate_rad_s=SIDEREAL_RATE_RAD_S, gravity_m_s2=None) -> "Site":
        """Build a site from a latitude in degrees (the CLI/parameter edge)."""
        return cls(np.radians(latitude_deg), earth_rate_rad_s, gravity_m_s2)

    @property
    def latitude_deg(self) -> float:
        """Latitude in degrees (for display only)."""
        return float(np.degrees(self.latitude_rad))

    @property
    def k_vertical_rad_s(self) -> float:
        """k = n sin γ: vertical Earth-rate component (Quet sec. 2 §I), Foucault rate."""
        return self.earth_rate_rad_s * np.sin(self.latitude_rad)

    @property
    def k_horizontal_rad_s(self) -> float:
        """k' = n cos γ: northward horizontal Earth-rate component (Quet sec. 2 §I)."""
        return self.earth_rate_rad_s * np.cos(self.latitude_rad)

    def earth_rate_enu(self) -> np.ndarray:
        """Earth-rate vector in ENU, n (0, cos γ, sin γ) (REP-145)."""
        return self.earth_rate_rad_s * np.array([0.0, np.cos(self.latitude_rad), np.sin(self.latitude_rad)])

    def earth_axis_north_enu(self) -> np.ndarray:
        """Unit vector along the north part of Earth's axis, in ENU."""
        return np.array([0.0, np.cos(self.latitude_rad), np.sin(self.latitude_rad)])

    def earth_rate_quet(self) -> np.ndarray:
        """Earth-rate vector in Quet's pendulum axes (N, E, D): (n cos γ, 0, −n sin γ) (eq. 17)."""
        return enu_to_quet(self.earth_rate_enu())


def quet_to_enu(v) -> np.ndarray:
    """Convert a vector (or an array of row vectors) from Quet's N-E-D axes to ENU."""
    return np.asarray(v, dtype=float) @ QUET_NED_TO_ENU.T


def enu_to_quet(v) -> np.ndarray:
    """Convert a vector (or an array of row vectors) from ENU to Quet's N-E-D axes."""
    return np.asarray(v, dtype=float) @ QUET_NED_TO_ENU


def compass_azimuth_from_enu(east, north) -> np.ndarray | float:
    """Compass azimuth (0 at north, clockwise, radians in (−π, π]) of a horizontal ENU vector.

    This is Quet's ψ (sec. 2 §I). The ROS yaw of the same vector is π/2 − azimuth.
    """
    return np.arctan2(east, north)


def plane_frame(normal_enu, site) -> tuple:
    """Quet's axes for a directing plane (sec. 4 §1): ``oz`` the normal, ``ox`` toward the
    projection of the north part of Earth's axis on the plane, ``oy = oz × ox``.

    Parameters
    ----------
    normal_enu : array_like, shape (3,)
        Plane normal in ENU (need not be unit).
    site : Site

    Returns
    -------
    R : ndarray, shape (3, 3)
        Columns are ox, oy, oz in ENU.
    sin_omega : float
        sin ω, ω the angle between the normal and Earth's axis (Quet's directing-plane ω).
    """
    z = np.asarray(normal_enu, dtype=float)
    z = z / np.linalg.norm(z)
    axis = site.earth_axis_north_enu()
    proj = axis - np.dot(axis, z) * z
    sin_omega = float(np.linalg.norm(proj))
    if sin_omega < 1e-12:
        # Plane perpendicular to Earth's axis: no preferred direction (Quet item 4).
        # Pick ox along the ENU direction least aligned with z, for a well-defined frame.
        ref = np.eye(3)[int(np.argmin(np.abs(z)))]
        proj = ref - np.dot(ref, z) * z
        sin_omega = 0.0
    x = proj / np.linalg.norm(proj)
    y = np.cross(z, x)
    return np.column_stack([x, y, z]), sin_omega
