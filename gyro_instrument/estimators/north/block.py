"""The ``north`` block's typed records: a horizontal gyroscope's (:class:`NorthBlock`, built in
:func:`.estimate.north_entry`), a rate gyro's (:class:`RateNorthBlock`, :func:`.rate_gyro.north_block`), the
block when no azimuth can be had (:class:`NullNorthBlock`, :func:`.estimate.null_block`) and a field
book's (:class:`FieldBookBlock`, :func:`.field_book_report.field_book_block`).

Azimuths are clockwise from true north, in degrees (the edge); σ in arcsec; rates in rad/s.
"""

from dataclasses import dataclass

from gyro_instrument.estimators import estimate_docs as D
from gyro_instrument.estimators.record import ABSENT, Json, Record, doc

__all__ = ["FieldBookBlock", "MethodEntry", "MissedPoint", "Outlier", "NorthBlock", "NullNorthBlock", "PreOrientation", "RateBias",
           "RateFisher", "RateMethodEntry", "RateNoiseModel", "RateNorthBlock", "RateScaleFactor",
           "RateScaleFactorAssumed", "RateSign", "TapeEntry"]

_MOUNT = ("the azimuth, clockwise from true north, of the scale's zero (a rate gyro: of the turntable's reference, "
          "index 0), deg")
_SIGMA = "its σ, arcsec"


@dataclass(frozen=True, kw_only=True)
class MethodEntry(Record):
    """One north method's result (schuler_mean, lavrov, transit, fit), tape-corrected."""

    mount_azimuth_deg: float = doc(_MOUNT)
    sigma_arcsec: float | None = doc(_SIGMA + " (null when the method gives none)")
    sigma_source: str = doc("where σ comes from")
    n_used: int = doc("reversal points, transits or samples used")
    needs: str = doc("what the method must observe")
    bias: str = doc("its model's biases, in words")
    notes: list[str] = doc("what the method noticed")
    bias_arcsec: float = doc("its bias in this set-up, in mount azimuth (the method on the fitted model's own "
                             "noise-free records, less the model's answer; 0 for the fit), arcsec", ABSENT)
    bias_flagged: bool = doc("true when |bias| > σ/4: not to be used as north here", ABSENT)
    period_s: float = doc("the swing period the method gives, s", ABSENT)
    crlb_arcsec: float = doc("the Cramér–Rao bound (the fit), arcsec", ABSENT)


@dataclass(frozen=True, kw_only=True)
class TapeEntry(Record):
    """The torsion tape's calibration: the joint fit's k_B/K, the tape zero and its drift, and the surveyors'
    calibration from undamped periods."""

    instrument: str = doc("the rotor-off swing's instrument")
    ratio_db_dk: float = doc("the fit's k_B/K (dimensionless)")
    ratio_sigma: float = doc("its σ (dimensionless)")
    zero_reading_deg: float = doc("the tape zero at mid-record, counter-clockwise scale reading, deg")
    zero_sigma_arcsec: float | None = doc("its σ, arcsec")
    zero_rate_arcsec_h: float = doc("its fitted drift, arcsec/h")
    surveyor_ratio: float | None = doc("T_on²/(T_off² − T_on²) from undamped periods (dimensionless)")
    surveyor_ratio_sigma: float | None = doc("its σ (dimensionless)")
    source: str = doc("how the calibration was made")


@dataclass(frozen=True, kw_only=True)
class PreOrientation(Record):
    """How far the swing's centre sits from north and what that costs each method."""

    centre_from_north_deg: float = doc("the swing's equilibrium on the scale, clockwise from north, deg")
    cost_arcsec: dict[str, float | None] = doc("each method's bias_arcsec, arcsec")
    tape_zero_from_north_deg: float = doc("the tape zero from north, deg", ABSENT)
    linear_tape_law_error_arcsec: float | None = doc("what N = c + x(c − Z) would err by, arcsec", ABSENT)


_NOTES = "the block's conventions in words"


@dataclass(frozen=True, kw_only=True)
class NorthBlock(Record):
    """A horizontal gyroscope's north (issue 24): the exact fit of the swing equation to the rotor-on and
    rotor-off records (estimators/north/exact.py), σ at the Cramér–Rao bound of the whole problem; the
    reversal-point methods beside it with their biases."""

    DOC = D.NORTH

    instrument: str = doc("the instrument whose block this is")
    mount_azimuth_deg: float = doc(_MOUNT)
    sigma_arcsec: float | None = doc(_SIGMA + ": the Cramér–Rao bound of the whole problem (tape calibration "
                                     "included) at the estimate")
    crlb_arcsec: float | None = doc("that bound, arcsec")
    method: str = doc("fit: the headline is always the exact fit", schema={"enum": ["fit"]})
    tape: TapeEntry | None = doc("the tape's calibration (null without tape_torsion)")
    methods: dict[str, MethodEntry] = doc("schuler_mean, lavrov, transit, fit")
    refused: dict[str, str] = doc("method -> why it was refused")
    pre_orientation: PreOrientation = doc("the swing's centre from north and its cost per method")
    notes: list[str] = doc(_NOTES)


@dataclass(frozen=True, kw_only=True)
class NullNorthBlock(Record):
    """No azimuth can be had (no directing torque, a record the methods cannot reduce, a fit refused): every
    number null, the whole circle, the reason."""

    instrument: str = doc("the instrument whose block this is")
    mount_azimuth_deg: None = doc("null")
    sigma_arcsec: None = doc("null")
    crlb_arcsec: None = doc("null")
    interval_deg: list[float] = doc("[0, 360]: the whole circle, deg", schema={
        "type": "array", "prefixItems": [{"const": 0.0}, {"const": 360.0}], "minItems": 2, "maxItems": 2})
    method: None = doc("null")
    tape: None = doc("null")
    methods: dict[str, Json] = doc("empty", schema={"type": "object", "maxProperties": 0})
    refused: dict[str, str] = doc("method -> why it was refused")
    reason: str = doc("why no azimuth")


@dataclass(frozen=True, kw_only=True)
class RateMethodEntry(Record):
    """One rate-gyro north method (gls; closed_form with four positions at 90° steps)."""

    mount_azimuth_deg: float = doc(_MOUNT)
    sigma_arcsec: float | None = doc(_SIGMA + ", propagated through the sensor's noise covariance")
    sigma_source: str = doc("where σ comes from")
    n_used: int = doc("samples used")
    needs: str = doc("what the method must observe")
    bias: str = doc("its model's biases, in words")
    bias_arcsec: float = doc("0: the linear model is exact, arcsec")
    bias_flagged: bool = doc("false")
    notes: list[str] = doc("what the method noticed")
    crlb_arcsec: float = doc("the Cramér–Rao bound (gls), arcsec", ABSENT)
    north_index_deg: float = doc("closed form: the turntable index that points north, deg", ABSENT)
    position_means_rad_s: list[float] = doc("closed form: the four positions' mean rates, rad/s", ABSENT)


@dataclass(frozen=True, kw_only=True)
class RateSign(Record):
    """How the mirror image of a two-position north was ruled out (or not)."""

    resolved_by: str | None = doc("data (three or more headings), prior (two positions, the mirror image outside "
                                  "the scene's prior), or null (the prior does not exclude it)",
                                  schema={"enum": ["data", "prior", None]})
    candidates_deg: list[float] = doc("the two candidates, deg", ABSENT)
    detail: str = doc("in words")


@dataclass(frozen=True, kw_only=True)
class RateBias(Record):
    """The gyro's bias: the turn-on bias plus the bias instability's mean over the record."""

    rate_rad_s: float = doc("bias, rad/s")
    sigma_rad_s: float = doc("its σ, rad/s")
    deg_h: float = doc("bias, deg/h")
    sigma_deg_h: float = doc("its σ, deg/h")
    meaning: str = doc("what it is")


@dataclass(frozen=True, kw_only=True)
class RateNoiseModel(Record):
    """The sensor's noise model the GLS uses (datasheet figures) and the bins fitted."""

    sigma_white_rad_s: float = doc("white angle random walk per sample, rad/s")
    sigma_gm_rad_s: float = doc("Gauss–Markov bias instability, rad/s")
    correlation_time_s: float = doc("its correlation time τ_c, s")
    dt_s: float = doc("sample interval, s")
    bins: int = doc("bin means fitted")
    samples: int = doc("samples in them")


@dataclass(frozen=True, kw_only=True)
class RateFisher(Record):
    """The Fisher information of the bin means."""

    matrix: list[list[float]] = doc("J = Hᵀ C⁻¹ H (units of the parameters: rad/s)")
    parameters: list[str] = doc("a, c, b (three or more headings) or d, b (two positions)")
    formula: str = doc("how J is formed")


@dataclass(frozen=True, kw_only=True)
class RateScaleFactor(Record):
    """The scale factor measured (three or more headings)."""

    amplitude_rad_s: float = doc("A, the fitted amplitude, rad/s")
    amplitude_sigma_rad_s: float = doc("its σ, rad/s")
    ppm: float = doc("A/(n cos γ) − 1 at the stated latitude, ppm")
    sigma_ppm: float = doc("its σ, ppm")
    meaning: str = doc("what it is")


@dataclass(frozen=True, kw_only=True)
class RateScaleFactorAssumed(Record):
    """Two positions: the scale factor assumed 0 and the bias a scale factor error makes."""

    assumed_ppm: float = doc("0, ppm")
    mount_shift_arcsec_per_100ppm: float | None = doc("the mount's shift per 100 ppm of scale factor, arcsec")


@dataclass(frozen=True, kw_only=True)
class RateNorthBlock(Record):
    """A rate gyro's north (issue 35): generalised least squares of r = A cos(M + φ) + b with the sensor's own
    noise covariance (white ARW + Gauss–Markov bias instability, exact for the bin means); σ = the
    Cramér–Rao bound."""

    DOC = D.RATE_NORTH

    instrument: str = doc("the instrument whose block this is")
    mount_azimuth_deg: float | None = doc(_MOUNT + "; null when two positions' mirror image is not excluded")
    sigma_arcsec: float | None = doc(_SIGMA + " = crlb_arcsec")
    crlb_arcsec: float | None = doc("the Cramér–Rao bound of the bin means, arcsec")
    method: str = doc("gls", schema={"enum": ["gls"]})
    tape: None = doc("null")
    methods: dict[str, RateMethodEntry] = doc("gls and, for four positions at 90° steps, closed_form")
    refused: dict[str, str] = doc("empty")
    pre_orientation: None = doc("null")
    sign: RateSign = doc("how the mirror image was resolved")
    bias: RateBias = doc("the gyro's bias")
    noise_model: RateNoiseModel = doc("the sensor's noise model")
    fisher: RateFisher = doc("the Fisher information")
    residual_chi2_per_dof: float | None = doc("χ²/dof of the fit")
    positions: int | None = doc("held headings (null for a carousel)")
    scale_factor: RateScaleFactor | RateScaleFactorAssumed = doc("measured (≥ 3 headings) or assumed (two)")
    interval_deg: None = doc("null: two positions, north ambiguous", ABSENT)
    reason: str = doc("why mount_azimuth_deg is null", ABSENT)
    undetermined: list[str] = doc("what the data cannot give")
    notes: list[str] = doc(_NOTES)


@dataclass(frozen=True, kw_only=True)
class MissedPoint(Record):
    """A turning point the book skipped (its number absent): left out in its place."""

    turning_point: int = doc("its number")
    line: int | None = doc("the book's line (null when the row is absent)")
    time_s: float | None = doc("its time when the row has one, s")


@dataclass(frozen=True, kw_only=True)
class Outlier(Record):
    """A reading far from its same-side neighbours' mean: named, not dropped."""

    column: str = doc("the book's column")
    turning_point: int = doc("its number")
    line: int = doc("the book's line")
    reading: str = doc("the reading as written")
    sigmas: float = doc("its residual in units of the neighbours' robust scatter")
    threshold_sigmas: float = doc("the book-wide threshold (false-alarm probability 0.002)")
    residual_arcsec: float = doc("its residual, arcsec")


_DMS = "the same in d°m′s″, to 0.1″"
_GON = "the same in gon, in [0, 400)"


@dataclass(frozen=True, kw_only=True)
class FieldBookBlock(Record):
    """The north of a field book: the Schuler mean (the headline) and Lavrov's, each with the angle in deg,
    d°m′s″ and gon, the circle reading of north, the reduction, the tape, the turning points read, missed and
    outlying (msg_docs/estimate.md "Field books" below)."""

    instrument: None = doc("null: a book names no instrument")
    field_book: str = doc("the book's file")
    scene: str | None = doc("the scene lending latitude and tape, null without --scene")
    scene_instrument: str | None = doc("the scene's first horizontal gyroscope, null without a scene")
    latitude_deg: float | None = doc("the scene's latitude, deg; null without a scene")
    mount_azimuth_deg: float = doc(_MOUNT)
    mount_azimuth_dms: str = doc(_DMS)
    mount_azimuth_gon: float = doc(_GON)
    north_reading_deg: float = doc("the circle reading of north (= −mount, in [0, 360)), deg")
    north_reading_dms: str = doc(_DMS)
    north_reading_gon: float = doc(_GON)
    sigma_arcsec: float | None = doc(_SIGMA + ", from the scatter of the turning points (null with 3)")
    crlb_arcsec: None = doc("null: no record")
    method: str = doc("schuler_mean: the headline", schema={"enum": ["schuler_mean"]})
    reduction: str = doc("raw: ... when neither the book nor the scene has a tape, else tape removed (...)")
    tape: dict[str, Json] | None = doc(
        "null for the raw reduction; else source, ratio_db_dk, ratio_sigma, zero_reading_deg / _dms / _gon (the tape "
        "zero's circle reading), zero_sigma_arcsec, and from the book's times the half periods, the undamped ones and "
        "each swing's damping ratio, each method's tape zero zero_reading_by_method_deg")
    methods: dict[str, dict[str, Json]] = doc(
        "schuler_mean and lavrov, each a method entry with the same angle fields (mount_azimuth_dms, _gon, "
        "north_reading_deg, _dms, _gon); schuler_mean.triple_means: the means (a_k + 2a_(k+1) + a_(k+2))/4 a "
        "surveyor prints beside the readings, with their turning points")
    turning_points: int = doc("the number read")
    missed: list[MissedPoint] = doc("turning points the book skipped")
    outliers: list[Outlier] = doc("readings named as outlying (not dropped)")
    refused: dict[str, str] = doc("method -> why it was refused")
    notes: list[str] = doc("what the reduction noticed")
