"""The estimate's typed tree: the top-level object, the combined latitude, Quet's classical methods, the
checks and the site (msg_docs/estimate.md is generated from these declarations through
``estimate.schema.json``: ``python tools/gen_estimate_docs.py``).

Each instrument's entry is its measurement kind's (:mod:`.entries`: a swing, a swing plane, an
instrument the estimator does not use), the ``north`` block the azimuth kinds' (:mod:`.north.block`).
Angles are in degrees here only (the edge), rates in rad/s, times in s; a quantity that cannot be
estimated is ``null`` with a ``reason``, never NaN.
"""

from dataclasses import dataclass

from gyro_instrument.estimators import estimate_docs as D
from gyro_instrument.estimators.entries import PlaneEntry, PlaneNull, PluginEntry, SwingEntry, SwingNull, UnusedEntry
from gyro_instrument.estimators.north.block import FieldBookBlock, NorthBlock, NullNorthBlock, RateNorthBlock
from gyro_instrument.estimators.record import ABSENT, Json, Record, doc

__all__ = ["Check", "ClassicMethods", "Combined", "Crlb", "DamagedStretch", "Disagreement", "Estimate", "FieldBookEstimate",
           "Foucault", "Item8", "Item9", "Item9Counting", "Item9Null", "NoRateMeasurement", "OtherLatitude", "Site",
           "Truth", "Unresolved"]

#: JSON Schema of the one-line check statuses (:mod:`.adequacy`)
CHECK_STATUSES = ["passed", "flagged", "failed", "no_signal", "not_applicable", "refused"]
#: the hemisphere values (:data:`.latitude.HEMISPHERE_UNDETERMINED` the third)
HEMISPHERES = ["north", "south", "not determined by these instruments"]


@dataclass(frozen=True, kw_only=True)
class Truth(Record):
    """The simulated site (the scene's nominal values for measured data)."""

    latitude_deg: float = doc("latitude of the site, deg")
    earth_rate_rad_s: float = doc("Earth rate n of the site, rad/s")


@dataclass(frozen=True, kw_only=True)
class Crlb(Record):
    """Cramér–Rao bounds for the same data and the same mode (``null`` where σ is)."""

    latitude_deg: float | None = doc("bound on the latitude's σ, deg")
    earth_rate_rad_s: float | None = doc("bound on the Earth rate's σ, rad/s")


@dataclass(frozen=True, kw_only=True)
class OtherLatitude(Record):
    """Another local fit not excluded at 3 σ."""

    latitude_deg: float = doc("the other mode's latitude, deg")
    delta_chi2: float = doc("how much worse it fits (Δχ² against the reported mode)")


_EARTH_RATE = "combined Earth rate n, rad/s; when n was taken as known, the known value"
_EARTH_RATE_SIGMA = "standard error of n, rad/s; null when n was taken as known"
_KNOWN = ("true when n was not estimated but held at the scene's site.earth_rate_rad_s (IERS conventional "
          "7.292115e-5 rad/s by default) and the latitude fitted alone")
_BASIS = "why n was held known or estimated; earth_rate_known is " + D.EARTH_RATE_KNOWN
_HEMI_BASIS = D.HEMISPHERE
_METHOD = "which measurements were combined and which instrument carries the latitude"


@dataclass(frozen=True, kw_only=True)
class Combined(Record):
    """The combined latitude and Earth rate (profile likelihood, Δχ² = 1) of the one mode reported."""

    earth_rate_rad_s: float | None = doc(_EARTH_RATE)
    earth_rate_sigma_rad_s: float | None = doc(_EARTH_RATE_SIGMA)
    earth_rate_known: bool = doc(_KNOWN)
    earth_rate_basis: str = doc(_BASIS)
    hemisphere: str = doc("north, south or not determined by these instruments", schema={"enum": HEMISPHERES})
    hemisphere_basis: str = doc(_HEMI_BASIS)
    latitude_deg: float = doc("combined latitude, deg: " + D.LATITUDE)
    latitude_sigma_deg: float | None = doc("1-σ half-interval of the latitude (Δχ² = 1), deg; null when the "
                                           "likelihood is not locally Gaussian (latitude_sigma_reason says why)")
    latitude_interval_deg: list[float] = doc("the Δχ² = 1 interval [low, high] of the mode, deg (asymmetric near "
                                             "the poles)", schema={"type": "array", "items": {"type": "number"},
                                                                   "minItems": 2, "maxItems": 2})
    latitude_interval_3sigma_deg: list[float] = doc("the Δχ² = 9 interval [low, high], deg", schema={
        "type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2})
    latitude_is_absolute: bool = doc("true when latitude_deg is |γ|: no instrument decides the hemisphere and "
                                     "none was assumed")
    crlb: Crlb = doc("Cramér–Rao bounds of the same mode")
    carried_by: dict[str, float] = doc("each instrument's share of the Fisher information on the latitude "
                                       "(dimensionless, sums to 1)")
    chi2: float = doc("goodness of fit of the combination (χ²)")
    dof: int = doc("degrees of freedom of the combination")
    latitude_sigma_reason: str = doc("why latitude_sigma_deg is null", ABSENT)
    other_latitudes_deg: list[OtherLatitude] = doc("other local fits not excluded at 3 σ (Δχ² < 9)", ABSENT)
    left_out_of_latitude: dict[str, str] = doc("gyroscopes left out near a flat point of their directing "
                                               "factor: name -> the reason", ABSENT)
    method: str = doc(_METHOD)


@dataclass(frozen=True, kw_only=True)
class Unresolved(Record):
    """Measurements that do not give the latitude (one that gives only n·s(γ), or several with the same s(γ)):
    latitude ``null`` with the reason, n their weighted mean where it is determined."""

    earth_rate_rad_s: float | None = doc(_EARTH_RATE)
    earth_rate_sigma_rad_s: float | None = doc(_EARTH_RATE_SIGMA)
    earth_rate_known: bool = doc(_KNOWN)
    earth_rate_basis: str = doc(_BASIS)
    hemisphere: str = doc("north, south or not determined by these instruments", schema={"enum": HEMISPHERES})
    hemisphere_basis: str = doc(_HEMI_BASIS)
    latitude_deg: None = doc("null: the latitude is not determined")
    latitude_sigma_deg: None = doc("null")
    reason: str = doc(D.REASON)
    crlb: Crlb = doc("Cramér–Rao bounds (the latitude's null)")
    method: str | None = doc(_METHOD + "; null when n is not determined either")


@dataclass(frozen=True, kw_only=True)
class NoRateMeasurement(Record):
    """No instrument gives an Earth-rate measurement: every combined value ``null`` with the reason."""

    latitude_deg: None = doc("null")
    latitude_sigma_deg: None = doc("null")
    earth_rate_rad_s: None = doc("null")
    earth_rate_sigma_rad_s: None = doc("null")
    crlb: Crlb = doc("null bounds")
    hemisphere: str = doc("not determined by these instruments", schema={"enum": HEMISPHERES})
    method: None = doc("null")
    reason: str = doc("why: no Earth-rate measurement")


@dataclass(frozen=True, kw_only=True)
class Item9(Record):
    """Quet item 9: cos γ = (T_m/T_h)² ρ_m/ρ_h (finite-amplitude, spin and ring-inertia corrections)."""

    DOC = D.ITEM9

    cos_latitude: float = doc("cos γ from the horizontal and meridian swings (dimensionless)")
    cos_latitude_sigma: float = doc("its standard error (dimensionless)")
    hemisphere: str = doc("the combination's hemisphere that signs the latitude", ABSENT, schema={"enum": HEMISPHERES})
    latitude_is_absolute: bool = doc("true when latitude_deg is |γ| (no hemisphere measured or assumed)", ABSENT)
    latitude_deg: float | None = doc("the latitude acos(cos γ), signed by hemisphere, deg; null with reason")
    latitude_sigma_deg: float = doc("half the 1-σ interval of the latitude, deg", ABSENT)
    linear_sigma_deg: float | None = doc("σ of the latitude by linear propagation, deg", ABSENT)
    reason: str = doc("why latitude_deg is null", ABSENT)
    uncorrected_cos_latitude: float = doc("the raw (T_m/T_h)² of the printed swing durations (dimensionless)")


@dataclass(frozen=True, kw_only=True)
class Item9Null(Record):
    """Item 9 not applicable: it needs both a horizontal and a meridian swing."""

    latitude_deg: None = doc("null")
    reason: str = doc("why item 9 is not computed")


@dataclass(frozen=True, kw_only=True)
class Item9Counting(Record):
    """Item 9 from Quet's counted swings."""

    cos_latitude: float = doc("cos γ from the counted swing durations (dimensionless)")
    latitude_deg: float | None = doc("acos of it, deg; null outside (0, 1]")
    swings: list[int] = doc("swings counted [horizontal, meridian]")


@dataclass(frozen=True, kw_only=True)
class Item8(Record):
    """Quet eq. (10): n = π²/(μ ρ0 T_m²) from the meridian swing (with the O(n²) correction)."""

    earth_rate_rad_s: float = doc("n, rad/s")
    earth_rate_sigma_rad_s: float = doc("its standard error, rad/s")
    formula: str = doc("the formula used")
    gain: float = doc("the meridian configuration's gain (dimensionless)")


@dataclass(frozen=True, kw_only=True)
class Foucault(Record):
    """The pendulum alone: k, the latitude asin(k/n) and n = k / sin γ (γ from item 9)."""

    foucault_rate_rad_s: float = doc("the Foucault rate k, rad/s")
    foucault_rate_sigma_rad_s: float = doc("its standard error, rad/s")
    note: str = doc("where n came from when no meridian gyroscope measured it", ABSENT)
    latitude_deg: float | None = doc("asin(k/n), deg; null with reason", ABSENT)
    reason: str = doc("why latitude_deg is null", ABSENT)
    latitude_sigma_deg: float = doc("half the 1-σ interval of that latitude, deg", ABSENT)
    earth_rate_rad_s: float | None = doc("n = k / sin(latitude from item 9), rad/s; null with reason_earth_rate")
    reason_earth_rate: str = doc("why earth_rate_rad_s is null", ABSENT)
    earth_rate_sigma_rad_s: float = doc("its standard error, rad/s", ABSENT)
    earth_rate_formula: str = doc("the formula used", ABSENT)


@dataclass(frozen=True, kw_only=True)
class ClassicMethods(Record):
    """Quet's classical methods side by side with the combination (each present when its instruments are)."""

    item9_counting: Item9Counting = doc("item 9 from Quet's counted swings", ABSENT)
    item9: Item9 | Item9Null = doc("Quet item 9: the latitude from the ratio of two swings", ABSENT)
    item8_eq10: Item8 = doc("eq. (10): n from the meridian swing", ABSENT)
    foucault: Foucault = doc("the pendulum alone", ABSENT)


@dataclass(frozen=True, kw_only=True)
class Check(Record):
    """One adequacy check of the data (estimators/adequacy.py) for one instrument (or ``combined``)."""

    DOC = D.CHECKS

    instrument: str = doc("the instrument's name, or combined")
    check: str = doc("amplitude, sampling, signal, period, fit, halves, site, hemisphere, north")
    status: str = doc("passed, flagged (with the figure), failed (site: the estimate disagrees with the scene's "
                      "site), no_signal, not_applicable", schema={"enum": CHECK_STATUSES})
    value: Json = doc("the figure checked (its unit as the check says), or null", schema={})
    expected: Json = doc("what it is checked against, or null", schema={})
    detail: str = doc("the check in words")


@dataclass(frozen=True, kw_only=True)
class Disagreement(Record):
    """One failed ``site`` check."""

    instrument: str = doc("the instrument, or combined")
    what: str = doc("foucault_rate or latitude", schema={"enum": ["foucault_rate", "latitude"]})
    z: float | None = doc("how many σ apart (signed; null when infinitely many: σ = 0)")
    measured_rad_s: float = doc("the plane's rate as measured, rad/s", ABSENT)
    measured_sigma_rad_s: float = doc("its σ, rad/s", ABSENT)
    foucault_rate_rad_s: float = doc("k after the ellipse correction, rad/s", ABSENT)
    foucault_rate_sigma_rad_s: float = doc("its σ, rad/s", ABSENT)
    expected_rad_s: float = doc("a free pendulum's rate at the site with this swing's ellipse, rad/s", ABSENT)
    free_rate_rad_s: float = doc("a free pendulum's rate n sin γ at the site, rad/s", ABSENT)
    headline: str = doc("the disagreement in words")


@dataclass(frozen=True, kw_only=True)
class Site(Record):
    """The scene's site as evidence (nothing compared when site.latitude_known is false)."""

    DOC = D.SITE

    latitude_known: bool = doc("false when the scene says site.latitude_known: false (a record from an unknown place)")
    latitude_deg: float = doc("the scene's latitude, deg")
    earth_rate_rad_s: float = doc("the scene's Earth rate, rad/s")
    detail: str = doc("why nothing is compared", ABSENT)
    expected_foucault_rate_rad_s: float = doc("n sin γ at the site, rad/s", ABSENT)
    agrees: bool = doc("no site check failed", ABSENT)
    disagreements: list[Disagreement] = doc("one per failed site check", ABSENT)


@dataclass(frozen=True, kw_only=True)
class DamagedStretch(Record):
    """One stretch a replayed bag lost (the estimate uses only the intact messages)."""

    offset: int | None = doc("where the loss starts in the file, bytes; null for a loss recorded by an earlier "
                             "recover, or for messages whose channel definition was lost")
    length: int | None = doc("its length, bytes (null as offset)")
    lost_from_s: float | None = doc("start of the log-time span lost, s from the scene's start (null: unknown)")
    lost_to_s: float | None = doc("its end, s (null: unknown)")
    span_from: str | None = doc("chunk index (the damaged chunk's message_start_time-message_end_time from the intact "
                                "summary), neighbouring messages (the summary is unusable: open between the last "
                                "intact message before and the first after) or recorded by recover")
    reason: str = doc("what was wrong, e.g. chunk CRC mismatch, chunk undecodable (ZstdError), unreadable records "
                      "(framing lost)")
    before_recovery: bool = doc("true for losses read from a recovered file's gyro_instrument_damage record", ABSENT)
    file: str = doc("the .mcap of a bag directory the loss is in (absent for a bare .mcap)", ABSENT)


Entry = SwingEntry | SwingNull | PlaneEntry | PlaneNull | UnusedEntry | PluginEntry


@dataclass(frozen=True, kw_only=True)
class Estimate(Record):
    """``gyro-instrument estimate SCENE --json`` (and ``--data``, ``replay``, the estimator node's
    ``estimate``, ``run --bag``'s ``.estimate.json``): one JSON object. Angles in degrees only here, at
    the edge; rates in rad/s. A quantity that cannot be estimated is null and a reason (or reason_*)
    field says why, never NaN or infinity."""

    scene: str = doc("the scene's name")
    seed: int | None = doc("the sensor-noise seed")
    observation_s: float | None = doc("record length, s (measured data: the data's span, first to last valid "
                                      "sample; replay: the longest matched topic's span)")
    truth: Truth = doc("the simulated site (measured data: the scene's nominal values)")
    instruments: dict[str, Entry] = doc(D.INSTRUMENTS)
    methods: ClassicMethods = doc("Quet's classical methods")
    combination: Combined | Unresolved | NoRateMeasurement = doc("the combined latitude and Earth rate", inline=True)
    north: NorthBlock | RateNorthBlock | NullNorthBlock = doc(
        "the azimuth block of the instrument with the smallest σ (each instrument's own is "
        "instruments.<name>.north); present whenever the scene has a horizontal plane gyroscope or a rate gyro", ABSENT)
    blocks: dict[str, Json] = doc("a plug-in kind's block under its BLOCK key (docs/extending.md)", ABSENT, inline=True)
    checks: list[Check] = doc("the adequacy checks of the data, one entry per instrument and check")
    site: Site = doc("the scene's site as evidence")
    scene_notes: list[str] = doc(D.SCENE_NOTES + " (written by the command line and the nodes)", ABSENT)
    data: str = doc("measured data (estimate --data): the file's name", ABSENT)
    data_notes: list[str] = doc("measured data: what was left out, sorted or not used (see docs/formats/csv.md)", ABSENT)
    topics: dict[str, Json] = doc("a bag recorded by another tool: matched (instrument -> topic), unmatched "
                                  "(instrument -> why), unused (topic -> type)", ABSENT, schema={
                                      "type": "object", "properties": {
                                          "matched": {"type": "object", "additionalProperties": {"type": "string"}},
                                          "unmatched": {"type": "object", "additionalProperties": {"type": "string"}},
                                          "unused": {"type": "object", "additionalProperties": {"type": "string"}}},
                                      "additionalProperties": False})
    damaged: list[DamagedStretch] = doc("replay of a bag that lost data: one entry per lost stretch (absent when "
                                        "nothing was lost)", ABSENT)
    observation_read_s: float = doc("replay of a cut recording: span of the joint samples decoded, s", ABSENT)
    recording_cut: str = doc("replay: why the recording stops short of observation_s", ABSENT)
    replay_notes: list[str] = doc("replay: what the bag reader found", ABSENT)


@dataclass(frozen=True, kw_only=True)
class FieldBookEstimate(Record):
    """``gyro-instrument estimate --reversal-points FILE [--scene SCENE] --json``: north from turning points
    written down by hand (estimators/north/field_book.py documents the columns and rules)."""

    scene: str | None = doc("the scene's name, null without --scene")
    field_book: str = doc("the book's file")
    north: FieldBookBlock = doc("the north block of the book")


#: The schema shipped in the package (``estimate.schema.json`` beside this module; package_data in setup.py).
SCHEMA_FILE = "estimate.schema.json"
SCHEMA_ID = "https://gyro-instrument.invalid/schemas/estimate.schema.json"


def estimate_schema() -> dict:
    """The JSON Schema (draft 2020-12) of every estimate object (:class:`Estimate`, :class:`FieldBookEstimate`),
    from the records' declarations (:func:`.record.schema_of`); ``tools/gen_estimate_docs.py`` writes it to
    :data:`SCHEMA_FILE` and msg_docs/estimate.md from it."""
    from gyro_instrument.estimators.record import schema_of
    return schema_of([Estimate, FieldBookEstimate], SCHEMA_ID, "gyro_instrument estimate",
                     "The JSON object of gyro-instrument estimate --json (a scene, --data, replay, run --bag's "
                     ".estimate.json, the estimator node's estimate) or of a field book (--reversal-points).")


def shipped_schema() -> dict:
    """The schema file shipped in the package (:data:`SCHEMA_FILE`), read."""
    import json
    from importlib import resources
    return json.loads(resources.files("gyro_instrument.estimators").joinpath(SCHEMA_FILE).read_text(encoding="utf-8"))
