"""North from a rate gyro on a turntable: generalised least squares at the Cramér–Rao bound (issue 35).

The record (``index`` φ, rad; ``rate`` r, rad/s; instruments/rate_gyro/instrument.py) obeys, at heading M + φ,

    r = A cos(M + φ) + b + g + w = a cos φ − c sin φ + b + g + w,   a = A cos M, c = A sin M,

A = (1 + s) n cos γ, b the turn-on bias, g the Gauss–Markov bias instability (σ_g, τ_c), w white
(σ_w per sample): linear in θ = (a, c, b). The samples are reduced to bin means: each held
position's run (a carousel's turn in bins of 10°), split into bins no longer than τ_c/16, so the
Gauss–Markov's shape inside a dwell is kept; the bin means' covariance is exact
(:func:`~gyro_instrument.instruments.rate_gyro.sensor.block_sums`):

    C = σ_w² diag(1/n) + σ_g² S / (n nᵀ),   S_ij = Σ_{I_i × I_j} ρ^|k−l|,   ρ = exp(−Δ/τ_c).

The Fisher information of the bin means is J = Hᵀ C⁻¹ H (H the bins' mean regressors
[mean cos φ, −mean sin φ, 1]); θ̂ = J⁻¹ Hᵀ C⁻¹ ȳ is efficient (linear Gaussian model: Cov θ̂ = J⁻¹,
the bound), and M = atan2(c, a), σ_M² = ∇Mᵀ J⁻¹ ∇M, ∇M = (−c, a, 0)/A². What the data determine:

- ≥ 3 distinct headings (four positions, a carousel): M, b and A — hence (1 + s) cos γ, never s and
  the latitude apart (one horizontal axis sees n cos γ only; its scale factor multiplies it);
- two positions φ0, φ0 + 180°: b and d = A cos(M + φ0) only; with A = n cos γ at the site's stated
  latitude (s taken as 0: its error moves M by s·cot(M + φ0)), cos(M + φ0) = d/A gives M and its
  mirror image −M − 2φ0 equally well: the scene's coarse prior ``mount_azimuth_prior_deg`` ±
  ``mount_azimuth_prior_tolerance_deg`` picks one (and says so in ``sign``);
- one position: the bias and the Earth rate are not separable (a null block).

Four positions at 90° steps also give the closed form N = atan2(r_90 − r_270, r_0 − r_180) (N = −M,
the index angle pointing north; r_k the mean rate at φ0 + k·90°), equal to the least squares for
white noise and equal dwells.
"""

import math

import numpy as np
from scipy.linalg import cho_factor, cho_solve, solve_triangular

from gyro_instrument.estimators.north.block import (NullNorthBlock, RateBias, RateFisher, RateMethodEntry, RateNoiseModel,
                                                     RateNorthBlock, RateScaleFactor, RateScaleFactorAssumed, RateSign)
from gyro_instrument.estimators.north.estimate import null_block
from gyro_instrument.instruments.rate_gyro.sensor import DEG_H, block_sums

ARCSEC_PER_RAD = 648000.0 / math.pi
#: a carousel's bins: at most this turn of the table each (rad)
CAROUSEL_BIN_RAD = math.radians(10.0)
#: bins are at most τ_c / BIN_TC_FRACTION long: the Gauss–Markov's shape inside a dwell is kept (σ over
#: the raw samples' bound: 1.027 at τ_c/4, 1.006 at τ_c/8, 1.0017 at τ_c/16 — a 90 s dwell, τ_c 60 s)
BIN_TC_FRACTION = 16.0
#: most bins one fit uses (dense covariance: the solve is O(k³)); bins are lengthened beyond it
MAX_BINS = 2000


def _wrap(x):
    return (x + math.pi) % (2.0 * math.pi) - math.pi


def sample_positions(t) -> tuple:
    """(integer sample index from the first sample, sample spacing Δ in s) of sample times ``t``."""
    t = np.asarray(t, dtype=float)
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    return np.rint((t - t[0]) / dt).astype(np.int64), dt


def bins_of(k, phi, carousel, max_len) -> list:
    """Contiguous (start, stop) ranges of the samples used: runs of consecutive sample indices ``k``
    at one index angle (≥ 2 samples; a slew's samples are left out), or, for a carousel, every
    sample; each run cut into pieces of at most ``max_len`` samples."""
    if k.size == 0:
        return []
    brk = np.diff(k) != 1
    if not carousel:
        brk |= np.diff(phi) != 0.0
    edges = np.concatenate([[0], np.flatnonzero(brk) + 1, [k.size]])
    out = []
    for s, e in zip(edges[:-1], edges[1:]):
        if e - s < 2 and not carousel:
            continue
        out.extend((i, min(i + max_len, e)) for i in range(s, e, max_len))
    return out


def design(k, phi, carousel, noise, dt_s, period_s=None, max_bins=MAX_BINS) -> dict:
    """The bins, their mean regressors H (k, 3), counts, first sample indices and the exact covariance
    of their means C (k, k) (module docstring); at most about ``max_bins`` bins."""
    tc_n = max(int(noise["correlation_time_s"] / (BIN_TC_FRACTION * dt_s)), 1)
    max_len = tc_n
    if carousel and period_s:
        max_len = min(max_len, max(int(period_s * CAROUSEL_BIN_RAD / (2 * math.pi) / dt_s), 1))
    max_len = max(max_len, int(math.ceil(k.size / max_bins)))
    bins = bins_of(k, phi, carousel, max_len)
    if not bins:
        return {"bins": [], "H": np.zeros((0, 3)), "n": np.zeros(0), "C": np.zeros((0, 0))}
    starts = np.array([b[0] for b in bins])
    n = np.array([b[1] - b[0] for b in bins], dtype=float)
    cos_p, sin_p = np.cos(phi), np.sin(phi)
    cos_m = np.array([cos_p[s:e].sum() for s, e in bins])
    sin_m = np.array([sin_p[s:e].sum() for s, e in bins])
    H = np.column_stack([cos_m / n, -sin_m / n, np.ones_like(n)])
    rho = math.exp(-dt_s / noise["correlation_time_s"])
    S = block_sums(k[starts], n, rho)
    C = noise["sigma_white_rad_s"] ** 2 * np.diag(1.0 / n) + noise["sigma_gm_rad_s"] ** 2 * S / np.outer(n, n)
    return {"bins": bins, "H": H, "n": n, "C": C, "phi": np.array([phi[s] for s, _ in bins])}


def bin_means(y, bins) -> np.ndarray:
    return np.array([y[s:e].mean() for s, e in bins])


def _offsets(phi, phi0) -> np.ndarray:
    """φ − φ0 in [0, 2π), a value within 1e-9 rad below 2π read as 0 (an index logged as 359.9999999°)."""
    off = np.mod(np.asarray(phi, dtype=float) - phi0, 2 * math.pi)
    return np.where(off > 2 * math.pi - 1e-9, 0.0, off)


def headings(d, phi0) -> dict:
    """The distinct held index angles (rad) of a design, relative to φ0: {'count', 'offsets'}."""
    off = _offsets(d["phi"], phi0)
    uniq = np.unique(np.round(off, 6))
    return {"count": int(uniq.size), "offsets": uniq}


def gls(H, C, y=None) -> tuple:
    """(θ̂ or None, J = Hᵀ C⁻¹ H, whitened residual χ² or None) of the linear model y = H θ + e, e ~ N(0, C)."""
    L = np.linalg.cholesky(C)
    Hw = solve_triangular(L, H, lower=True)
    J = Hw.T @ Hw
    if y is None:
        return None, J, None
    yw = solve_triangular(L, y, lower=True)
    theta = cho_solve(cho_factor(J), Hw.T @ yw)
    r = yw - Hw @ theta
    return theta, J, float(r @ r)


def _arcsec(x):
    return None if x is None or not math.isfinite(x) else float(x) * ARCSEC_PER_RAD


def _deg360(m_rad) -> float:
    return math.degrees(m_rad) % 360.0


def _full_fit(theta, cov, A0) -> dict:
    """M, A, the scale factor and their σ from θ = (a, c, b) and its covariance (≥ 3 headings)."""
    a, c, b = theta
    A2 = a * a + c * c
    g = np.array([-c, a, 0.0]) / A2
    gA = np.array([a, c, 0.0]) / math.sqrt(A2)
    A = math.sqrt(A2)
    return {"mount_rad": math.atan2(c, a), "sigma_rad": math.sqrt(g @ cov @ g), "amplitude_rad_s": A,
            "amplitude_sigma_rad_s": math.sqrt(gA @ cov @ gA), "bias_rad_s": b, "bias_sigma_rad_s": math.sqrt(cov[2, 2]),
            "scale_factor_ppm": (A / A0 - 1.0) * 1e6 if A0 else None,
            "scale_factor_sigma_ppm": math.sqrt(gA @ cov @ gA) / A0 * 1e6 if A0 else None}


def _two_fit(theta, cov, A0, phi0, prior_rad, tol_rad) -> dict:
    """Two headings φ0, φ0 + 180°: d = A0 cos(M + φ0) (A0 = n cos γ, s = 0) and b; M = ±acos(d/A0) − φ0,
    the sign from the prior (module docstring)."""
    d, b = theta
    ratio = d / A0
    clamped = abs(ratio) > 1.0
    psi = math.acos(max(-1.0, min(1.0, ratio)))
    sin_psi = math.sin(psi)
    sigma = math.sqrt(cov[0, 0]) / (A0 * sin_psi) if sin_psi > 0 else math.inf
    cands = [_wrap(psi - phi0), _wrap(-psi - phi0)]
    dist = [abs(_wrap(m - prior_rad)) for m in cands]
    pick = int(np.argmin(dist))
    other = 1 - pick
    resolved = dist[pick] <= tol_rad < dist[other]
    return {"mount_rad": cands[pick], "sigma_rad": sigma, "bias_rad_s": b, "bias_sigma_rad_s": math.sqrt(cov[1, 1]),
            "candidates_deg": [_deg360(m) for m in cands], "resolved": resolved, "clamped": clamped,
            "sf_shift_rad_per_ppm": (1e-6 * math.cos(psi) / sin_psi) if sin_psi > 0 else math.inf,
            "distance_deg": [math.degrees(x) for x in dist], "picked": pick}


def closed_form(y, d, phi0) -> dict | None:
    """The four-position closed form (module docstring) with σ by propagating C; None unless the held
    headings are four at 90° steps from φ0."""
    off = _offsets(d["phi"], phi0)
    k = np.rint(off / (0.5 * math.pi)).astype(int) % 4
    if not np.allclose(off, np.rint(off / (0.5 * math.pi)) * 0.5 * math.pi, atol=1e-9) or set(k) != {0, 1, 2, 3}:
        return None
    W = np.zeros((4, len(k)))
    for j in range(4):
        W[j, k == j] = d["n"][k == j] / d["n"][k == j].sum()
    r = W @ y
    cov_r = W @ d["C"] @ W.T
    X, Y = r[0] - r[2], r[1] - r[3]
    north = math.atan2(Y, X)                        # N = atan2(r90 - r270, r0 - r180), index of north from phi0
    dXY = np.array([[1, 0, -1, 0], [0, 1, 0, -1]], dtype=float)
    g = np.array([Y, -X]) / (X * X + Y * Y) @ dXY   # d(psi)/dr for psi = -N = atan2(-Y, X)
    return {"mount_rad": _wrap(-north - phi0), "sigma_rad": math.sqrt(g @ cov_r @ g), "north_index_rad": north,
            "position_means_rad_s": [float(v) for v in r]}


def _prepare(obs, rec):
    """(sample index, φ, rate, Δ, noise model, design) of a record's finite samples."""
    t, phi, r = (np.asarray(rec[x], dtype=float) for x in ("t", "index", "rate"))
    ok = np.isfinite(t) & np.isfinite(phi) & np.isfinite(r)
    t, phi, r = t[ok], phi[ok], r[ok]
    k, dt = sample_positions(t)
    noise = obs.noise_model(dt)
    p = obs.instrument.p
    carousel = bool(p.carousel_rate_deg_s)
    period = 360.0 / abs(p.carousel_rate_deg_s) if carousel else None
    return k, phi, r, dt, noise, design(k, phi, carousel, noise, dt, period)


def fit_record(obs, rec) -> dict:
    """The fit of one record (module docstring): mode 'full' (≥ 3 headings), 'two' or a 'reason'."""
    inst, p = obs.instrument, obs.instrument.p
    A0 = inst.horizontal_rate_rad_s()
    if not A0:
        return {"reason": "no Earth rate about a horizontal axis: earth_rotation is not simulated, or the site is "
                          "at a pole (n cos(latitude) = 0)"}
    k, phi, r, dt, noise, d = _prepare(obs, rec)
    if len(d["bins"]) < 3:
        return {"reason": f"{len(d['bins'])} held position run(s) in the record: at least two headings, each held "
                          f"for >= 2 samples, are needed"}
    phi0 = math.radians(p.first_index_deg)
    carousel = bool(p.carousel_rate_deg_s)
    head = headings(d, phi0)
    y = bin_means(r, d["bins"])
    out = {"noise": noise, "bins": len(d["bins"]), "samples": int(d["n"].sum()), "dt_s": dt, "design": d, "y": y}
    if carousel or head["count"] >= 3:
        theta, J, chi2 = gls(d["H"], d["C"], y)
        out.update(mode="full", headings=None if carousel else head["count"], fisher=J, chi2=chi2, dof=len(y) - 3,
                   **_full_fit(theta, np.linalg.inv(J), A0))
        if not carousel:
            out["closed_form"] = closed_form(y, d, phi0)
        return out
    if head["count"] == 2 and abs(head["offsets"][1] - head["offsets"][0] - math.pi) < 1e-6:
        u = d["H"][:, 0] * math.cos(phi0) - d["H"][:, 1] * math.sin(phi0)   # cos(phi - phi0) = +-1
        H2 = np.column_stack([u, np.ones_like(u)])
        theta, J, chi2 = gls(H2, d["C"], y)
        out.update(mode="two", headings=2, fisher=J, chi2=chi2, dof=len(y) - 2,
                   **_two_fit(theta, np.linalg.inv(J), A0, phi0, math.radians(p.mount_azimuth_prior_deg),
                              math.radians(p.mount_azimuth_prior_tolerance_deg)))
        return out
    return {"reason": f"{head['count']} distinct heading(s) held: one position cannot separate the bias from the "
                      "Earth rate; two must be 180 deg apart (or use >= 3)"}


def _method(f, method, needs, crlb_rad=None, **more) -> RateMethodEntry:
    """One method's entry (``more``: the closed form's own keys)."""
    out = {"mount_azimuth_deg": _deg360(f["mount_rad"]), "sigma_arcsec": _arcsec(f["sigma_rad"]),
           "sigma_source": "the sensor's noise model (white + Gauss-Markov), propagated", "n_used": f.get("n_used"),
           "needs": needs, "bias": method, "bias_arcsec": 0.0, "bias_flagged": False, "notes": []}
    if crlb_rad is not None:
        out["crlb_arcsec"] = _arcsec(crlb_rad)
    return RateMethodEntry(**out, **more)


def _sign(f, p) -> RateSign:
    """The ``sign`` entry: how the mirror image of a two-position north was ruled out (or not)."""
    if f["mode"] != "two":
        return RateSign(resolved_by="data", detail="three or more headings: cos and sin of the heading are both "
                                                    "measured, M = atan2(c, a) has no mirror image")
    how = (f"the coarse prior mount_azimuth_prior_deg = {p.mount_azimuth_prior_deg:g} +/- "
           f"{p.mount_azimuth_prior_tolerance_deg:g} deg: the candidates lie {f['distance_deg'][0]:.3g} and "
           f"{f['distance_deg'][1]:.3g} deg from it")
    return RateSign(resolved_by="prior" if f["resolved"] else None, candidates_deg=f["candidates_deg"],
                    detail=how + ("" if f["resolved"] else "; the prior does not exclude the other one: north is "
                                  "ambiguous (state a prior that does, or add positions)"))


def north_block(obs, f) -> "RateNorthBlock | NullNorthBlock":
    """The ``north`` block (keys as the gyrotheodolite's, estimators/north/estimate.py) from :func:`fit_record`."""
    p, name = obs.instrument.p, obs.name
    if "reason" in f:
        return null_block(name, f["reason"])
    f["n_used"] = f["samples"]
    noise = f["noise"]
    methods = {"gls": _method(f, "none: the linear model is exact and its noise covariance the sensor's",
                              "two headings 180 deg apart (and a prior) or three or more", f["sigma_rad"])}
    cf = f.get("closed_form")
    if cf is not None:
        cf["n_used"] = f["samples"]
        methods["closed_form"] = _method(cf, "none for equal dwells; unequal ones weight the positions unevenly",
                                         "four positions at 90 deg steps", north_index_deg=math.degrees(cf["north_index_rad"]),
                                         position_means_rad_s=cf["position_means_rad_s"])
    undetermined = ["latitude and scale factor: a horizontal axis reads (1 + s) n cos(latitude) only; the site's "
                    "latitude is taken as given",
                    "the Earth's vertical rate n sin(latitude): the sensitive axis is horizontal"]
    block = {"instrument": name, "mount_azimuth_deg": _deg360(f["mount_rad"]), "sigma_arcsec": _arcsec(f["sigma_rad"]),
             "crlb_arcsec": _arcsec(f["sigma_rad"]), "method": "gls", "tape": None, "methods": methods, "refused": {},
             "pre_orientation": None, "sign": _sign(f, p),
             "bias": RateBias(rate_rad_s=f["bias_rad_s"], sigma_rad_s=f["bias_sigma_rad_s"], deg_h=f["bias_rad_s"] / DEG_H,
                              sigma_deg_h=f["bias_sigma_rad_s"] / DEG_H,
                              meaning="the turn-on bias plus the bias instability's mean over the record"),
             "noise_model": RateNoiseModel(**noise, bins=f["bins"], samples=f["samples"]),
             "fisher": RateFisher(matrix=f["fisher"].tolist(),
                                  parameters=(["a", "c", "b"] if f["mode"] == "full" else ["d", "b"]),
                                  formula="J = H^T C^-1 H over bin means, C = sigma_w^2 diag(1/n) + sigma_g^2 S/(n n^T)"),
             "residual_chi2_per_dof": f["chi2"] / f["dof"] if f["dof"] > 0 else None,
             "positions": f["headings"]}
    if f["mode"] == "full":
        block["scale_factor"] = RateScaleFactor(amplitude_rad_s=f["amplitude_rad_s"],
                                                amplitude_sigma_rad_s=f["amplitude_sigma_rad_s"], ppm=f["scale_factor_ppm"],
                                                sigma_ppm=f["scale_factor_sigma_ppm"],
                                                meaning="A/(n cos latitude) - 1 at the site's stated latitude")
    else:
        undetermined.append("with two positions latitude and north are not separable (the data give d = (1 + s) n "
                            "cos(latitude) cos(M + phi0) only): n cos(latitude) at the stated latitude and a scale "
                            "factor of 0 are assumed")
        block["scale_factor"] = RateScaleFactorAssumed(
            assumed_ppm=0.0, mount_shift_arcsec_per_100ppm=_arcsec(100 * f["sf_shift_rad_per_ppm"]))
        if not f["resolved"]:
            block.update(mount_azimuth_deg=None, interval_deg=None,
                         reason="two positions: north and its mirror image fit equally and the prior does not decide")
        if f["clamped"]:
            undetermined.append("the measured difference exceeds the Earth rate: cos(M + phi0) clamped to +-1")
    block["undetermined"] = undetermined
    block["notes"] = ["mount_azimuth_deg: azimuth, clockwise from true north, of the turntable's reference (index 0); "
                      "the index reads clockwise, so the sensitive axis points at mount + index",
                      f"noise: white {noise['sigma_white_rad_s']:.4g} rad/s per sample, Gauss-Markov "
                      f"{noise['sigma_gm_rad_s']:.4g} rad/s with tau_c {noise['correlation_time_s']:g} s (the instrument's "
                      "datasheet figures), turn-on bias fitted"]
    return RateNorthBlock(**block)


def north_entry(obs, rec, corrections=(), checks=None, sensor=None) -> tuple:
    """The ``north`` block of a rate gyro's record (``ENGINES[RATE_AZIMUTH]``); (block, None): not an
    Earth-rate measurement for the latitude."""
    try:
        f = fit_record(obs, rec)
    except (np.linalg.LinAlgError, ValueError) as exc:
        return null_block(obs.name, f"the fit was refused: {exc}"), None
    return north_block(obs, f), None
