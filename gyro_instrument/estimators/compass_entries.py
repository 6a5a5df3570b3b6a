"""The ``compass`` block of a ship's gyrocompass in the estimate (issue 39 item 6; the kind
:class:`.compass_kind.CompassKind`, the numbers :mod:`.compass_fit`). Angles in degrees (the edge), times
in s; a quantity the record cannot give is ``null`` with its reason."""

from dataclasses import dataclass

from gyro_instrument.estimators.record import ABSENT, Record, doc

__all__ = ["CompassBlock", "CompassNull", "SettlingCurve", "SettlingCurveNull", "TrackError"]


@dataclass(frozen=True, kw_only=True)
class SettlingCurve(Record):
    """The settling curve e(t) = e_s + A exp(−λ τ) cos(ω τ + φ) [+ B exp(−μ τ)] fitted by nonlinear least
    squares (σ from its covariance, s² (JᵀJ)⁻¹; estimators/compass_fit.py), beside the linear theory's."""

    model: str = doc("damped sinusoid, or damped sinusoid + exponential mode (damping in azimuth's third order)")
    period_s: float = doc("the damped period T_d = 2π/ω, s")
    period_sigma_s: float = doc("its standard error, s")
    undamped_period_s: float = doc("2π/√(λ² + ω²), s")
    undamped_period_sigma_s: float = doc("its standard error, s")
    damping_ratio: float = doc("ζ = λ/√(λ² + ω²) (dimensionless)")
    damping_ratio_sigma: float = doc("its standard error")
    log_decrement: float = doc("Λ = λ T_d per period (dimensionless)")
    log_decrement_sigma: float = doc("its standard error")
    swing_ratio: float = doc("ratio of successive swings to either side of the settle point, exp(λ T_d/2)")
    swing_ratio_sigma: float = doc("its standard error")
    settle_point_error_deg: float = doc("the curve's asymptote e_s: the heading error it settles to, deg")
    settle_point_error_sigma_deg: float = doc("its standard error, deg")
    amplitude_deg: float = doc("|A|: the swing at the record's start, deg")
    amplitude_sigma_deg: float = doc("its standard error, deg")
    residual_rms_deg: float = doc("rms of the fit's residuals, deg")
    sigma_basis: str = doc("sensor noise (the scene's σ) or residual scatter (the residuals exceed it: σ widened)",
                           schema={"enum": ["sensor noise", "residual scatter"]})
    samples: int = doc("samples fitted")
    theory_undamped_period_s: float | None = doc("the linear theory's undamped period at the record's mean "
                                                 "latitude on a pier, s (theory.py); null without Earth rate")
    theory_damping_ratio: float | None = doc("the linear theory's ζ for damping in tilt (theory.py); null for "
                                             "damping in azimuth or none (no closed form here)")


@dataclass(frozen=True, kw_only=True)
class SettlingCurveNull(Record):
    """No settling curve in the record: period and damping not determined."""

    period_s: None = doc("null")
    damping_ratio: None = doc("null")
    reason: str = doc("why: the record is shorter than one swing, starts settled, or the fit failed")


@dataclass(frozen=True, kw_only=True)
class TrackError(Record):
    """The heading error along the track after settling, beside what the closed forms predict for the ship's
    speed, course and latitude and the compass's corrections (theory.py)."""

    rms_deg: float = doc("rms of the heading error after settling (reading noise included), deg")
    max_abs_deg: float = doc("largest |heading error| after settling (reading noise included), deg")
    predicted_mean_deg: float = doc("mean of the error the closed forms predict over the same readings: the "
                                    "compass's speed and latitude corrections less the settled offset of the "
                                    "equations (speed error atan2(−V_N, RΩcos φ + V_E), damping error), deg")
    measured_minus_predicted_deg: float = doc("the settle-point error less predicted_mean_deg, deg")
    measured_minus_predicted_sigma_deg: float = doc("its standard error, deg: the settle point's from the "
                                                    "noise, or the settled readings' 20-min block means' scatter "
                                                    "/ √B when the check 'stationary' finds them wandering, "
                                                    "their own scatter when they span under three blocks")


@dataclass(frozen=True, kw_only=True)
class CompassBlock(Record):
    """A ship's gyrocompass read against the ship's course (its ``compass`` block): the settle-point error
    (ISO 22090-1 §3.10–3.12), the settling curve's period and damping, the heading error along the track."""

    settled_at_s: float | None = doc("when the compass settled (ISO 22090-1 §3.10: three readings 30 min apart "
                                     "within 0.7°), s from the record's start; null: not settled")
    settle_point_error_deg: float | None = doc("mean heading error (reading − true course) of every reading after "
                                               "settling, deg; null when not settled")
    settle_point_error_sigma_deg: float | None = doc("its standard error from the noise, σ_n/√N, deg (of this "
                                                     "record's mean: a compass still wandering is flagged by the "
                                                     "check 'stationary')")
    settle_point_samples: int = doc("readings averaged")
    iso_settle_point_error_deg: float | None = doc("ISO 22090-1 §3.11–3.12: the mean of ten readings 20 min apart "
                                                   "after settling, deg; null when the record is too short")
    iso_settle_point_rms_deg: float | None = doc("§3.13: rms of those ten readings about their mean, deg")
    reading_noise_deg: float = doc("σ_n of one reading: the larger of the sensor's and the settled readings' "
                                   "scatter (second differences), deg")
    reason: str = doc("why settle_point_error_deg is null", ABSENT)
    settling_curve: SettlingCurve | SettlingCurveNull = doc("the settling curve fitted: period and damping")
    track: TrackError = doc("the heading error along the track after settling", ABSENT)
    notes: list[str] = doc("what the estimator assumed (the track's source)")


@dataclass(frozen=True, kw_only=True)
class CompassNull(Record):
    """A compass the record cannot measure (no readings, or no Earth rate: it seeks no north)."""

    settle_point_error_deg: None = doc("null")
    reason: str = doc("why")
