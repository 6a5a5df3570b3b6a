"""Heading out: what a ``sensor_msgs/Imu`` in the site's ENU frame carries, from a north estimate.

The gyrocompass finds the azimuth A of the instrument's reference direction (its scale zero, or
whatever direction the estimate is of): clockwise from true north, radians. Navigation users take
a heading as an IMU orientation; this module turns (A, σ_A) and the site into the fields of one
``sensor_msgs/Imu`` message, as plain tuples, so the ROS layer only copies them (no rclpy here).

Frames (REP-103, REP-145)
-------------------------
- World frame: the site's local ENU frame (x east, y north, z up; REP-103), aligned with *true*
  north (REP-145 speaks of magnetic north for magnetometer IMUs; a gyrocompass references the
  Earth's axis, so here the world frame's y is true north — say so where the topic is documented).
- Sensor (body) frame, REP-103 body convention: x forward = the instrument's reference direction,
  y left, z up. The instrument is levelled (its directing plane horizontal, Quet sec. 4 §1), so
  the body z is the ENU z and roll = pitch = 0 exactly in the model.
- Orientation: the rotation taking body vectors into ENU (REP-145 "orientation of the sensor frame
  w.r.t. the world frame"), a pure yaw ψ = π/2 − A about ENU z (REP-103: yaw 0 at east,
  counter-clockwise; an azimuth is 0 at north, clockwise). As a quaternion in the message's
  component order (geometry_msgs/Quaternion: x, y, z, w):
  ``q = (0, 0, sin(ψ/2), cos(ψ/2))``.
- Angular velocity (REP-145: the rate of the sensor frame w.r.t. an inertial frame, in the sensor
  frame): **not provided** by default (element 0 of its covariance −1, issue 37): the instrument
  measures no rate, and the Earth-rate vector rotated by the estimate would be fused by a
  navigation filter (robot_localization) as a gyro reading of variance 0. With ``rate_measured``
  (a caller that does measure it, or to state what a rate gyro at rest would read) it is the
  Earth-rate vector
  ``n (0, cos γ, sin γ)`` (ENU, REP-145; :meth:`Site.earth_rate_enu`) expressed in the body frame,
  ``ω_b = Rᵀ ω_enu = n (cos γ cos A, cos γ sin A, sin γ)``: pointing north (A = 0) the forward
  axis reads n cos γ, the left axis 0 and the up axis n sin γ; pointing east (A = π/2) the left
  axis (then north) reads n cos γ. |ω_b| = n for every A and γ.
- Linear acceleration: not provided (see "Covariances"). An instrument at rest and level would read
  +g on its up axis (REP-145: "if the body z axis points upwards, its z axis should indicate +g"),
  but the gyrocompass has no accelerometer, and (0, 0, g) would carry nothing of the estimate (it
  is the same for every A): publishing it would let a consumer fuse a premise as a measurement.
  The horizontal components of ω_b, by contrast, depend on A and carry the estimate.

Covariances (sensor_msgs/msg/Imu.msg comments, followed exactly)
----------------------------------------------------------------
Imu.msg: a known covariance is filled in (variances alone on the diagonal); "a covariance matrix
of all zeros will be interpreted as covariance unknown"; for a data element with no estimate,
"set element 0 of the associated covariance matrix to -1" (readers check element 0 for −1 and
disregard the element). The orientation covariance is "row major about x, y, z axes": element 0
roll, 4 pitch, 8 yaw (rad²). (REP-145, a Draft, says NaN in element 0 for an unreported field; the
message definition's −1 is what consumers test, and it is used here.)

- Orientation with A and σ_A: yaw variance σ_A² (element 8). Roll and pitch are set to 0 (the
  instrument is levelled) but are not estimated: −1 in element 0 would tell readers to discard the
  whole orientation, yaw included, so they get an explicit variance instead — ``level_sigma_rad²``
  when the caller knows the levelling accuracy (e.g. a theodolite's plate level), else
  :data:`UNMEASURED_TILT_VARIANCE_RAD2` = π²/3, the variance of an angle spread uniformly over a
  full turn: the least informative statement a finite variance can make. Off-diagonal terms 0
  (yaw's error is the estimate's, the tilts' the levelling's: independent).
- Orientation with A but no σ (an estimate that gives none): all zeros, "covariance unknown".
- Angular velocity not measured (the default): vector zero, element 0 = −1.
- No estimate (A is None): orientation not provided (element 0 = −1, quaternion the message's
  default identity); the angular velocity cannot be put in an unknown body frame either (−1).
- Angular velocity: first-order propagation of σ_A (and of optional σ_γ, σ_n) through ω_b(A, γ, n):
  ``Σ = σ_A² j_A j_Aᵀ + σ_γ² j_γ j_γᵀ + σ_n² j_n j_nᵀ`` with ``j_A = n cos γ (−sin A, cos A, 0)``,
  ``j_γ = n (−sin γ cos A, −sin γ sin A, cos γ)``, ``j_n = ω_b / n``. Valid for σ ≪ 1 rad (the
  neglected second-order term is ~σ²/2 of the value). Without σ_A: all zeros (unknown).
- Linear acceleration: not provided (element 0 = −1, vector zero).
"""

import math
from dataclasses import dataclass

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.quaternion import quat_from_rotvec
from gyro_instrument.core.site import Site

#: Rate (Hz of the node's clock: sim time) of the live heading of an instrument sampled at least this
#: fast; one sampled slower gets a heading with every sample (issue 37: a gyrocompass output is
#: continuous, a navigation stack fuses it at 10 Hz or more)
HEADING_RATE_HZ = 10.0

#: Imu.msg: element 0 of a covariance set to this means "no estimate of this data element".
NOT_PROVIDED = -1.0

#: Variance (rad²) given to roll and pitch when the levelling accuracy is not known: that of an
#: angle uniform over a full turn, (2π)²/12 = π²/3. Used because −1 in element 0 would void the
#: whole orientation (yaw included); see the module docstring.
UNMEASURED_TILT_VARIANCE_RAD2 = math.pi ** 2 / 3.0

_UNKNOWN = (0.0,) * 9
_NOT_PROVIDED_COV = (NOT_PROVIDED,) + (0.0,) * 8
_ENU_UP = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class ImuFields:
    """The fields of one ``sensor_msgs/Imu`` (header left to the ROS layer), as plain tuples.

    Attributes
    ----------
    orientation_xyzw : tuple of 4 float
        Body → ENU rotation as geometry_msgs/Quaternion components in the message's order
        (x, y, z, w).
    orientation_covariance : tuple of 9 float
        Row-major about x, y, z (roll, pitch, yaw), rad²; Imu.msg conventions (module docstring).
    angular_velocity_xyz_rad_s : tuple of 3 float
        Earth's rotation rate in the body frame (x forward, y left, z up), rad/s.
    angular_velocity_covariance : tuple of 9 float
        Row-major about x, y, z, (rad/s)².
    linear_acceleration_xyz_m_s2 : tuple of 3 float
        Always zero: not provided (covariance element 0 = −1).
    linear_acceleration_covariance : tuple of 9 float
        ``(-1, 0, …, 0)``: not provided.
    """

    orientation_xyzw: tuple
    orientation_covariance: tuple
    angular_velocity_xyz_rad_s: tuple
    angular_velocity_covariance: tuple
    linear_acceleration_xyz_m_s2: tuple = (0.0, 0.0, 0.0)
    linear_acceleration_covariance: tuple = _NOT_PROVIDED_COV


def yaw_from_azimuth(azimuth_rad: float) -> float:
    """ROS yaw ψ = π/2 − A (REP-103: 0 at east, counter-clockwise) of a compass azimuth A
    (0 at north, clockwise), wrapped to (−π, π], radians."""
    yaw = math.remainder(math.pi / 2 - float(azimuth_rad), 2 * math.pi)
    return math.pi if yaw == -math.pi else yaw


def orientation_xyzw(azimuth_rad: float) -> tuple:
    """Quaternion (x, y, z, w) of a levelled body whose forward axis has azimuth ``azimuth_rad``.

    A rotation by ψ = π/2 − A about ENU z (REP-103); roll = pitch = 0. The scalar-first quaternion
    of :func:`gyro_instrument.core.quaternion.quat_from_rotvec` reordered to the message's
    (x, y, z, w), with w ≥ 0.
    """
    w, x, y, z = quat_from_rotvec(_ENU_UP, np.array(yaw_from_azimuth(azimuth_rad)))
    return (float(x) + 0.0, float(y) + 0.0, float(z) + 0.0, float(w) + 0.0)  # + 0.0: no −0.0


def earth_rate_body(azimuth_rad: float, site: Site) -> np.ndarray:
    """Earth's rotation vector in the levelled body frame (x forward, y left, z up), rad/s.

    ``ω_b = Rz(ψ)ᵀ n (0, cos γ, sin γ) = n (cos γ cos A, cos γ sin A, sin γ)`` with ψ = π/2 − A
    (REP-145: a gyro at rest reads the Earth rate, in the sensor frame). Norm n.
    """
    a, lat, n = float(azimuth_rad), site.latitude_rad, site.earth_rate_rad_s
    return n * np.array([math.cos(lat) * math.cos(a), math.cos(lat) * math.sin(a), math.sin(lat)])


def earth_rate_body_covariance(azimuth_rad: float, sigma_rad: float, site: Site,
                               latitude_sigma_rad: float = 0.0, earth_rate_sigma_rad_s: float = 0.0) -> np.ndarray:
    """First-order covariance (3×3, (rad/s)²) of :func:`earth_rate_body` from independent errors
    σ_A (azimuth), σ_γ (latitude) and σ_n (Earth rate); equations in the module docstring."""
    a, lat, n = float(azimuth_rad), site.latitude_rad, site.earth_rate_rad_s
    j_a = n * math.cos(lat) * np.array([-math.sin(a), math.cos(a), 0.0])
    j_lat = n * np.array([-math.sin(lat) * math.cos(a), -math.sin(lat) * math.sin(a), math.cos(lat)])
    j_n = np.array([math.cos(lat) * math.cos(a), math.cos(lat) * math.sin(a), math.sin(lat)])
    return (sigma_rad ** 2 * np.outer(j_a, j_a) + latitude_sigma_rad ** 2 * np.outer(j_lat, j_lat)
            + earth_rate_sigma_rad_s ** 2 * np.outer(j_n, j_n))


def _checked(name: str, value, *, optional: bool, positive: bool | None) -> float | None:
    """``value`` as a finite float (> 0 if ``positive``, ≥ 0 if False, any sign if None), or None
    when ``optional``; SceneError naming the field otherwise."""
    if value is None and optional:
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    if not math.isfinite(v) or (positive is not None and (v <= 0.0 if positive else v < 0.0)):
        rng = {True: "a finite number > 0", False: "a finite number >= 0", None: "a finite number"}[positive]
        raise SceneError(name, value, rng + (" (or None: not known)" if optional else "") + ", radians / SI")
    return v


def imu_fields(azimuth_rad: float | None, sigma_rad: float | None, site: Site, *,
               level_sigma_rad: float | None = None, latitude_sigma_rad: float = 0.0,
               earth_rate_sigma_rad_s: float = 0.0, rate_measured: bool = False) -> ImuFields:
    """The ``sensor_msgs/Imu`` fields of a north estimate at a site (conventions: module docstring).

    Parameters
    ----------
    azimuth_rad : float or None
        Azimuth A of the instrument's reference direction, clockwise from true north, rad (any
        finite value; wrapped). None: no estimate yet (orientation and rate not provided).
    sigma_rad : float or None
        Standard error of A, rad, > 0. None: the estimate gives none (covariances all zero,
        "unknown", per Imu.msg).
    site : Site
        Latitude γ and Earth rate n.
    level_sigma_rad : float or None
        Levelling accuracy (roll and pitch σ, rad, ≥ 0); None: not known, variance
        :data:`UNMEASURED_TILT_VARIANCE_RAD2`.
    latitude_sigma_rad, earth_rate_sigma_rad_s : float
        Optional σ of γ (rad) and n (rad/s) propagated into the rate covariance (default 0: the
        site is given).
    rate_measured : bool
        False (default): the angular velocity is not provided (zero, covariance element 0 = −1):
        nothing here measures it. True: the Earth's rate in the body frame with its propagated
        covariance (module docstring).

    Returns
    -------
    ImuFields

    Raises
    ------
    SceneError
        A non-finite azimuth, a σ ≤ 0 or non-finite, a negative or non-finite levelling/site σ.
    """
    a = _checked("north.azimuth_rad", azimuth_rad, optional=True, positive=None)
    s = _checked("north.sigma_rad", sigma_rad, optional=True, positive=True)
    lev = _checked("imu.level_sigma_rad", level_sigma_rad, optional=True, positive=False)
    s_lat = _checked("site.latitude_sigma_rad", latitude_sigma_rad, optional=False, positive=False)
    s_n = _checked("site.earth_rate_sigma_rad_s", earth_rate_sigma_rad_s, optional=False, positive=False)
    if a is None:
        return ImuFields((0.0, 0.0, 0.0, 1.0), _NOT_PROVIDED_COV, (0.0, 0.0, 0.0), _NOT_PROVIDED_COV)
    rate = tuple(float(v) for v in earth_rate_body(a, site)) if rate_measured else (0.0, 0.0, 0.0)
    if s is None:
        return ImuFields(orientation_xyzw(a), _UNKNOWN, rate, _UNKNOWN if rate_measured else _NOT_PROVIDED_COV)
    tilt_var = UNMEASURED_TILT_VARIANCE_RAD2 if lev is None else lev ** 2
    orient_cov = (tilt_var, 0.0, 0.0, 0.0, tilt_var, 0.0, 0.0, 0.0, s ** 2)
    if not rate_measured:
        return ImuFields(orientation_xyzw(a), orient_cov, rate, _NOT_PROVIDED_COV)
    rate_cov = earth_rate_body_covariance(a, s, site, s_lat, s_n)
    return ImuFields(orientation_xyzw(a), orient_cov, rate, tuple(float(v) for v in rate_cov.ravel()))

