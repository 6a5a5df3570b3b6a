"""Each instrument's entry of the estimate, one record per measurement kind (:mod:`.kinds`): a swing about
a directing line (``gyro``: :class:`SwingEntry`, built in :func:`.swing.swing_estimate`), a swing plane's
precession (``pendulum``: :class:`PlaneEntry`, built in :func:`.kinds.plane_estimate`), and an instrument
the estimator does not measure or that gives only a block (:class:`UnusedEntry`). A plug-in kind's entry is
its own (:class:`PluginEntry`, open). Units: s, rad, rad/s.
"""

from dataclasses import dataclass

from gyro_instrument.estimators.compass_entries import CompassBlock, CompassNull
from gyro_instrument.estimators.north.block import NorthBlock, NullNorthBlock, RateNorthBlock
from gyro_instrument.estimators.record import ABSENT, Json, Record, doc

__all__ = ["Counting", "CountingNull", "EllipseScale", "PlaneEntry", "PlaneNull", "PluginEntry", "RestPoint",
           "SwingEntry", "SwingNull", "UnusedEntry"]


def _not_shipped() -> dict:
    """The schema of a plug-in's ``type``: none of the shipped instruments' (their classes say)."""
    from gyro_instrument.instruments import SHIPPED
    return {"type": "string", "not": {"enum": [cls.type_name for cls in SHIPPED]}}


_TYPE = "the instrument's type (its plug-in name)"
_NORTH = ("the instrument's own azimuth block (a horizontal gyroscope, a rate gyro); the top-level north is the "
          "one with the smallest σ")
_NorthAny = NorthBlock | RateNorthBlock | NullNorthBlock


@dataclass(frozen=True, kw_only=True)
class Counting(Record):
    """Quet's counting baseline: the swing duration from the counted swings."""

    swing_duration_s: float = doc("one swing (half a period) from the counted swings, s")
    swing_duration_sigma_s: float = doc("its standard error, s")
    swings: int = doc("swings counted")
    small_amplitude_swing_duration_s: float = doc("the counted duration reduced to small amplitude, s")


@dataclass(frozen=True, kw_only=True)
class CountingNull(Record):
    """The swings could not be counted."""

    swing_duration_s: None = doc("null")
    reason: str = doc("why")


@dataclass(frozen=True, kw_only=True)
class SwingEntry(Record):
    """A gyroscope's swing about its directing line (kind ``gyro``): Quet's swing duration T (one swing =
    half a period) fitted, reduced to small amplitude, and the counting baseline."""

    type: str = doc(_TYPE)
    configuration: str = doc("the directing line's configuration (horizontal, meridian, locked, ...)")
    mean_spin_rad_s: float = doc("mean rotor spin over the record, rad/s")
    swing_duration_s: float = doc("Quet's T, one swing = half a period, s")
    swing_duration_sigma_s: float = doc("its standard error, s")
    small_amplitude_swing_duration_s: float = doc("T / (2/π)K(sin(a/2)): the small-amplitude swing, s")
    small_amplitude_swing_duration_sigma_s: float = doc("its standard error, s")
    crlb_swing_duration_s: float = doc("Cramér–Rao bound of T, s")
    amplitude_rad: float = doc("swing amplitude (rms over the record when damped), rad")
    finite_amplitude_factor: float = doc("(2/π)K(sin(a/2)) applied (1 without the correction)")
    period_s: float = doc("2 T, s")
    noise_rad: float = doc("residual rms of the fit, rad")
    fit_method: str = doc("which fit measured the swing")
    samples: int = doc("samples fitted")
    notes: list[str] = doc("what the fit noticed (spin decay warp, damping fitted, ...)")
    counting: Counting | CountingNull = doc("Quet's method: the swings counted")
    second_order_correction: float = doc("the O(n²) correction of the exact equation applied to y (dimensionless)",
                                         ABSENT)
    extra: dict[str, Json] = doc("another observation's extra keys", ABSENT, inline=True)
    north: _NorthAny = doc(_NORTH, ABSENT)


@dataclass(frozen=True, kw_only=True)
class SwingNull(Record):
    """A gyroscope whose swing was not measured: ``swing_duration_s`` null with the reason."""

    type: str = doc(_TYPE)
    configuration: str = doc("the directing line's configuration")
    mean_spin_rad_s: float = doc("mean rotor spin over the record, rad/s", ABSENT)
    swing_duration_s: None = doc("null")
    reason: str = doc("why no swing was measured")
    north: _NorthAny = doc(_NORTH, ABSENT)


@dataclass(frozen=True, kw_only=True)
class RestPoint(Record):
    """The swing's centre fitted, not assumed (the deflections are taken about it)."""

    east_rad: float = doc("east deflection of the rest point at at_time_s, rad")
    drift_east_rad_s: float = doc("its drift, rad/s")
    north_rad: float = doc("north deflection of the rest point at at_time_s, rad")
    drift_north_rad_s: float = doc("its drift, rad/s")
    at_time_s: float = doc("the time the rest point is given at, s")


@dataclass(frozen=True, kw_only=True)
class EllipseScale(Record):
    """How the ellipse (Airy) correction hangs on the position scale: (3/8) a b/l² times the swing
    frequency, so a scale s times the assumed one multiplies it by s² while the measured turn is unchanged."""

    exponent: int = doc("2: the correction scales as the square of the position scale")
    share_of_measured_rate: float | None = doc("the correction over the measured rate (dimensionless)")
    k_without_correction_rad_s: float = doc("the measured plane rate, rad/s")
    k_at_half_scale_rad_s: float = doc("k were the scale half the assumed one, rad/s")
    k_at_double_scale_rad_s: float = doc("k were the scale double, rad/s")
    matters: bool = doc("halving the scale would move k by more than its σ")


@dataclass(frozen=True, kw_only=True)
class PlaneEntry(Record):
    """A pendulum's swing plane (kind ``pendulum``): the Foucault rate k = n sin γ, the exact elliptic-integral
    ellipse correction inverted."""

    type: str = doc(_TYPE)
    foucault_rate_rad_s: float = doc("the Foucault rate k, rad/s")
    foucault_rate_sigma_rad_s: float = doc("its standard error (sigma_basis says how), rad/s")
    crlb_foucault_rate_rad_s: float = doc("Cramér–Rao bound from the scene's sensor noise √(σ² + q²/12), "
                                          "dropouts as fewer samples; 0 without noise, rad/s")
    measured_plane_rate_rad_s: float = doc("the swing plane's turn as measured, before the ellipse correction, rad/s")
    measured_plane_rate_sigma_rad_s: float = doc("its standard error, rad/s")
    sigma_basis: str = doc("white (σ from the record's noise through the Cramér–Rao bound) or record scatter (the "
                           "residuals are not white: the largest of their scatter, Newey–West HAC and blocking)",
                           schema={"enum": ["white", "record scatter"]})
    sigma_basis_detail: str = doc("the figures behind sigma_basis")
    ellipse_correction_rad_s: float = doc("the ellipse (Airy) correction subtracted, rad/s")
    amplitude_rad: float = doc("the swing's major semi-axis, rad")
    minor_axis_rad: float = doc("its minor semi-axis (signed by the sense of the ellipse), rad")
    period_s: float = doc("the swing period, s")
    period_sigma_s: float = doc("its standard error, s")
    rest_point: RestPoint = doc("the swing's centre fitted and its drift")
    windows: int = doc("swing periods (windows) fitted")
    notes: list[str] = doc("what the fit noticed")
    ellipse_scale: EllipseScale = doc("how the ellipse correction hangs on the position scale")


@dataclass(frozen=True, kw_only=True)
class PlaneNull(Record):
    """A pendulum whose swing plane was not measured."""

    type: str = doc(_TYPE)
    foucault_rate_rad_s: None = doc("null")
    reason: str = doc("why")


@dataclass(frozen=True, kw_only=True)
class UnusedEntry(Record):
    """An instrument the estimator does not measure for the Earth rate (a free gyroscope, Puiseux's body), or
    one that gives only a block (a rate gyro: its ``north``; a ship's gyrocompass: its ``compass``)."""

    type: str = doc(_TYPE)
    reason: str = doc("not used by the estimator (...)", ABSENT)
    north: _NorthAny = doc(_NORTH, ABSENT)
    compass: CompassBlock | CompassNull = doc("a ship's gyrocompass's block (settle-point error, period and damping, "
                                              "heading error along the track)", ABSENT)
    extra: dict[str, Json] = doc("a plug-in kind's block under its BLOCK key", ABSENT, inline=True)


@dataclass(frozen=True, kw_only=True)
class PluginEntry(Record):
    """Another measurement kind's entry as that kind gives it (a plug-in's, docs/extending.md): any keys,
    ``type`` not a shipped instrument's."""

    OPEN = True
    type: str = doc("the plug-in instrument's type (not a shipped one)", schema=_not_shipped)
