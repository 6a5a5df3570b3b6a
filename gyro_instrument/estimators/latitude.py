"""Latitude γ and Earth rate n from the instruments' measurements, with honest uncertainty.

Each measurement is linear in the unknown rates for a fixed latitude:

* a gyroscope whose axis swings about a directing line (plane gyroscope, cone, locked gimbal):
  K = (π/T0)² = g n ρ s(γ) (Quet sec. 4 §1 eq. 9; §IV), g = C/J the known inertia gain, ρ the mean
  measured spin, T0 the small-amplitude swing duration, s(γ) = sin ω the sine of the angle between
  the directing plane's normal and Earth's axis: cos γ for a horizontal plane, 1 for the meridian.
  Dividing by g ρ gives y = n s(γ);
* a Foucault pendulum: k = n sin γ (sec. 2).

For each trial γ the best n (or, when the inertia gain is not trusted, n and G = g n) follows in
closed form, so the weighted χ² is profiled over γ alone; γ̂ is its minimum and the 1-σ interval is
where χ² rises by 1. This reproduces Quet's item 9 (cos γ = (T_m/T_h)² ρ_m/ρ_h) and eq. (10)
(n = π²/(μ ρ0 T_m²)) when only the two gyroscopes are given.

What the data cannot determine is stated, never hidden in a σ:

* **hemisphere** — a gyroscope whose plane normal lies in the horizontal or the meridian plane has
  an even s(γ) (cos γ, 1): item 9 and the gimbal's T'/T'' fix cos γ, not the sign of γ, and the
  profile likelihood has two equal modes ±γ̂. Only a sign-sensitive measurement (the pendulum's
  k = n sin γ, or a gyroscope plane tilted out of both) can choose; otherwise the result is |γ|
  with ``hemisphere = "not determined by these instruments"``, or the signed value under the
  user's explicit assumption (``estimator.hemisphere``). σ and the Cramér–Rao bound always come
  from the one mode reported.
* **separability** — when every measurement has the same dependence on γ (a pendulum alone: only
  n sin γ; one horizontal gyroscope or two: only n cos γ), n and γ cannot be separated. Then n is
  taken as known (IERS 7.292115e-5 rad/s, or the scene's value) and γ alone is fitted, and the
  result says so (``earth_rate_known``, ``earth_rate_basis``); ``estimator.earth_rate: estimate``
  refuses instead (latitude null with the reason) and ``known`` holds n even where it could be
  estimated.
* **local σ** — σ is the half-width of the mode's own Δχ² = 1 interval; when that interval reaches
  a boundary (a pole, or the equator for |γ|) the likelihood is not locally Gaussian there and σ is
  null, with the interval and the Δχ² = 9 interval reported instead.
* **other modes** — any other local minimum not excluded at 3 σ (Δχ² < 9) is listed.
"""

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq, minimize_scalar

HALF_PI = math.pi / 2
GRID = np.linspace(-HALF_PI, HALF_PI, 3601)

#: The hemisphere is taken from the data only when the best fit in the other hemisphere is worse
#: by at least this Δχ² (3 σ); below it the sign is "not determined".
HEMISPHERE_DCHI2 = 9.0

HEMISPHERE_UNDETERMINED = "not determined by these instruments"


@dataclass
class RateMeasurement:
    """y = n · s(γ) (``kind='gyro'``, y = K/(gρ)) or y = n sin γ (``kind='pendulum'``).

    ``geometry`` is the plane normal in ENU for a gyroscope (s = √(1 − (N·a(γ))²), a(γ) the unit
    Earth axis (0, cos γ, sin γ)); ``gain_known`` False means y = K/ρ and the gain is fitted.
    ``axis`` True: ``geometry`` is a sensitive axis instead, and y = n (N·a(γ))/|N|, signed (a rate
    measured along an axis: a measurement kind of a plug-in or a rate gyroscope).
    """

    name: str
    kind: str
    value: float
    sigma: float
    geometry: tuple = (0.0, 0.0, 1.0)
    gain_known: bool = True
    crlb_sigma: float = math.nan
    axis: bool = False

    def shape(self, gamma) -> np.ndarray | float:
        """s(γ): sin γ for a pendulum, sin ω(γ) for a gyroscope, N·a(γ) along an axis (γ scalar or
        array, rad)."""
        gamma = np.asarray(gamma, dtype=float)
        if self.kind == "pendulum":
            return np.sin(gamma)
        nx, ny, nz = self.geometry
        norm = math.sqrt(nx * nx + ny * ny + nz * nz)
        c = (ny * np.cos(gamma) + nz * np.sin(gamma)) / norm
        if self.axis:
            return c
        return np.sqrt(np.maximum(1.0 - c * c, 0.0))

    def sign_sensitive(self) -> bool:
        """True when s(γ) ≠ s(−γ) somewhere: the measurement can tell the hemispheres apart."""
        s, m = self.shape(GRID), self.shape(-GRID)
        return float(np.max(np.abs(s - m))) > 1e-9 * max(float(np.max(np.abs(s))), 1e-300)


def _chi2(gamma, meas, use_crlb=False, n_known=None):
    """Profiled χ²(γ) and the best rates at γ, by the closed-form normal equations.

    Unknowns: n alone, or (n, G) when some gyroscope's gain is not trusted (its rows are
    y = G s(γ), the pendulum's y = n sin γ); with ``n_known`` (rad/s) n is held at that value and
    only G is fitted. ``gamma`` may be an array (vectorised over a grid).
    """
    if np.ndim(gamma) == 0:
        return _chi2_scalar(float(gamma), meas, use_crlb, n_known)
    g = np.atleast_1d(np.asarray(gamma, dtype=float))
    two = any(m.kind == "gyro" and not m.gain_known for m in meas)
    # accumulate the 2x2 (or 1x1) normal equations Σ w a aᵀ θ = Σ w a y
    S = np.zeros((2, 2) + g.shape)
    b = np.zeros((2,) + g.shape)
    rows = []
    for m in meas:
        sig = m.crlb_sigma if use_crlb else m.sigma
        w = 1.0 / (sig * sig)
        s = m.shape(g)
        j = 1 if (two and m.kind == "gyro" and not m.gain_known) else 0
        S[j, j] += w * s * s
        b[j] += w * s * m.value
        rows.append((w, s, j, m.value))
    # the two blocks decouple (each row has one nonzero coefficient)
    with np.errstate(divide="ignore", invalid="ignore"):
        n = np.where(S[0, 0] > 0, b[0] / S[0, 0], 0.0) if n_known is None else np.full(g.shape, n_known)
        G = np.where(S[1, 1] > 0, b[1] / S[1, 1], 0.0) if two else np.zeros_like(n)
    theta = np.array([n, G])
    # χ² from the residuals, not as Σ w y² − θ·b: those two terms are ~(y/σ)² ~ 1e12 here and
    # their difference kept only ~1e-3 of χ², enough to move the latitude by 0.03 σ
    chi2 = np.zeros_like(n)
    for w, s, j, y in rows:
        r = y - theta[j] * s
        chi2 += w * r * r
    return np.maximum(chi2, 0.0), theta


def _shape_scalar(m, gamma):
    """:meth:`RateMeasurement.shape` on one float (the profile's root finders call it ~100 times)."""
    if m.kind == "pendulum":
        return math.sin(gamma)
    nx, ny, nz = m.geometry
    c = (ny * math.cos(gamma) + nz * math.sin(gamma)) / math.sqrt(nx * nx + ny * ny + nz * nz)
    return c if m.axis else math.sqrt(max(1.0 - c * c, 0.0))


def _chi2_scalar(gamma, meas, use_crlb, n_known=None):
    """:func:`_chi2` at one latitude, on floats (same sums in the same order)."""
    two = any(m.kind == "gyro" and not m.gain_known for m in meas)
    S, b, rows = [0.0, 0.0], [0.0, 0.0], []
    for m in meas:
        sig = m.crlb_sigma if use_crlb else m.sigma
        w = 1.0 / (sig * sig)
        s = _shape_scalar(m, gamma)
        j = 1 if (two and m.kind == "gyro" and not m.gain_known) else 0
        S[j] += w * s * s
        b[j] += w * s * m.value
        rows.append((w, s, j, m.value))
    theta = [(b[0] / S[0] if S[0] > 0 else 0.0) if n_known is None else n_known,
             (b[1] / S[1] if S[1] > 0 else 0.0) if two else 0.0]
    chi2 = 0.0
    for w, s, j, y in rows:
        r = y - theta[j] * s
        chi2 += w * r * r
    return max(chi2, 0.0), np.array(theta)


@dataclass
class LatitudeResult:
    """The combined estimate; angles in rad, rates in rad/s.

    ``latitude_rad`` is signed, or |γ| when ``latitude_is_absolute`` (hemisphere not determined and
    not assumed); ``latitude_sigma_rad`` is the local 1-σ half-width, or None with
    ``sigma_reason``; ``latitude_rad`` itself is None (with ``reason``) when the measurements cannot
    separate n and γ."""

    latitude_rad: float
    latitude_lo_rad: float
    latitude_hi_rad: float
    latitude_sigma_rad: float
    earth_rate_rad_s: float
    earth_rate_sigma_rad_s: float
    chi2: float
    dof: int
    carried_by: dict
    dropped: dict = None
    hemisphere: str = HEMISPHERE_UNDETERMINED
    hemisphere_basis: str = ""
    latitude_is_absolute: bool = False
    sigma_reason: str = None
    interval_3sigma_rad: tuple = None
    other_modes: list = field(default_factory=list)
    domain: tuple = (-HALF_PI, HALF_PI)
    reason: str = None
    earth_rate_known: bool = False
    earth_rate_basis: str = ""


EARTH_RATE_MODES = ("estimate", "known")


def solve_latitude(meas, use_crlb=False, hemisphere=None, flat_sigma=3.0, domain=None, earth_rate=None,
                   n_known=None, n_source="") -> LatitudeResult:
    """Latitude and Earth rate from :class:`RateMeasurement` objects (profile likelihood).

    Parameters
    ----------
    meas : list of RateMeasurement
        At least one (one alone separates n and γ only when it is independent of γ).
    use_crlb : bool
        Use each measurement's Cramér–Rao σ instead of its estimated σ (the bound of the same data).
    hemisphere : {None, 'north', 'south'}
        The user's explicit assumption (``estimator.hemisphere``), used only when the measurements
        do not determine the sign of γ; a measured sign always wins (and the conflict is noted).
    flat_sigma : float
        A gyroscope measured within this many σ of the flat maximum of its s(γ) (a horizontal
        gyroscope near the equator: cos γ ≈ 1) is left out of the latitude when a pendulum can carry
        it: its information on γ is non-Gaussian there (``dropped`` says which and why).
    domain : (float, float), optional
        Force the search interval (rad); the Cramér–Rao solve passes the estimate's own ``domain``
        so that both describe the same mode.
    earth_rate : {None, 'estimate', 'known'}
        ``estimate``: n is fitted with γ (a latitude is null where they cannot be separated);
        ``known``: n is held at ``n_known`` and γ alone is fitted; None (default): estimated where
        the measurements separate n and γ, known where they do not (a pendulum alone: k = n sin γ;
        one horizontal gyroscope: n cos γ) — the scene's ``estimator.earth_rate``.
    n_known : float, optional
        The known Earth rate, rad/s (the IERS conventional 7.292115e-5 or the scene's value);
        without it n is always estimated.
    n_source : str
        Where ``n_known`` comes from, for ``earth_rate_basis``.

    Returns
    -------
    LatitudeResult

    Raises
    ------
    ValueError
        No measurement.
    """
    if not meas:
        raise ValueError("need at least one measurement")
    if earth_rate not in (None,) + EARTH_RATE_MODES:
        raise ValueError(f"earth_rate = {earth_rate!r}; expected one of {EARTH_RATE_MODES} or None")
    reason = _inseparable(meas)
    fixed, basis = None, "estimated with the latitude (profile likelihood)"
    if n_known is not None and earth_rate != "estimate" and not (reason and reason.endswith("n is")):
        if reason:
            fixed = n_known
            basis = (f"known, not estimated: {n_known:.9g} rad/s ({n_source or 'given'}); "
                     f"{reason[0].lower() + reason[1:].split('; add ')[0]}, so the latitude is fitted with n "
                     "known (estimator.earth_rate: estimate refuses instead)")
        elif earth_rate == "known":
            fixed = n_known
            basis = (f"known, not estimated: {n_known:.9g} rad/s ({n_source or 'given'}), as the scene's "
                     "estimator.earth_rate: known asks")
    if reason and fixed is None:
        if n_known is not None and earth_rate == "estimate" and not reason.endswith("n is"):
            reason += " (estimator.earth_rate: estimate; unset it or set known to fit the latitude with n known)"
        res = _inseparable_result(meas, use_crlb, reason)
        res.earth_rate_basis = ("estimated: the measurements do not depend on the latitude" if res.earth_rate_rad_s
                                is not None else "not determined: " + reason)
        return res
    res = _solve(meas, use_crlb, hemisphere, domain, fixed)
    has_pendulum = any(m.kind == "pendulum" for m in meas)
    dropped = {}
    for m in meas:
        if m.kind != "gyro" or not has_pendulum:
            continue
        sg = m.shape(GRID)
        if np.ptp(sg) < 1e-12:
            continue
        sig = m.crlb_sigma if use_crlb else m.sigma
        if res.earth_rate_rad_s * float(np.max(sg)) - m.value < flat_sigma * sig:
            dropped[m.name] = (f"within {flat_sigma:g} sigma of the flat maximum of its directing factor "
                               f"(cos(latitude) ≈ 1 near the equator): no Gaussian latitude information")
    kept = [m for m in meas if m.name not in dropped]
    if fixed is None:
        resolvable = len(kept) >= 2 and not _inseparable(kept)
    else:
        resolvable = any(np.ptp(m.shape(GRID)) >= 1e-12 for m in kept)
    if dropped and resolvable:
        res = _solve(kept, use_crlb, hemisphere, domain, fixed)
    res.dropped = dropped
    res.earth_rate_known, res.earth_rate_basis = fixed is not None, basis
    return res


def _inseparable(meas):
    """A reason when n and γ cannot be separated: every s(γ) proportional to one shape."""
    rows = np.array([m.shape(GRID) for m in meas])
    norms = np.linalg.norm(rows, axis=1)
    rows = rows[norms > 0] / norms[norms > 0, None]
    if len(rows) >= 2:
        sv = np.linalg.svd(rows, compute_uv=False)
        if sv[1] > 1e-6 * sv[0]:
            return None
    names = ", ".join(m.name for m in meas)
    if len(meas) == 1:
        m = meas[0]
        if np.ptp(m.shape(GRID)) < 1e-12:
            return (f"the latitude is not determined: one measurement ({names}), in a directing plane containing "
                    "Earth's axis (sin ω = 1), gives n alone; n is")
        more = ("a gyroscope in the meridian plane (eq. 10 gives n)" if m.kind == "pendulum"
                else "a second configuration (item 9: horizontal and meridian) or a pendulum")
        return (f"n and the latitude cannot be separated: one measurement ({names}) gives only their product "
                f"n·s(latitude); add {more}")
    if all(np.ptp(m.shape(GRID)) < 1e-12 for m in meas):
        return (f"the latitude is not determined: every measurement ({names}) is independent of it "
                "(directing planes containing Earth's axis, sin ω = 1); n is")
    return (f"n and the latitude cannot be separated: every measurement ({names}) has the same "
            "dependence on the latitude, so only their product n·s(latitude) is measured")


def _inseparable_result(meas, use_crlb, reason):
    """Latitude None; n only when every shape is constant (then it is a weighted mean)."""
    const = reason.endswith("n is")
    n = sig_n = None
    if const:
        w = np.array([1.0 / (m.crlb_sigma if use_crlb else m.sigma) ** 2 * float(m.shape(0.0)) ** 2 for m in meas])
        y = np.array([m.value / float(m.shape(0.0)) for m in meas])
        n = float(np.sum(w * y) / np.sum(w))
        sig_n = float(1.0 / math.sqrt(np.sum(w)))
        reason = reason[:-len("; n is")] + ("; n is their weighted mean" if len(meas) > 1 else "; n is its value")
    return LatitudeResult(None, None, None, None, n, sig_n, math.nan, len(meas) - 1, {m.name: 0.0 for m in meas},
                          dropped={}, latitude_is_absolute=False, reason=reason,
                          hemisphere=HEMISPHERE_UNDETERMINED, hemisphere_basis=reason)


def _mode(f, vals, grid, mask):
    """The minimum of χ² over the grid points in ``mask``, refined between its neighbours."""
    idx = np.nonzero(mask)[0]
    i = int(idx[np.argmin(vals[idx])])
    lo, hi = grid[max(i - 1, idx[0])], grid[min(i + 1, idx[-1])]
    if hi > lo:
        r = minimize_scalar(f, bounds=(lo, hi), method="bounded", options={"xatol": 1e-13})
        if r.fun <= vals[i]:
            return float(r.x), float(r.fun), i
    return float(grid[i]), float(vals[i]), i


def _edge(f, g_hat, target, direction, bound):
    """Where χ² first exceeds ``target`` walking from ``g_hat`` toward ``bound``; (γ, reached_bound)."""
    step = 1e-9
    g = g_hat
    while True:
        g2 = g_hat + direction * step
        if direction * (g2 - bound) >= 0:
            if f(bound) <= target:
                return bound, True
            return brentq(lambda x: f(x) - target, g, bound, xtol=1e-15), False
        if f(g2) > target:
            return brentq(lambda x: f(x) - target, g, g2, xtol=1e-15), False
        g = g2
        step *= 2.0


def _hemisphere(f, vals, meas, hemisphere):
    """(domain, hemisphere, basis, absolute): the search interval and what decides the sign."""
    north, south = (0.0, HALF_PI), (-HALF_PI, 0.0)
    sensitive = [m.name for m in meas if m.sign_sensitive()]
    note = ""
    if sensitive:
        best, cbest, _ = _mode(f, vals, GRID, np.ones_like(GRID, dtype=bool))
        other = (GRID < 0) if best >= 0 else (GRID > 0)
        g_o, c_o, i_o = _mode(f, vals, GRID, other)
        # the other hemisphere's best is a mode of its own (not the same basin leaning over the equator)
        edge_i = int(np.argmin(np.abs(GRID))) + (-1 if best >= 0 else 1)
        separate = abs(i_o - edge_i) > 1
        if not separate or c_o - cbest >= HEMISPHERE_DCHI2:
            side = "north" if best >= 0 else "south"
            basis = (f"measured: the sign of {', '.join(sensitive)} "
                     f"(the other hemisphere's best fit is worse by Δχ² = {c_o - cbest:.3g})")
            if hemisphere and hemisphere != side and separate:
                basis += f"; the assumption estimator.hemisphere = {hemisphere} contradicts it and is not used"
            return (-HALF_PI, HALF_PI), side, basis, False
        note = (f"{', '.join(sensitive)} cannot decide it: the two hemispheres' best fits differ by only "
                f"Δχ² = {c_o - cbest:.3g} < {HEMISPHERE_DCHI2:g}; ")
    else:
        note = ("every measurement depends on the latitude through cos(latitude) only (item 9, the gimbal's "
                "T'/T''): +latitude and -latitude fit equally; ")
    if hemisphere in ("north", "south"):
        return (north if hemisphere == "north" else south), hemisphere, \
            note + f"assumed: estimator.hemisphere = {hemisphere}", False
    if sensitive:
        best = _mode(f, vals, GRID, np.ones_like(GRID, dtype=bool))[0]
        return (north if best >= 0 else south), HEMISPHERE_UNDETERMINED, \
            note + ("the better fit is reported, the other hemisphere's in other_latitudes_deg; set "
                    "estimator.hemisphere: north|south to choose"), False
    return north, HEMISPHERE_UNDETERMINED, \
        note + "|latitude| reported; set estimator.hemisphere: north|south to sign it", True


def _solve(meas, use_crlb=False, hemisphere=None, domain=None, n_known=None):
    """Profile-likelihood latitude and Earth rate (see :func:`solve_latitude`); with ``n_known`` the
    Earth rate is held there (its σ is then None)."""
    f = lambda g: _chi2(g, meas, use_crlb, n_known)[0]  # noqa: E731
    vals = _chi2(GRID, meas, use_crlb, n_known)[0]
    if domain is None:
        domain, side, basis, absolute = _hemisphere(f, vals, meas, hemisphere)
    else:
        side, basis, absolute = None, "", False
    a, b = domain
    mask = (GRID >= a - 1e-15) & (GRID <= b + 1e-15)
    g_hat, c_min, i = _mode(f, vals, GRID, mask)
    target = c_min + 1.0
    g_lo, lo_edge = _edge(f, g_hat, target, -1.0, a)
    g_hi, hi_edge = _edge(f, g_hat, target, +1.0, b)
    lo3, lo_edge = _edge(f, g_hat, c_min + 9.0, -1.0, a)
    hi3, hi_edge = _edge(f, g_hat, c_min + 9.0, +1.0, b)
    sigma, sigma_reason = 0.5 * (g_hi - g_lo), None
    # σ is a local statement: only when the likelihood is quadratic out to 3 σ on both sides. A
    # 3-sigma region that reaches a pole (sin γ flat) or the equator (|γ|: cos γ flat) is not: there
    # a half-width would under- or over-state the error (a mode 2σ from the equator is ~4σ from 0)
    if lo_edge or hi_edge:
        where = ("a pole" if (lo_edge and a == -HALF_PI) or (hi_edge and b == HALF_PI) else "the equator")
        sigma = None
        sigma_reason = (f"the 3-sigma region reaches {where}: the likelihood is not locally Gaussian there, so "
                        "no sigma; see the 1- and 3-sigma intervals")
    others = _other_modes(f, vals, mask, c_min, (lo3, hi3), side == HEMISPHERE_UNDETERMINED and not absolute)
    if n_known is None:
        n_hat, sig_n, (gp, gm) = _earth_rate(meas, g_hat, sigma, (g_lo, g_hi), use_crlb)
    else:
        n_hat, sig_n = float(n_known), None
        gp, gm = min(g_hat + 1e-7, HALF_PI), max(g_hat - 1e-7, -HALF_PI)
    share = _information_share(meas, n_hat, gp, gm, use_crlb)
    has_gain = any(m.kind == "gyro" and not m.gain_known for m in meas)
    dof = len(meas) - ((2 if n_known is None else 1) + (1 if has_gain else 0))
    res = LatitudeResult(g_hat, g_lo, g_hi, sigma, n_hat, sig_n, c_min, dof, share,
                         hemisphere=side, hemisphere_basis=basis, latitude_is_absolute=absolute,
                         sigma_reason=sigma_reason, interval_3sigma_rad=(lo3, hi3), other_modes=others,
                         domain=domain)
    if absolute:
        flip = -1.0 if g_hat < 0 else 1.0
        lo, hi = sorted((flip * g_lo, flip * g_hi))
        lo3, hi3 = sorted((flip * res.interval_3sigma_rad[0], flip * res.interval_3sigma_rad[1]))
        res.latitude_rad, res.latitude_lo_rad, res.latitude_hi_rad = flip * g_hat, lo, hi
        res.interval_3sigma_rad = (lo3, hi3)
        res.other_modes = [(flip * g, d) for g, d in others]
    return res


def _other_modes(f, vals, mask, c_min, interval_3sigma, mirror):
    """Other local minima of χ²(γ) not excluded at 3 sigma, as (γ, Δχ²): the best mode outside the
    domain when the hemisphere is undetermined (``mirror``), and any inside it beyond the 3-sigma
    interval within :data:`HEMISPHERE_DCHI2`."""
    lo3, hi3 = interval_3sigma
    others = []
    if mirror:
        g_o, c_o, _ = _mode(f, vals, GRID, ~mask | (np.abs(GRID) < 1e-15))
        others.append((g_o, c_o - c_min))
    inside = np.nonzero(mask)[0]
    for j in inside[1:-1]:
        if vals[j] <= vals[j - 1] and vals[j] <= vals[j + 1] and not (lo3 <= GRID[j] <= hi3) \
                and vals[j] - c_min < HEMISPHERE_DCHI2:
            g_j, c_j, _ = _mode(f, vals, GRID, (np.arange(GRID.size) >= j - 1) & (np.arange(GRID.size) <= j + 1))
            others.append((g_j, c_j - c_min))
    return others


def _earth_rate(meas, g_hat, sigma, interval, use_crlb):
    """n̂ at γ̂ and its standard error: σ(n) at fixed γ̂ plus the γ uncertainty propagated through
    n̂(γ) (by the derivative when γ has a sigma, else half the spread over the 1-sigma interval).

    Returns
    -------
    tuple
        (n̂, σ(n), (γ̂ + dγ, γ̂ − dγ) the points of the derivative, clipped to the poles).
    """
    g_lo, g_hi = interval
    _, theta = _chi2(g_hat, meas, use_crlb)
    n_hat = float(theta[0])
    info_n = sum(float(m.shape(g_hat)) ** 2 / (m.crlb_sigma if use_crlb else m.sigma) ** 2
                 for m in meas if not (m.kind == "gyro" and not m.gain_known))
    sig_n_fixed = 1.0 / math.sqrt(info_n) if info_n > 0 else math.inf
    dg = 1e-7
    gp, gm = min(g_hat + dg, HALF_PI), max(g_hat - dg, -HALF_PI)
    if sigma is not None:
        dn_dg = (_chi2(gp, meas, use_crlb)[1][0] - _chi2(gm, meas, use_crlb)[1][0]) / (gp - gm)
        spread = dn_dg * sigma
    else:
        spread = 0.5 * abs(_chi2(g_hi, meas, use_crlb)[1][0] - _chi2(g_lo, meas, use_crlb)[1][0])
    return n_hat, math.sqrt(sig_n_fixed ** 2 + spread ** 2), (gp, gm)


def _information_share(meas, n_hat, gp, gm, use_crlb):
    """Each measurement's share of the information on γ (n held at n̂): name -> fraction."""
    info = {}
    for m in meas:
        sig = m.crlb_sigma if use_crlb else m.sigma
        ds = float(m.shape(gp) - m.shape(gm)) / (gp - gm)
        info[m.name] = (n_hat * ds / sig) ** 2
    total = sum(info.values()) or 1.0
    return {k: v / total for k, v in info.items()}


def item9_cos_latitude(T_meridian_s, T_horizontal_s, spin_meridian=1.0, spin_horizontal=1.0) -> float:
    """Quet item 9: cos γ = (T_m / T_h)² · ρ_m / ρ_h (small-amplitude one-swing durations)."""
    return (T_meridian_s / T_horizontal_s) ** 2 * spin_meridian / spin_horizontal
