"""Starting the exact fit, and what its model says of the surveyors' reductions (issue 33).

Part of :mod:`gyro_instrument.estimators.north`. :func:`joint_fit` starts
:func:`.exact.fit` from damped-sine fits of each record (the rotor-off swing gives k_B = ω_u² and
d = 2δ, its centre Z; the rotor-on swing's centre c and undamped frequency give N by the exact tape
relation :func:`.fit.tape_north` and K = (ω_u² − k_B)/cos(c − N)); :func:`tape_from_records` is the
surveyors' tape calibration done right (undamped periods, the drifting zero fitted, the exact
relation), and :func:`method_biases` runs a reduction on the fitted model's own noise-free records,
so that a method's bias in *this* set-up (a large swing about an off-north centre, damping, drift)
is known and stated beside it.
"""

import math
from dataclasses import dataclass

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators.north import exact
from gyro_instrument.estimators.north.fit import fit_model, sine_fit, tape_north, undamped_omega


@dataclass(frozen=True)
class SineSummary:
    """A damped-sine fit of one record: centre at ``t_ref_s`` (rad), its drift (rad/s), the damped
    angular frequency ω and amplitude decay rate δ (rad/s, 1/s) with σ's, and the model's reading
    and rate at the record's first time."""

    centre_rad: float
    drift_rad_s: float
    omega_rad_s: float
    damping_per_s: float
    omega_sigma: float
    damping_sigma: float
    t_ref_s: float
    reading0: float
    rate0: float
    centre_cov: tuple = (0.0, 0.0, 0.0)     # var(c), cov(c, drift), var(drift)

    def undamped(self) -> tuple:
        """(ω_u, σ): ω_u² = ω² + δ² (:func:`.fit.undamped_omega`)."""
        return undamped_omega(self.omega_rad_s, self.damping_per_s, self.omega_sigma, self.damping_sigma)

    def centre_at(self, t_s) -> float:
        return self.centre_rad + self.drift_rad_s * (t_s - self.t_ref_s)

    def centre_sigma_at(self, t_s) -> float:
        dt = t_s - self.t_ref_s
        vc, cd, vd = self.centre_cov
        return math.sqrt(max(vc + 2 * dt * cd + dt * dt * vd, 0.0))


def summarise(t, w, sigma=None, drift=False) -> SineSummary:
    """:class:`SineSummary` of a record (clockwise reading w, rad) by :func:`.fit.sine_fit`."""
    sol, t_ref = sine_fit(t, w, sigma, True, drift)
    x = sol.x
    tau0 = t[0] - t_ref
    h = 1e-3 * math.pi / x[3]
    u = fit_model(np.array([tau0, tau0 + h, tau0 - h]), x, True, drift)
    J = sol.jac
    try:
        cov = np.linalg.inv(J.T @ J) * (2 * sol.cost / max(t.size - x.size, 1) if sigma is None else sigma ** 2)
        sw, sd = math.sqrt(cov[3, 3]), math.sqrt(cov[4, 4])
        cc = (cov[0, 0], cov[0, -1], cov[-1, -1]) if drift else (cov[0, 0], 0.0, 0.0)
    except np.linalg.LinAlgError:
        sw = sd = math.nan
        cc = (0.0, 0.0, 0.0)
    return SineSummary(float(x[0]), float(x[-1]) if drift else 0.0, float(x[3]), float(x[4]), sw, sd, t_ref,
                       float(u[0]), float((u[1] - u[2]) / (2 * h)), tuple(float(v) for v in cc))


def tape_from_records(on, off, t_at) -> dict:
    """The surveyors' tape calibration from damped-sine summaries of both swings: k_B = ω_off,u²,
    the ratio x = ω_off,u²/(ω_on,u² − ω_off,u²) from UNDAMPED frequencies (:func:`.fit.undamped_omega`),
    the tape zero Z at time ``t_at`` from the rotor-off centre and its fitted drift. ``on``/``off``:
    :class:`SineSummary`. Returns {ratio, ratio_sigma, zero_rad, zero_sigma_rad, kb}."""
    (wo, so), (wf, sf) = on.undamped(), off.undamped()
    x = wf ** 2 / (wo ** 2 - wf ** 2)
    den = (wo ** 2 - wf ** 2) ** 2
    sx = math.hypot(2 * wo * wf ** 2 / den * so, 2 * wf * wo ** 2 / den * sf)
    return {"ratio": x, "ratio_sigma": sx if math.isfinite(sx) else 0.0, "zero_rad": off.centre_at(t_at),
            "zero_sigma_rad": off.centre_sigma_at(t_at), "kb": wf ** 2}


def _summaries(eq, records, sigma) -> list:
    """:func:`summarise` of each record, None where the record is too short for its sine fit (a
    rotor-off swing of 26 min observed for 30 min holds two reversal points)."""
    out = []
    for r in records:
        try:
            out.append(summarise(r.t, r.w, sigma, eq.drift and r.kind == "off"))
        except (SceneError, np.linalg.LinAlgError, ValueError):
            out.append(None)
    return out


def start_values(eq, records, sigma=None, fallback=None) -> dict:
    """Starting parameters of :func:`.exact.fit` for ``records`` (rotor-on first, then rotor-off).

    From damped-sine fits of each record (module docstring); where a record is too short for one,
    from ``fallback`` ({name: value} of :data:`.exact.GLOBAL`, e.g. the scene's declared constants —
    a start only: the answer is the least-squares optimum of the data) and the record's first
    readings. Raises SceneError when neither is there.
    """
    sums = _summaries(eq, records, sigma)
    fb = dict(fallback or {})
    if sums[0] is None:
        raise SceneError("record", f"{records[0].t.size} samples", "the rotor-on swing must hold at least three "
                         "reversal points (a swing and a half) to start the fit; observe longer")
    on = sums[0]
    out = {}
    (wo, _) = on.undamped()
    if eq.tape:
        off = sums[1]
        if off is None and "tape" not in fb:
            raise SceneError("rotor_off_instrument", f"{records[1].t.size} samples", "the rotor-off swing must "
                             "hold at least three reversal points (a swing and a half) to start the fit; observe longer")
        kb = off.undamped()[0] ** 2 if off is not None else fb["tape"]
        Z = off.centre_at(eq.t_ref_s) if off is not None else fb.get("zero", 0.0)
        c = on.centre_at(eq.t_ref_s)
        N = tape_north(c, Z, kb / (wo ** 2 - kb))
        out.update(tape=kb, zero=Z, zero_rate=off.drift_rad_s if off is not None else fb.get("zero_rate", 0.0),
                   damping=2 * (off.damping_per_s if off is not None else on.damping_per_s))
        out["directing"] = (wo ** 2 - kb) / math.cos(c - N)
    else:
        N = on.centre_rad
        out.update(directing=wo ** 2, damping=2 * on.damping_per_s)
    out["north"] = N
    for i, (r, s) in enumerate(zip(records, sums)):
        if s is not None:
            out[f"{r.kind}{i}_w0"], out[f"{r.kind}{i}_v0"] = s.reading0, s.rate0
        else:
            out[f"{r.kind}{i}_w0"] = float(r.w[0])
            out[f"{r.kind}{i}_v0"] = float((r.w[1] - r.w[0]) / (r.t[1] - r.t[0])) if r.t.size > 1 else 0.0
    return out


#: swings of the first window of a long record's fit (each next window doubles it)
WINDOW_SWINGS = 32


def joint_fit(eq, records, sigma=None, fallback=None) -> exact.ExactFit:
    """The exact fit of ``records`` started by :func:`start_values`.

    When that fit does not converge on a record of more than 2 × :data:`WINDOW_SWINGS` swings (over
    thousands of swings the damped-sine start's frequency, off by the amplitude's shift — 6e-4
    relative at 0.1 rad — leaves the phase tens of radians off), the fit is made again on growing
    windows from the record's start (32 swings, then twice as long, …, each started from the last
    one's answer). Raises :class:`.exact.NotConverged` when that fails too, SceneError as
    :func:`.exact.fit` does.
    """
    start = start_values(eq, records, sigma, fallback)
    try:
        return exact.fit(eq, records, start, sigma)
    except exact.NotConverged:
        t0 = min(float(r.t[0]) for r in records)
        span = max(float(r.t[-1]) for r in records) - t0
        swing_s = 2.0 * math.pi / math.sqrt(max(start["directing"] + start.get("tape", 0.0), 1e-300))
        window = WINDOW_SWINGS * swing_s
        if window >= 0.5 * span:
            raise
    while window < 0.5 * span:
        part = [exact.Record(r.t[r.t <= t0 + window], r.w[r.t <= t0 + window], r.kind) for r in records]
        if all(p.t.size >= 8 for p in part):
            start = dict(start, **exact.fit(eq, part, start, sigma).par())
        window *= 2.0
    return exact.fit(eq, records, start, sigma)


def model_records(eq, result, records) -> list:
    """The fitted model's noise-free readings at each record's times (list of :class:`.exact.Record`)."""
    par = result.par()
    out = []
    for i, r in enumerate(records):
        w, _ = exact.swing(eq, par, r.kind, r.t, par[f"{r.kind}{i}_w0"], par[f"{r.kind}{i}_v0"])
        out.append(exact.Record(r.t, w, r.kind))
    return out


def linear_law_error_rad(centre_rad, zero_rad, ratio) -> float:
    """What the linear tape law N = c + x(c − Z) errs by against the exact :func:`.fit.tape_north` (rad)."""
    return float(centre_rad + ratio * (centre_rad - zero_rad) - tape_north(centre_rad, zero_rad, ratio))


def equilibrium(north_rad, directing_per_s2, tape_per_s2=0.0, zero_rad=0.0) -> float:
    """The swing's equilibrium c on the scale (rad): K sin(c − N) = k_B (Z − c), by Newton from N
    (the restoring torque K sin(u − N) + k_B (u − Z) is monotonic while K cos(c − N) + k_B > 0, which
    a tape weaker than the directing torque guarantees near the root; derived in :func:`.fit.tape_north`).
    """
    N, K, kb, Z = float(north_rad), float(directing_per_s2), float(tape_per_s2), float(zero_rad)
    c = N
    if not kb:
        return c
    for _ in range(100):
        f = K * math.sin(c - N) - kb * (Z - c)
        step = f / (K * math.cos(c - N) + kb)
        c -= step
        if abs(step) < 1e-15:
            break
    return float(c)
