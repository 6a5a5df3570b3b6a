"""Field books: turning points written down by hand, read into SI and reduced (issues 24 and 33).

A surveyor with a gyrotheodolite reads the horizontal circle (following the swing with the tangent
screw) or a scale at each turning point, and perhaps times it; with a torsion tape she also swings
the gyroscope with the rotor off and reads the tape's turning points. A field book is a CSV table
of those readings, one turning point a row, in the order observed::

    # station A, 2024-05-02, GAK1 no. 123          (lines starting with # are comments)
    turning_point,side,time_hms,reading_dms,tape_time_s,tape_reading_div
    1,left,10:02:11,179°01'56",0,0.8
    2,right,10:06:12,181°17'26",160.2,-0.6
    ...

Columns (any order; only ``reading`` is required):

==========================  =====================================================================
``reading_<unit>``          rotor-on turning points: clockwise circle (or scale) readings
``time_<tunit>``            their times (optional; a missed reading's time may stand alone)
``tape_reading_<unit>``     rotor-off turning points of the tape alone (optional)
``tape_time_<tunit>``       their times (optional; with ``time`` they give the tape ratio D_B/D_K)
``turning_point``           the book's numbers of the rotor-on turning points (optional; a skipped
                            number is a missed point)
``side``                    ``left`` / ``right`` (optional; checked against the readings: a left
                            turning point reads less than the right ones beside it)
``remark``                  free text, not read
==========================  =====================================================================

Angle units ``<unit>`` (:data:`~gyro_instrument.core.angle_formats.ANGLE_UNITS`): rad, mrad, deg,
gon, mgon, arcmin, arcsec as numbers; ``dms`` as printed (``179°01'56"``, ``179.01.56``,
``179 01 56``, ``179-01-56``); ``ddmmss``, the DD.MMSS notation (``179.0156``; never guessed from
a decimal column); ``div``, scale divisions of a value stated with ``--scale-division``. Time units
``<tunit>``: s, ms, us, ns, min, ``hms`` (clock times ``mm:ss`` or ``hh:mm:ss``; a bare ``time``
column with colons is read so). A bare ``reading`` / ``time`` header takes its unit from
``--angle-unit`` / ``--time-unit``; a header unit the option contradicts is refused. The separator
is sniffed from the header as for ``--data`` (``,``; ``;`` with decimal commas; tab) unless
``--separator`` names it.

Rules: a row with its reading empty is a missed turning point, left out in its place (the others
keep theirs; its time, if written, still times the swing); empty cells after a column's last value
end that column. Readings must alternate about the centre; times must increase; readings that
straddle the circle's zero (359°59′, 0°01′) are unwrapped about the first, noted. Errors are
:class:`~gyro_instrument.core.errors.SceneError` naming the file, the line, the column and the value.

The reduction (:func:`reduce_field_book`): the Schuler mean and Lavrov's estimate with σ from the
scatter (:mod:`gyro_instrument.estimators.north`; with missed points, the same methods over the
turning points present: the Schuler mean as the mean of the complete triple means, Lavrov's
geometric sequence fitted at the points' numbers). With the tape's readings and the times of both
swings: the tape ratio from the *undamped* half periods (Lavrov's damping ratio per swing q =
e^(−δ T_half), ω_u² = ω_d² + δ², :func:`.north.undamped_omega`) and the exact relation
N = c − atan(x (Z − c)) (:func:`.north.tape_corrected`). Outliers are named, not dropped
(:func:`outliers`).
"""

import csv
import math

import numpy as np
from scipy import stats
from scipy.optimize import least_squares

from gyro_instrument.core.angle_formats import ANGLE_UNITS, NUMBER_UNITS  # noqa: F401
from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators import north
from gyro_instrument.estimators.north.means import geometric_sequence, geometric_sequence_jac
from gyro_instrument.estimators.north.field_book_read import (  # noqa: F401
    COLUMNS, TIME_UNITS, FieldBook, Swing, read_field_book)

#: Book-wide false-alarm probability of the outlier test (:func:`outliers`).
OUTLIER_ALPHA = 0.002


def write_field_book(path, readings_rad, times_s=None, tape_readings_rad=None, tape_times_s=None,
                     angle_unit="deg", decimals=None) -> None:
    """Write a field book (module docstring): readings in ``angle_unit`` (a number unit; ``decimals``
    places, else full precision, 17 significant digits), times in s; columns of unequal length end early."""
    if angle_unit not in NUMBER_UNITS:
        raise SceneError("angle_unit", angle_unit, f"must be one of {', '.join(NUMBER_UNITS)}")
    k = NUMBER_UNITS[angle_unit]
    cols = [(f"reading_{angle_unit}", np.asarray(readings_rad, dtype=float) / k)]
    if times_s is not None:
        cols.append(("time_s", np.asarray(times_s, dtype=float)))
    if tape_readings_rad is not None:
        cols.append((f"tape_reading_{angle_unit}", np.asarray(tape_readings_rad, dtype=float) / k))
        if tape_times_s is not None:
            cols.append(("tape_time_s", np.asarray(tape_times_s, dtype=float)))

    def fmt(v, angle):
        return f"{v:.{decimals}f}" if (decimals is not None and angle) else repr(float(v))

    n = max(c.size for _, c in cols)
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow([name for name, _ in cols])
        for i in range(n):
            w.writerow([fmt(c[i], "reading" in name) if i < c.size else "" for name, c in cols])


# ----------------------------------------------------------------------------- the methods, gaps allowed
def triple_means(sw) -> tuple:
    """(first turning-point numbers, means (a_k + 2 a_(k+1) + a_(k+2))/4 in rad) of every complete triple:
    the means a surveyor prints beside the readings (each one estimate of the centre)."""
    pos = dict(zip(sw.index.tolist(), sw.readings_rad.tolist()))
    ks = [k for k in pos if k + 1 in pos and k + 2 in pos]
    return np.array(ks, dtype=int), np.array([(pos[k] + 2 * pos[k + 1] + pos[k + 2]) / 4 for k in ks])


def book_schuler_mean(sw) -> north.NorthEstimate:
    """The Schuler mean of the turning points present: :func:`.north.schuler_mean` when none is missed;
    else the mean of the complete triple means with σ from their scatter, σ̂_a² = |P m|² / tr(BᵀPB)
    (B the triples' rows over the readings present, P the centring: :func:`.north.means.scatter_sigma`'s
    formula with B written out)."""
    if sw.consecutive:
        return north.schuler_mean(sw.readings_rad)
    ks, m = triple_means(sw)
    if ks.size == 0:
        raise SceneError("--reversal-points", sw.column, "no three consecutive turning points are present: the "
                         "Schuler mean needs at least one complete triple")
    col = {k: j for j, k in enumerate(sw.index.tolist())}
    B = np.zeros((ks.size, sw.index.size))
    for r, k in enumerate(ks):
        B[r, [col[k], col[k + 1], col[k + 2]]] = (0.25, 0.5, 0.25)
    w = B.mean(axis=0)
    sig, src = None, "none: a single complete triple leaves no scatter"
    if ks.size >= 2:
        P = np.eye(ks.size) - 1.0 / ks.size
        res = P @ m
        sa = math.sqrt(float(res @ res) / float(np.trace(B.T @ P @ B)))
        sig, src = sa * math.sqrt(float(w @ w)), f"from the scatter of the {ks.size} complete triple means " \
                                                  f"({ks.size - 1} dof)"
    return north.NorthEstimate("schuler_mean", float(m.mean()), sig, src, int(sw.index.size),
                               "≥ 3 consecutive reversal points (≥ 4 for a σ from the scatter)",
                               (f"{len(sw.missed)} missed turning point(s) left out: the mean of the complete "
                                f"triple means",))


def geometric_fit(sw, c0) -> tuple:
    """Lavrov's geometric sequence a_i = c + d(−q)^i fitted at the points' numbers i (least squares,
    from the centre ``c0``): (params (c, d, q), covariance or None (3 points), residuals)."""
    i = (sw.index - sw.index[0]).astype(float)
    a = sw.readings_rad
    adj = np.nonzero(np.diff(sw.index) == 1)[0]
    ratios = [-(a[j + 1] - c0) / (a[j] - c0) for j in adj if a[j] != c0]
    q0 = float(np.median(ratios)) if ratios else 1.0
    d0 = (a[0] - c0) if a[0] != c0 else float(np.ptp(a)) / 2
    sol = least_squares(lambda p: geometric_sequence(p, i) - a, [c0, d0, q0], jac=lambda p: geometric_sequence_jac(p, i),
                        method="lm", xtol=1e-15, ftol=1e-15)
    J = geometric_sequence_jac(sol.x, i)
    dof = a.size - 3
    cov = np.linalg.pinv(J.T @ J) * float(sol.fun @ sol.fun) / dof if dof > 0 else None
    return sol.x, cov, sol.fun


def _lavrov(sw, c0) -> tuple:
    """(Lavrov's NorthEstimate, q, σq or nan) over the points present (:func:`.north.lavrov` when none is
    missed; else :func:`geometric_fit`)."""
    p, cov, _ = geometric_fit(sw, c0)
    sq = math.sqrt(cov[2, 2]) if cov is not None else math.nan
    if sw.consecutive:
        return north.lavrov(sw.readings_rad), float(p[2]), sq
    sig = math.sqrt(cov[0, 0]) if cov is not None else None
    src = (f"from the scatter about the geometric fit ({sw.index.size - 3} dof)" if cov is not None
           else "none: 3 readings leave no scatter")
    est = north.NorthEstimate("lavrov", float(p[0]), sig, src, int(sw.index.size), "≥ 3 reversal points at "
                              "known places in the swing (≥ 4 for a σ from the scatter)",
                              (f"damping ratio per swing q = {p[2]:.6g}",
                               f"{len(sw.missed)} missed turning point(s) left out: fitted at the points' numbers"))
    return est, float(p[2]), sq


def half_period(sw) -> tuple:
    """(T_half, σ) s: the slope of time against turning-point number over every timed row (a missed
    reading's time included), by least squares; σ nan from 2 times. None without 2 times."""
    k, t = sw.time_index.astype(float), sw.time_values_s
    if t.size < 2:
        return None
    A = np.vstack([k, np.ones_like(k)]).T
    coef, *_ = np.linalg.lstsq(A, t, rcond=None)
    if t.size < 3:
        return float(coef[0]), math.nan
    r = t - A @ coef
    return float(coef[0]), float(math.sqrt(r @ r / (t.size - 2) / np.sum((k - k.mean()) ** 2)))


def undamped_half_period(T, sT, q, sq) -> tuple:
    """(T_u, σ) s, the half period of the undamped swing: δ = −ln(q)/T (q = e^(−δ T) per swing, Lavrov),
    ω_d = π/T, ω_u² = ω_d² + δ² (:func:`.north.undamped_omega`), T_u = π/ω_u; σ's of T and q propagated
    (nan read as 0)."""
    sT, sq = (0.0 if not math.isfinite(s) else s for s in (sT, sq))
    delta = -math.log(q) / T if q > 0 else 0.0
    wd = math.pi / T
    s_wd = math.pi * sT / T ** 2
    s_delta = math.hypot(sq / (q * T), math.log(q) * sT / T ** 2) if q > 0 else 0.0
    wu, s_wu = north.undamped_omega(wd, delta, s_wd, s_delta)
    return math.pi / wu, math.pi * s_wu / wu ** 2


# ----------------------------------------------------------------------------- outliers
def _neighbour_residuals(sw, centre_rad) -> list:
    """[(position, number, residual rad)] of each reading with both same-side neighbours (k ± 2) present:
    the reading less its neighbours' mean, the mean taken of their deviations from the centre
    geometrically, c ± √(e₋ e₊) (exact for an exponentially damped swing, whose deviations on one side
    are geometric; the arithmetic mean is off by d (1 − q²)²/(2q²), second order in the damping),
    arithmetically when the two lie on opposite sides of ``centre_rad``."""
    pos = dict(zip(sw.index.tolist(), sw.readings_rad.tolist()))
    out = []
    for j, k in enumerate(sw.index.tolist()):
        if k - 2 in pos and k + 2 in pos:
            e1, e2 = pos[k - 2] - centre_rad, pos[k + 2] - centre_rad
            pred = (centre_rad + math.copysign(math.sqrt(e1 * e2), e1) if e1 * e2 > 0
                    else (pos[k - 2] + pos[k + 2]) / 2)
            out.append((j, k, float(sw.readings_rad[j] - pred)))
    return out


def outliers(sw, centre_rad, alpha=OUTLIER_ALPHA) -> list:
    """The readings far from their neighbours' mean, named (not dropped).

    Each reading with both same-side neighbours present gives a residual r_k (:func:`_neighbour_residuals`);
    its scale s_k is 1.4826 × the median |r| of the *other* residuals, leaving out r_(k±2), which share
    a reading with r_k: an outlier neither hides itself nor, by the median, a second one beside it. The
    threshold is Student's t quantile at 1 − α/(2n), as many degrees of freedom as residuals kept
    (Bonferroni over the n residuals, α = :data:`OUTLIER_ALPHA`); the median scale is noisier than an
    rms, so a book of Gaussian noise names one in about 1–2 % of books of 9 to 40 points (measured over
    3000 books each; ``tests/test_field_books.py`` checks it), while a reading 15 σ off is named.
    Needs ≥ 2 other residuals (ν ≥ 9). A reading two places from a named one (on its side) holds half
    the named one's error in its residual and is not named beside it.

    Returns
    -------
    list of dict
        ``{column, turning_point, line, reading, sigmas, threshold_sigmas, residual_arcsec}``, ``sigmas``
        the residual in units of s_k.
    """
    rows = _neighbour_residuals(sw, centre_rad)
    n, found = len(rows), []
    for j, k, r in rows:
        keep = np.array([x for _, kk, x in rows if abs(kk - k) not in (0, 2)])
        if keep.size < 2:
            continue
        z = r / (1.4826 * float(np.median(np.abs(keep))))
        thr = float(stats.t.ppf(1.0 - alpha / (2.0 * n), keep.size))
        if abs(z) > thr:
            found.append({"column": sw.column, "turning_point": int(k) + sw.first_number, "line": int(sw.lines[j]),
                          "reading": sw.texts[j], "sigmas": float(z), "threshold_sigmas": thr,
                          "residual_arcsec": r * 648000.0 / math.pi})
    out, blamed = [], set()
    for o in sorted(found, key=lambda o: -abs(o["sigmas"])):    # a named reading's same-side neighbours carry
        if o["turning_point"] not in blamed:                   # half its error in their residuals: not named
            out.append(o)
            blamed |= {o["turning_point"] - 2, o["turning_point"] + 2}
    return sorted(out, key=lambda o: o["turning_point"])


# ----------------------------------------------------------------------------- the tape
def _period_ratio(book, lav_q) -> tuple:
    """(ratio, σ, entry) from the undamped half periods of both swings (module docstring)."""
    hp = {s: half_period(sw) for s, sw in (("on", book.on), ("off", book.off))}
    _, q_off, sq_off = _lavrov(book.off, book_schuler_mean(book.off).centre_rad)
    q = {"on": lav_q, "off": (q_off, sq_off)}
    und = {s: undamped_half_period(*hp[s], *q[s]) for s in hp}
    try:
        ratio, rs = north.tape_ratio(und["on"][0], und["off"][0], und["on"][1], und["off"][1])
    except SceneError as exc:
        raise SceneError("--reversal-points", book.path, f"{book.off.column}: the tape's half period "
                                                         f"{und['off'][0]:.6g} s must exceed the rotor-on one "
                                                         f"{und['on'][0]:.6g} s ({exc.valid})") from None
    entry = {"source": "the book: the rotor-off turning points and the times of both swings",
             "rotor_on_half_period_s": hp["on"][0], "rotor_off_half_period_s": hp["off"][0],
             "rotor_on_undamped_half_period_s": und["on"][0], "rotor_off_undamped_half_period_s": und["off"][0],
             "damping_ratio_per_swing": {"rotor_on": q["on"][0], "rotor_off": q["off"][0]}}
    return ratio, rs, entry


def _scene_x(est, tape) -> float:
    """The measured-ratio form x of the scene's D_B/D_K = r for :func:`.north.tape_corrected`: with the sine
    law the equilibrium is D_K sin(c − N) = D_B (Z − c), so x = r / cos(c − N) = r / √(1 − r²(Z − c)²);
    with the small-angle law D_K (c − N) = D_B (Z − c), x = tan(r (Z − c)) / (Z − c)."""
    r, dz = tape["ratio"], tape["zero_rad"] - est.centre_rad
    if not tape["sine_law"]:
        return r if dz == 0 else math.tan(r * dz) / dz
    s = r * dz
    if abs(s) >= 1:
        raise SceneError("--reversal-points", f"{math.degrees(est.centre_rad):.6g} deg", "the swing centre is too far "
                         "from the scene's tape zero for the scene's tape: no equilibrium (|D_B/D_K (Z - c)| >= 1)")
    return r / math.sqrt(1.0 - s * s)


def _tape_zeros(off) -> dict:
    """Each method's tape zero from the rotor-off turning points: the Schuler mean's and Lavrov's (the
    latter exact under exponential damping), so that each method reduces both swings alike."""
    z = book_schuler_mean(off)
    return {"schuler_mean": z, "lavrov": _lavrov(off, z.centre_rad)[0]}


def _book_times_mean(book) -> float | None:
    t = book.on.time_values_s
    return float(t.mean()) if t.size else None


def reduce_field_book(book, scene_tape=None) -> tuple:
    """The Schuler mean and Lavrov's estimate of a field book, tape-corrected when a tape is known.

    Parameters
    ----------
    book : FieldBook
    scene_tape : dict, optional
        The scene's tape, used when the book holds no tape readings or no times for both swings:
        ``{instrument, ratio (D_B/D_K), zero_rad (clockwise circle reading at t = 0), drift_rad_s,
        sine_law}``.

    Returns
    -------
    (ests, tape, notes) : ({name: NorthEstimate}, dict or None, list of str)
        ``tape`` says where the tape came from, its ratio and zero; None for the raw reduction.
    """
    notes = []
    schuler = book_schuler_mean(book.on)
    lav, q_on, sq_on = _lavrov(book.on, schuler.centre_rad)
    ests = {"schuler_mean": schuler, "lavrov": lav}
    off_ok = book.off is not None and book.off.index.size >= 3
    zeros = _tape_zeros(book.off) if off_ok else None
    if off_ok and half_period(book.on) and half_period(book.off):
        ratio, rs, entry = _period_ratio(book, (q_on, sq_on))
        ests = {k: north.tape_corrected(v, zeros[k].centre_rad, ratio, rs, zeros[k].sigma_rad or 0.0)
                for k, v in ests.items()}
        return ests, entry | {"ratio_db_dk": ratio, "ratio_sigma": rs, "zero_rad": zeros["schuler_mean"].centre_rad,
                              "zero_sigma_rad": zeros["schuler_mean"].sigma_rad or 0.0,
                              "zero_reading_by_method_deg": {k: math.degrees(z.centre_rad) for k, z in zeros.items()}}, \
            notes + ([f"the book's own tape used; the scene's ({scene_tape['instrument']}, D_B/D_K = "
                      f"{scene_tape['ratio']:.6g}) is not"] if scene_tape else [])
    if book.off is not None:
        notes.append("tape readings " + ("without the times of both swings" if off_ok else "fewer than 3")
                     + (": the tape zero from the book, D_B/D_K from the scene" if scene_tape and off_ok else
                        ": the tape ratio D_B/D_K is unknown and the tape torque is not removed"))
    if scene_tape is None or (book.off is not None and not off_ok):
        return ests, None, notes
    zero, source = scene_tape["zero_rad"], f"the scene's tape ({scene_tape['instrument']})"
    zeros = zeros or {k: north.NorthEstimate(k, zero, 0.0, "the scene", 0, "") for k in ests}
    if off_ok:
        zero, source = zeros["schuler_mean"].centre_rad, "the book's tape zero, the scene's D_B/D_K"
    elif scene_tape["drift_rad_s"] and _book_times_mean(book) is not None:
        zero += scene_tape["drift_rad_s"] * _book_times_mean(book)
        zeros = {k: north.NorthEstimate(k, zero, 0.0, "the scene", 0, "") for k in ests}
        notes.append("the scene's tape zero drifts: taken at the book's mean time, its clock read as the scene's")
    ests = {k: north.tape_corrected(v, zeros[k].centre_rad, _scene_x(v, scene_tape | {"zero_rad": zeros[k].centre_rad}),
                                    0.0, zeros[k].sigma_rad or 0.0) for k, v in ests.items()}
    zs = zeros["schuler_mean"].sigma_rad or 0.0
    return ests, {"source": source, "instrument": scene_tape["instrument"], "ratio_db_dk": scene_tape["ratio"],
                  "ratio_sigma": 0.0, "zero_rad": zero, "zero_sigma_rad": zs}, notes


def field_book_north(book, scene_tape=None) -> dict:
    """``{name: NorthEstimate}`` of :func:`reduce_field_book` (the Schuler mean and Lavrov's estimate)."""
    return reduce_field_book(book, scene_tape)[0]
